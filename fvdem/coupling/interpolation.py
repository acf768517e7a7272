"""Gas -> particle interpolation: trilinear interpolation of cell-centred fields to particle centres.

On a structured ``GasMesh`` the cell centres form a regular lattice; a particle's value blends the
eight surrounding centres. Next to a wall (beyond the outermost centres) the field is held constant
(zero gradient); on periodic axes the lattice wraps. Trilinear interpolation reproduces linear
fields exactly inside the lattice and is continuous as a particle moves between cells.
"""
from __future__ import annotations

import numba
import numpy as np
from numba import njit

NEAREST, TRILINEAR = 0, 1


@njit(cache=True)
def trilinear(field, points, first_centre, spacing, shape, periodic, out):
    """Interpolate ``field`` (C, k) given in FiPy cell order (x fastest) to ``points`` (N, 3) into
    ``out`` (N, k), with the 8 cell/weight pairs of ``_point_weights``."""
    k = field.shape[1]
    cells = np.empty(8, np.int64)
    weights = np.empty(8)
    for p in range(points.shape[0]):
        _point_weights(points[p, 0], points[p, 1], points[p, 2], 1.0, TRILINEAR, first_centre, spacing, shape,
                       periodic, cells, weights, 0)
        for c in range(k):
            total = 0.0
            for j in range(8):
                total += weights[j] * field[cells[j], c]
            out[p, c] = total
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


# --------------------------------------------------------------------------- particle <-> cell weights


@njit(cache=True)
def _point_weights(x, y, z, share, kernel, first_centre, spacing, shape, periodic, cells, weights, start):
    """Write the 8 (trilinear) or 1 (nearest cell) cell/weight pairs of one point into slots from
    ``start``; returns the next free slot."""
    nx, ny = shape[0], shape[1]
    point = (x, y, z)
    lo = np.empty(3, np.int64)
    hi = np.empty(3, np.int64)
    w = np.empty(3)
    for d in range(3):
        t = (point[d] - first_centre[d]) / spacing[d]
        n = shape[d]
        if kernel == NEAREST:
            c = int(np.floor(t + 0.5))
            if periodic[d]:
                c %= n
            else:
                c = min(max(c, 0), n - 1)
            lo[d] = c
            hi[d] = c
            w[d] = 0.0
            continue
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
    corners = 1 if kernel == NEAREST else 8
    for corner in range(corners):
        ix = hi[0] if corner & 1 else lo[0]
        iy = hi[1] if corner & 2 else lo[1]
        iz = hi[2] if corner & 4 else lo[2]
        weight = ((w[0] if corner & 1 else 1.0 - w[0]) * (w[1] if corner & 2 else 1.0 - w[1])
                  * (w[2] if corner & 4 else 1.0 - w[2]))
        cells[start] = ix + nx * (iy + ny * iz)
        weights[start] = share * weight
        start += 1
    return start


@njit(cache=True, parallel=True)
def particle_weights(position, axis, radius, half_length, satellites, kernel, first_centre, spacing, shape,
                     periodic, cells, weights):
    """Cell indices and weights (N, K) that map each particle to the grid: ``satellites`` points spread
    evenly along the axis over the full length (1 point for spheres), each carrying ``1/points`` of
    the particle, to the nearest cell (``kernel = NEAREST``) or to the 8 surrounding cell centres
    (``TRILINEAR``). Unused slots get weight 0. Each row's weights sum to 1."""
    per_point = 1 if kernel == NEAREST else 8
    for i in numba.prange(position.shape[0]):
        points = satellites if half_length[i] > 0.0 else 1
        extent = half_length[i] + radius[i]
        for k in range(points):
            s = 0.0 if points == 1 else -extent + (2.0 * k + 1.0) * extent / points
            _point_weights(position[i, 0] + s * axis[i, 0], position[i, 1] + s * axis[i, 1],
                                  position[i, 2] + s * axis[i, 2], 1.0 / points, kernel, first_centre, spacing,
                                  shape, periodic, cells[i], weights[i], k * per_point)
        for j in range(points * per_point, cells.shape[1]):
            cells[i, j] = 0
            weights[i, j] = 0.0
    return cells, weights


@njit(cache=True, parallel=True)
def gather(field, cells, weights, out):
    """``out[i] = sum_k weights[i, k] field[cells[i, k]]``: cell field (C, m) to particles (N, m)."""
    for i in numba.prange(cells.shape[0]):
        for c in range(field.shape[1]):
            total = 0.0
            for k in range(cells.shape[1]):
                total += weights[i, k] * field[cells[i, k], c]
            out[i, c] = total
    return out


@njit(cache=True)
def scatter(values, cells, weights, out):
    """``out[cells[i, k]] += weights[i, k] values[i]``: particle values (N, m) to cells (C, m) — the
    transpose of ``gather``, so what particles receive and what cells give up sum to the same."""
    for i in range(cells.shape[0]):
        for k in range(cells.shape[1]):
            w = weights[i, k]
            if w != 0.0:
                cell = cells[i, k]
                for c in range(values.shape[1]):
                    out[cell, c] += w * values[i, c]
    return out


class ParticleGridMap:
    """Particle <-> cell weights of one particle configuration on a ``GasMesh``.

    ``kernel`` ``"trilinear"`` (cloud-in-cell: the 8 surrounding cell centres of each satellite
    point; continuous as particles move) or ``"nearest"`` (the cell holding each point).
    ``satellites`` points along a rod's axis (spheres use one). ``gather`` interpolates cell fields to
    the particles; ``scatter`` is its transpose, used to deposit particle quantities.
    """

    def __init__(self, mesh, particles, kernel="trilinear", satellites=5):
        self.mesh = mesh
        self.kernel = {"trilinear": TRILINEAR, "nearest": NEAREST}[kernel]
        points = satellites if np.any(particles.half_length > 0) else 1
        width = points * (8 if self.kernel == TRILINEAR else 1)
        n = particles.count
        self.cells = np.empty((n, width), np.int64)
        self.weights = np.empty((n, width))
        particle_weights(particles.position, particles.axis, particles.radius, particles.half_length, int(satellites),
                         self.kernel, mesh.cell_centers[0], np.asarray(mesh.spacing, float),
                         np.asarray(mesh.shape, np.int64), np.asarray(mesh.periodic, np.bool_), self.cells, self.weights)

    def gather(self, field):
        values = np.asarray(field, float)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        out = np.empty((self.cells.shape[0], flat.shape[1]))
        gather(flat, self.cells, self.weights, out)
        return out[:, 0] if values.ndim == 1 else out

    def scatter(self, values):
        values = np.asarray(values, float)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        out = np.zeros((self.mesh.cell_count, flat.shape[1]))
        scatter(flat, self.cells, self.weights, out)
        return out[:, 0] if values.ndim == 1 else out
