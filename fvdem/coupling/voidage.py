"""Particle -> grid voidage mapping (the first half of the coupling bridge).

Three methods, chosen by name (all through the particle-to-cell weights of ``ParticleGridMap``):

- ``centroid``: a particle's whole volume goes to the cell holding its centre. A particle crossing a
  face moves ``V_p`` at once, so the voidage of a cell jumps by ``V_p / V_cell``.
- ``divided``: the volume is split equally over ``satellites`` points spaced evenly along the axis
  over the particle's full length (caps included) — the "divided"/satellite-point method for
  elongated particles (an AR-4 rod is 12 mm long in 15 mm cells). A jump is at most
  ``V_p / (satellites V_cell)``. Spheres use one point.
- ``trilinear``: the satellite points are spread over the 8 surrounding cell centres with trilinear
  (cloud-in-cell) weights — the transpose of the gas-to-particle interpolation. The voidage then
  changes continuously as a particle moves, and the pressure-gradient force on the particles and the
  ``-eps grad p`` of the gas add up to the full ``-grad p`` (momentum of the mixture conserved).

Cells are those of a structured ``GasMesh`` (FiPy's order: x fastest, then y, then z). Points
outside a walled grid are clamped to the boundary cells; periodic axes wrap.
"""
from __future__ import annotations

import numpy as np

from .interpolation import ParticleGridMap

METHODS = ("centroid", "divided", "trilinear")


def voidage(particles, mesh, method="divided", satellites=5, minimum=0.2, grid_map=None):
    """Gas volume fraction per cell and the number of over-packed cells (solid fraction above
    ``1 - minimum``, clipped to ``minimum``: a diagnostic that the grid is too fine for the particles).
    ``grid_map``: the trilinear ``ParticleGridMap`` of the current configuration, if already built."""
    if method not in METHODS:
        raise ValueError(f"voidage method {method!r}: expected one of {METHODS}")
    from ..dem.particles import spherocylinder_volume
    volume = spherocylinder_volume(particles.radius, particles.half_length)
    if method != "trilinear" or grid_map is None:
        grid_map = ParticleGridMap(mesh, particles, "trilinear" if method == "trilinear" else "nearest",
                                   1 if method == "centroid" else satellites)
    eps = 1.0 - grid_map.scatter(volume) / mesh.cell_volumes
    return np.maximum(eps, minimum), int(np.count_nonzero(eps < minimum))
