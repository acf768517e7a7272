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


def read_pvd(path) -> list:
    """The ``(time, file)`` rows of a PVD collection (``write_pvd``'s), in its order; [] without the file."""
    import xml.etree.ElementTree as ET
    try:
        root = ET.parse(path).getroot()
    except (OSError, ET.ParseError):
        return []
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


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


def gas_grid(mesh):
    """Points and VTK hexahedra of a structured ``GasMesh`` in FiPy's cell order (x fastest)."""
    nx, ny, nz = mesh.shape
    dx, dy, dz = mesh.spacing
    origin = mesh.cell_centers[0] - 0.5 * np.array([dx, dy, dz])
    gx, gy, gz = np.meshgrid(np.arange(nx + 1) * dx, np.arange(ny + 1) * dy, np.arange(nz + 1) * dz, indexing="ij")
    points = origin + np.stack([gx.ravel(order="F"), gy.ravel(order="F"), gz.ravel(order="F")], axis=1)

    def vid(i, j, k):
        return i + (nx + 1) * (j + (ny + 1) * k)
    i, j, k = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij")
    i, j, k = i.ravel(order="F"), j.ravel(order="F"), k.ravel(order="F")
    hexes = np.stack([vid(i, j, k), vid(i + 1, j, k), vid(i + 1, j + 1, k), vid(i, j + 1, k),
                      vid(i, j, k + 1), vid(i + 1, j, k + 1), vid(i + 1, j + 1, k + 1), vid(i, j + 1, k + 1)], axis=1)
    centres = points[hexes].mean(axis=1)
    if not np.allclose(centres, mesh.cell_centers, atol=1e-9 * max(mesh.spacing)):
        raise ValueError("gas grid cell order differs from FiPy's (x fastest, then y, then z)")
    return points, hexes


def write_gas_vtu(path, gas) -> None:
    """Gas fields of a ``GasPhase`` (its ``mesh``, ``velocity``, ``pressure``, ``voidage``) as cell data:
    interstitial and superficial velocity [m/s], pressure [Pa], voidage."""
    points, hexes = gas_grid(gas.mesh)
    cell_data = {
        "velocity": [gas.velocity],
        "superficial_velocity": [gas.velocity * gas.voidage[:, None]],
        "pressure": [gas.pressure],
        "voidage": [gas.voidage],
    }
    tmp = Path(str(path) + ".tmp.vtu")
    meshio.write(tmp, meshio.Mesh(points, [("hexahedron", hexes)], cell_data=cell_data), binary=True)
    os.replace(tmp, path)
