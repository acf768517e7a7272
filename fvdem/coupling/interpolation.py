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
    cells = np.empty((1, 8), np.int64)
    weights = np.empty((1, 8))
    for p in range(points.shape[0]):
        _point_weights(points[p, 0], points[p, 1], points[p, 2], 1.0, TRILINEAR, first_centre, spacing, shape,
                       periodic, cells, weights, 0, 0)
        for c in range(k):
            total = 0.0
            for j in range(8):
                total += weights[0, j] * field[cells[0, j], c]
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


@njit(cache=True, inline="always")
def _axis_weights(coordinate, first_centre, spacing, n, periodic, kernel):
    """Lower and upper cell index along one axis and the upper one's weight: the cell holding the
    point (``NEAREST``; weight 0) or the two centres around it (``TRILINEAR``); beyond the outermost
    centres of a walled axis the boundary cell alone (zero gradient), wrapped on a periodic one."""
    t = (coordinate - first_centre) / spacing
    if kernel == NEAREST:
        c = int(np.floor(t + 0.5))
        if periodic:
            c %= n
        else:
            c = min(max(c, 0), n - 1)
        return c, c, 0.0
    i0 = int(np.floor(t))
    if periodic:
        return i0 % n, (i0 + 1) % n, t - i0
    if i0 < 0:
        return 0, 0, 0.0
    if i0 >= n - 1:
        return n - 1, n - 1, 0.0
    return i0, i0 + 1, t - i0


@njit(cache=True, inline="always")
def _point_weights(x, y, z, share, kernel, first_centre, spacing, shape, periodic, cells, weights, row, start):
    """Write the 8 (trilinear) or 1 (nearest cell) cell/weight pairs of one point into row ``row`` of
    ``cells``/``weights`` from slot ``start``; returns the next free slot. Inlined, on whole arrays and
    without allocation: it runs once per point per coupling step (a called function taking row views
    cost ~50 ns per point in reference counting)."""
    nx, ny = shape[0], shape[1]
    lx, hx, wx = _axis_weights(x, first_centre[0], spacing[0], shape[0], periodic[0], kernel)
    ly, hy, wy = _axis_weights(y, first_centre[1], spacing[1], shape[1], periodic[1], kernel)
    lz, hz, wz = _axis_weights(z, first_centre[2], spacing[2], shape[2], periodic[2], kernel)
    corners = 1 if kernel == NEAREST else 8
    for corner in range(corners):
        ix = hx if corner & 1 else lx
        iy = hy if corner & 2 else ly
        iz = hz if corner & 4 else lz
        weight = ((wx if corner & 1 else 1.0 - wx) * (wy if corner & 2 else 1.0 - wy)
                  * (wz if corner & 4 else 1.0 - wz))
        cells[row, start] = ix + nx * (iy + ny * iz)
        weights[row, start] = share * weight
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
                           shape, periodic, cells, weights, i, k * per_point)
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


SCATTER_CHUNKS = 4  # particle blocks deposited in parallel, each into its own copy of the cells


@njit(cache=True, inline="always")
def scatter_blocks(n):
    """The number of fixed particle blocks a race-free deposition or sum over ``n`` particles is cut
    into: ``SCATTER_CHUNKS``, or one block for a handful of particles."""
    return SCATTER_CHUNKS if n >= 4 * SCATTER_CHUNKS else 1


@njit(cache=True, parallel=True)
def scatter(values, cells, weights, out):
    """``out[cells[i, k]] += weights[i, k] values[i]``: particle values (N, m) to cells (C, m) — the
    transpose of ``gather``, so what particles receive and what cells give up sum to the same.

    Race-free in parallel: the particles are cut into ``SCATTER_CHUNKS`` fixed blocks, each deposited
    into its own copy of the cells, and the copies are added in block order, so the result does not
    depend on the number of threads (bit for bit)."""
    n = cells.shape[0]
    chunks = scatter_blocks(n)
    partial = np.zeros((chunks, out.shape[0], out.shape[1]))
    for chunk in numba.prange(chunks):
        block = partial[chunk]
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            for k in range(cells.shape[1]):
                w = weights[i, k]
                if w != 0.0:
                    cell = cells[i, k]
                    for c in range(values.shape[1]):
                        block[cell, c] += w * values[i, c]
    for cell in numba.prange(out.shape[0]):
        for chunk in range(chunks):
            for c in range(values.shape[1]):
                out[cell, c] += partial[chunk, cell, c]
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
