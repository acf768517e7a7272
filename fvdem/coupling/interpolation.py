"""Gas -> particle interpolation: trilinear interpolation of cell-centred fields to particle centres.

On a structured ``GasMesh`` the cell centres form a regular lattice; a particle's value blends the
eight surrounding centres. Next to a wall (beyond the outermost centres) the field is held constant
(zero gradient); on periodic axes the lattice wraps. Trilinear interpolation reproduces linear
fields exactly inside the lattice and is continuous as a particle moves between cells.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def trilinear(field, points, first_centre, spacing, shape, periodic, out):
    """Interpolate ``field`` (C, k) given in FiPy cell order (x fastest) to ``points`` (N, 3) into
    ``out`` (N, k)."""
    nx, ny = shape[0], shape[1]
    k = field.shape[1]
    for p in range(points.shape[0]):
        lo = np.empty(3, np.int64)
        hi = np.empty(3, np.int64)
        w = np.empty(3)
        for d in range(3):
            t = (points[p, d] - first_centre[d]) / spacing[d]
            n = shape[d]
            i0 = int(np.floor(t))
            f = t - i0
            if periodic[d]:
                lo[d] = i0 % n
                hi[d] = (i0 + 1) % n
                w[d] = f
            elif i0 < 0:
                lo[d] = 0
                hi[d] = 0
                w[d] = 0.0
            elif i0 >= n - 1:
                lo[d] = n - 1
                hi[d] = n - 1
                w[d] = 0.0
            else:
                lo[d] = i0
                hi[d] = i0 + 1
                w[d] = f
        for c in range(k):
            out[p, c] = 0.0
        for corner in range(8):
            ix = hi[0] if corner & 1 else lo[0]
            iy = hi[1] if corner & 2 else lo[1]
            iz = hi[2] if corner & 4 else lo[2]
            weight = ((w[0] if corner & 1 else 1.0 - w[0]) * (w[1] if corner & 2 else 1.0 - w[1])
                      * (w[2] if corner & 4 else 1.0 - w[2]))
            cell = ix + nx * (iy + ny * iz)
            for c in range(k):
                out[p, c] += weight * field[cell, c]
    return out


def interpolate(mesh, field, points):
    """Cell field (C,) or (C, k) interpolated to ``points`` (N, 3); returns (N,) or (N, k)."""
    values = np.asarray(field, float)
    flat = values.reshape(len(values), -1)
    out = np.empty((len(points), flat.shape[1]))
    trilinear(np.ascontiguousarray(flat), np.ascontiguousarray(points, dtype=float), mesh.cell_centers[0],
              np.asarray(mesh.spacing, float), np.asarray(mesh.shape, np.int64), np.asarray(mesh.periodic, np.bool_),
              out)
    return out[:, 0] if values.ndim == 1 else out
