"""Contact geometry kernels: shortest distance between particle axis segments.

Every shape pair (sphere–sphere, sphere–spherocylinder, spherocylinder–spherocylinder,
particle–wall) is reduced to the same contact geometry: overlap ``delta`` [m], unit normal
``n`` pointing from the partner to the particle, and lever arms from each centre to the contact
point. The force law (``contact_law.py``) then serves every shape pair.

A particle's axis segment is ``centre + s * axis`` with ``s`` in ``[-half_length, half_length]``.
Spheres have ``half_length = 0`` and the segment is a point.
"""
from __future__ import annotations

import numpy as np
from numba import njit

PARALLEL_TOLERANCE = 1e-10  # 1 - (a1.a2)^2 below this counts as parallel


@njit(cache=True, inline="always")
def _clamp(x, lo, hi):
    """``x`` within ``[lo, hi]`` as ``min(max(x, lo), hi)``: compiled to min/max instructions, no branch.
    The same values as ``lo if x < lo else (hi if x > hi else x)``, but in a fluidized bed of rods the
    clamps of ``segment_parameters`` fall either way at random and their branches were mispredicted:
    the segment geometry of the listed pairs of a fluidized 32,500-rod bed cost 3-5x more with them
    (docs/benchmarks.md, "The rods' step")."""
    return min(max(x, lo), hi)


@njit(cache=True, inline="always")
def segment_parameters(rx, ry, rz, a1x, a1y, a1z, h1, a2x, a2y, a2z, h2):
    """Parameters ``(s, t)`` of the closest points of two segments (Vega & Lago 1994).

    Segment 1: ``p1 + s a1``, ``|s| <= h1``; segment 2: ``p2 + t a2``, ``|t| <= h2``; ``r = p1 - p2``;
    ``a1``, ``a2`` unit vectors. Minimises ``|r + s a1 - t a2|^2`` over the rectangle: the
    unconstrained minimum clamped in ``s``, the optimal clamped ``t`` for it, then the optimal
    clamped ``s`` for that ``t`` (exact for this convex quadratic). For parallel segments the
    minimum is not unique: the midpoint of the overlap of their projections is returned so
    that side-by-side rods touch at the middle of their common stretch.
    """
    b = a1x * a2x + a1y * a2y + a1z * a2z
    d1 = a1x * rx + a1y * ry + a1z * rz
    e = a2x * rx + a2y * ry + a2z * rz
    denom = 1.0 - b * b
    if denom > PARALLEL_TOLERANCE:
        s = _clamp((b * e - d1) / denom, -h1, h1)
    else:
        # projection of segment 2 onto line 1 covers [-d1 - h2, -d1 + h2]
        lo = max(-h1, -d1 - h2)
        hi = min(h1, -d1 + h2)
        if lo <= hi:
            s = 0.5 * (lo + hi)
        else:
            s = _clamp(-d1, -h1, h1)
    t = _clamp(e + b * s, -h2, h2)
    s = _clamp(b * t - d1, -h1, h1)
    return s, t


@njit(cache=True, inline="always")
def cross(ax, ay, az, bx, by, bz):
    """The cross product ``a x b`` of two vectors given by their components."""
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True)
def segment_distance(p1, a1, h1, p2, a2, h2):
    """Shortest distance [m] between two axis segments (for tests and diagnostics)."""
    r = p1 - p2
    s, t = segment_parameters(r[0], r[1], r[2], a1[0], a1[1], a1[2], h1, a2[0], a2[1], a2[2], h2)
    d = r + s * a1 - t * a2
    return np.sqrt(d[0] ** 2 + d[1] ** 2 + d[2] ** 2)


@njit(cache=True, inline="always")
def minimum_image(d, length, periodic):
    """Shift a separation component ``d`` [m] by whole box lengths if the axis is periodic."""
    if periodic:
        d -= length * np.floor(d / length + 0.5)
    return d
