"""Particle -> grid voidage mapping (the first half of the coupling bridge).

Two methods, chosen by name:

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
from numba import njit

METHODS = ("centroid", "divided", "trilinear")


@njit(cache=True)
def deposit_solid_volume(position, axis, radius, half_length, volume, lower, spacing, shape, periodic, satellites,
                         solid):
    """Add each particle's volume [m^3] to ``solid`` (flat, FiPy cell order), over ``satellites``
    points along its axis (1 for spheres or for the centroid method)."""
    for i in range(position.shape[0]):
        points = satellites if half_length[i] > 0.0 else 1
        extent = half_length[i] + radius[i]
        share = volume[i] / points
        for k in range(points):
            s = 0.0 if points == 1 else -extent + (2.0 * k + 1.0) * extent / points
            index = 0
            stride = 1
            for d in range(3):
                x = position[i, d] + s * axis[i, d]
                c = int(np.floor((x - lower[d]) / spacing[d]))
                n = shape[d]
                if periodic[d]:
                    c %= n
                elif c < 0:
                    c = 0
                elif c >= n:
                    c = n - 1
                index += c * stride
                stride *= n
            solid[index] += share
    return solid


def voidage(particles, mesh, method="divided", satellites=5, minimum=0.2, grid_map=None):
    """Gas volume fraction per cell and the number of over-packed cells (solid fraction above
    ``1 - minimum``, clipped to ``minimum``: a diagnostic that the grid is too fine for the particles).
    ``grid_map``: the trilinear ``ParticleGridMap`` of the current configuration, if already built."""
    if method not in METHODS:
        raise ValueError(f"voidage method {method!r}: expected one of {METHODS}")
    from ..dem.particles import spherocylinder_volume
    volume = spherocylinder_volume(particles.radius, particles.half_length)
    if method == "trilinear":
        if grid_map is None:
            from .interpolation import ParticleGridMap
            grid_map = ParticleGridMap(mesh, particles, "trilinear", satellites)
        eps = 1.0 - grid_map.scatter(volume) / mesh.cell_volumes
        return np.maximum(eps, minimum), int(np.count_nonzero(eps < minimum))
    solid = np.zeros(mesh.cell_count)
    deposit_solid_volume(particles.position, particles.axis, particles.radius, particles.half_length, volume,
                         mesh.cell_centers[0] - 0.5 * np.asarray(mesh.spacing), np.asarray(mesh.spacing, float),
                         np.asarray(mesh.shape, np.int64), np.asarray(mesh.periodic, np.bool_),
                         1 if method == "centroid" else int(satellites), solid)
    eps = 1.0 - solid / mesh.cell_volumes
    over_packed = int(np.count_nonzero(eps < minimum))
    return np.maximum(eps, minimum), over_packed
