"""ParaView output: particle snapshots as VTU (meshio) collected in a PVD file.

Each snapshot is an unstructured grid of vertices with point data ``velocity``, ``angular_velocity``,
``axis``, ``colour``, ``id``, ``radius`` and ``length`` (total, caps included). In ParaView open the
``.pvd``, apply *Glyph* (sphere scaled by ``radius`` for spheres; cylinder oriented by ``axis`` and
scaled by ``length`` for spherocylinders) and colour by ``colour``.
"""
from __future__ import annotations

import os
from pathlib import Path
from xml.sax.saxutils import quoteattr

import meshio
import numpy as np


def write_particles_vtu(path, particles) -> None:
    """Write one particle snapshot, rows sorted by particle id."""
    order = np.argsort(particles.ids, kind="stable")
    points = particles.position[order]
    cells = [("vertex", np.arange(len(points), dtype=np.int64).reshape(-1, 1))]
    point_data = {
        "velocity": particles.velocity[order],
        "angular_velocity": particles.angular_velocity[order],
        "axis": particles.axis[order],
        "colour": particles.colour[order].astype(np.int32),
        "id": particles.ids[order].astype(np.int64),
        "radius": particles.radius[order],
        "length": 2.0 * (particles.half_length[order] + particles.radius[order]),
    }
    tmp = Path(str(path) + ".tmp.vtu")
    meshio.write(tmp, meshio.Mesh(points, cells, point_data=point_data), binary=True)
    os.replace(tmp, path)


def write_pvd(path, entries) -> None:
    """PVD collection; ``entries`` is a list of ``(time, relative_file_name)``."""
    lines = ['<?xml version="1.0"?>',
             '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">', "  <Collection>"]
    for time, name in entries:
        lines.append(f'    <DataSet timestep="{time:.9g}" group="" part="0" file={quoteattr(str(name))}/>')
    lines += ["  </Collection>", "</VTKFile>", ""]
    tmp = Path(str(path) + ".tmp")
    tmp.write_text("\n".join(lines))
    os.replace(tmp, path)
