"""Particle -> grid voidage mapping (the first half of the coupling bridge), methods registered by name.

Every method goes through the particle-to-cell weights of ``ParticleGridMap`` and differs in the
points a particle's volume is split over and the weights of a point:

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

A new method is one ``register_voidage`` call: the case checks, ``fvdem schema`` and the bridge read
``METHODS``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .interpolation import ParticleGridMap


@dataclass(frozen=True)
class VoidageMethod:
    """A registered voidage method: point ``weights`` ('nearest': the cell holding the point;
    'trilinear': the 8 surrounding cell centres), whether the volume is split over ``satellite``
    points along the axis (else one point, the centre), a one-line ``summary`` and ``reference``."""

    name: str
    weights: str
    satellites: bool
    summary: str
    reference: str = ""

    def points(self, satellites: int) -> int:
        return satellites if self.satellites else 1


METHODS: dict[str, VoidageMethod] = {}


def register_voidage(name: str, *, weights: str, satellites: bool, summary: str, reference: str = "") -> VoidageMethod:
    if weights not in ("nearest", "trilinear"):
        raise ValueError(f"voidage method {name!r}: weights {weights!r}, expected 'nearest' or 'trilinear'")
    METHODS[name] = method = VoidageMethod(name, weights, satellites, summary, reference)
    return method


def voidage_names() -> tuple:
    return tuple(METHODS)


def describe_voidage() -> str:
    """One line per registered method, for the case reference and ``fvdem schema``."""
    return "; ".join(f"'{m.name}': {m.summary}" for m in METHODS.values())


register_voidage("divided", weights="nearest", satellites=True,
                 summary="satellite points along the axis, each to its cell",
                 reference="CFDEMcoupling's 'divided' voidage model (Goniva et al. 2012, Particuology 10)")
register_voidage("centroid", weights="nearest", satellites=False,
                 summary="whole particle to the cell of its centre",
                 reference="CFDEMcoupling's 'centre' voidage model")
register_voidage("trilinear", weights="trilinear", satellites=True,
                 summary="satellite points spread over the 8 nearest cell centres, the transpose of the interpolation",
                 reference="cloud-in-cell (Hockney & Eastwood 1988)")


def voidage(particles, mesh, method="divided", satellites=5, minimum=0.2, grid_map=None):
    """Gas volume fraction per cell and the number of over-packed cells (solid fraction above
    ``1 - minimum``, clipped to ``minimum``: a diagnostic that the grid is too fine for the particles).
    ``grid_map``: a ``ParticleGridMap`` of the current configuration, if already built (used when its
    weights and points are the method's, else a map is built)."""
    try:
        m = METHODS[method]
    except KeyError:
        raise ValueError(f"voidage method {method!r}: expected one of {voidage_names()}") from None
    from ..dem.particles import spherocylinder_volume
    volume = spherocylinder_volume(particles.radius, particles.half_length)
    if grid_map is None or not grid_map.fits(m.weights, m.points(satellites), particles):
        grid_map = ParticleGridMap(mesh, particles, m.weights, m.points(satellites))
    eps = 1.0 - grid_map.scatter(volume) / mesh.cell_volumes
    return np.maximum(eps, minimum), int(np.count_nonzero(eps < minimum))
