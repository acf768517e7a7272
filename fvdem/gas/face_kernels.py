"""Compiled face-to-cell sums of the gas solver on its structured grid.

Every face normal of the grid is +-1 along one axis, so a face's contribution to a cell's Gauss sum
has one component. The sparse-matrix forms (``GasSolver._divergence @ (p_f A_f n_f)``) stay in the
solver as the reference the tests compare these kernels with.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def gauss_gradient(face_values, first, second, axis, signed_area, volumes):
    """``(1 / V_c) sum_f phi_f A_f n_f`` over each cell's faces, outward (C, 3).

    ``first``/``second``: the face's two cells (second -1 on the boundary; the normal points from
    first to second, outward on the boundary); ``axis``: the normal's axis; ``signed_area``: ``A_f``
    times the normal's sign (zero on faces that carry nothing, such as a periodic face's unused
    copy); ``volumes`` (C,)."""
    n = len(volumes)
    out = np.zeros((n, 3))
    for f in range(len(face_values)):
        value = face_values[f] * signed_area[f]
        a = axis[f]
        out[first[f], a] += value
        if second[f] >= 0:
            out[second[f], a] -= value
    for c in range(n):
        out[c, 0] /= volumes[c]
        out[c, 1] /= volumes[c]
        out[c, 2] /= volumes[c]
    return out
