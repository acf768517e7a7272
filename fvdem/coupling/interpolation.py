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
    ``out`` (N, k), with the (up to 8) cell/weight pairs of ``_point_weights``."""
    k = field.shape[1]
    cells = np.empty((1, 8), np.int64)
    weights = np.empty((1, 8))
    for p in range(points.shape[0]):
        used = _point_weights(points[p, 0], points[p, 1], points[p, 2], 1.0, TRILINEAR, first_centre, spacing,
                              shape, periodic, cells, weights, 0, 0)
        for c in range(k):
            total = 0.0
            for j in range(used):
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


# The two axis helpers are called, not inlined by numba (``inline="always"``): ``particle_weights`` calls them
# at 18 sites, and numba's passes over its parallel loop then took 50 s of a first run's compilation, against 14 s
# called (LLVM inlines them where it pays); the same weights bit for bit, and the same speed within 2-7 %
# either way (the rods' map faster, the spheres' slower by 1-1.5 ns a particle; docs/benchmarks.md).
@njit(cache=True)
def _axis_span(coordinate, first_centre, spacing, n, periodic, kernel):
    """Lower and upper cell index along one axis and the upper one's weight: the cell holding the point
    (``NEAREST``; weight 0) or the two centres around it (``TRILINEAR``); beyond the outermost centres of a
    walled axis the boundary cell alone (zero gradient). On a periodic axis the indices are not wrapped:
    they may lie outside ``[0, n)`` (``_axis_weights`` wraps them)."""
    t = (coordinate - first_centre) / spacing
    if kernel == NEAREST:
        c = int(np.floor(t + 0.5))
        if not periodic:
            c = min(max(c, 0), n - 1)
        return c, c, 0.0
    i0 = int(np.floor(t))
    if periodic:
        return i0, i0 + 1, t - i0
    if i0 < 0:
        return 0, 0, 0.0
    if i0 >= n - 1:
        return n - 1, n - 1, 0.0
    return i0, i0 + 1, t - i0


@njit(cache=True)
def _axis_weights(coordinate, first_centre, spacing, n, periodic, kernel):
    """``_axis_span`` with the indices wrapped on a periodic axis."""
    lo, hi, w = _axis_span(coordinate, first_centre, spacing, n, periodic, kernel)
    if periodic:
        return lo % n, hi % n, w
    return lo, hi, w


@njit(cache=True, inline="always")
def _point_weights(x, y, z, share, kernel, first_centre, spacing, shape, periodic, cells, weights, row, start):
    """Write the 8 (trilinear) or 1 (nearest cell) cell/weight pairs of one point into row ``row`` of
    ``cells``/``weights`` from slot ``start``, in corner order, the zero weights left out without a branch
    (a zero's slot is written and taken by the next pair; the row needs room for all 8); returns the next
    free slot. Inlined, on whole arrays and without allocation: it runs once per point per coupling step (a
    called function taking row views cost ~50 ns per point in reference counting)."""
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
        start += weight != 0.0
    return start


WEIGHT_CHUNKS = 64  # fixed particle blocks of ``particle_weights``, each with its own block of cells


@njit(cache=True, parallel=True)
def particle_weights(position, axis, radius, half_length, satellites, kernel, first_centre, spacing, shape,
                     periodic, cells, weights, counts):
    """Cell indices and weights that map each particle to the grid: ``satellites`` points spread evenly
    along the axis over the full length (1 point for spheres), each carrying ``1/points`` of the
    particle, to the nearest cell (``kernel = NEAREST``) or to the 8 surrounding cell centres
    (``TRILINEAR``). Row i holds its particle's ``counts[i]`` cells with nonzero weight first, each once
    with the weights of all its points summed (x fastest, then y, then z); the slots from ``counts[i]`` on
    are not written. Each row's weights sum to 1.

    Why each cell once: an AR-4 rod's 5 points x 8 corners (40 pairs) fall in about 10 distinct cells of
    the bed's 15 mm grid, so every gather and deposition reads a quarter of the pairs (docs/benchmarks.md).
    The points lie on a line, so along each axis their indices lie between those of the two end points;
    where they span at most three indices on every axis (every particle shorter than a cell), the points'
    corner weights are summed into a 3 x 3 x 3 block of cells and its nonzero entries written out. A
    particle spanning more (a rod longer than a cell) keeps one entry per point and corner (the same sums,
    a cell possibly twice). Nearest cells: a point's cell is its predecessor's or one it never returns to
    (each axis's index is monotone along the line), so each point is merged with its predecessor at most.
    Spheres: one point's 8 (or 1) cells and weights, in the same order, less the zeros."""
    per_point = 1 if kernel == NEAREST else 8
    n = position.shape[0]
    nx, ny, nz = shape[0], shape[1], shape[2]
    chunks = min(WEIGHT_CHUNKS, n)
    for chunk in numba.prange(chunks):
        block = np.empty(64)  # 3 x 3 x 3 cells (and a margin) with strides 1, 4, 16
        found_cells = np.empty(27, np.int64)
        found_weights = np.empty(27)
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            points = satellites if half_length[i] > 0.0 else 1
            extent = half_length[i] + radius[i]
            share = 1.0 / points
            px, py, pz = position[i, 0], position[i, 1], position[i, 2]
            ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
            if points == 1:  # a sphere: its point's nonzero corners in order
                counts[i] = _point_weights(px, py, pz, share, kernel, first_centre, spacing, shape, periodic, cells,
                                           weights, i, 0)
                continue
            if per_point == 1:  # nearest cells along a line: a point's cell is its predecessor's or a new one
                count = 0
                previous = -1
                for k in range(points):
                    s = -extent + (2.0 * k + 1.0) * extent / points
                    lx, _, _ = _axis_weights(px + s * ax, first_centre[0], spacing[0], nx, periodic[0], kernel)
                    ly, _, _ = _axis_weights(py + s * ay, first_centre[1], spacing[1], ny, periodic[1], kernel)
                    lz, _, _ = _axis_weights(pz + s * az, first_centre[2], spacing[2], nz, periodic[2], kernel)
                    cell = lx + nx * (ly + ny * lz)
                    repeat = cell == previous
                    slot = count - 1 if repeat else count
                    weights[i, slot] = (weights[i, slot] if repeat else 0.0) + share
                    cells[i, slot] = cell
                    count += not repeat
                    previous = cell
                counts[i] = count
                continue
            # the end points' (the first and last points') indices bound all points' along each axis
            s_end = -extent + extent / points
            lx0, hx0, wx0 = _axis_span(px + s_end * ax, first_centre[0], spacing[0], nx, periodic[0], kernel)
            ly0, hy0, wy0 = _axis_span(py + s_end * ay, first_centre[1], spacing[1], ny, periodic[1], kernel)
            lz0, hz0, wz0 = _axis_span(pz + s_end * az, first_centre[2], spacing[2], nz, periodic[2], kernel)
            lx1, hx1, wx1 = _axis_span(px - s_end * ax, first_centre[0], spacing[0], nx, periodic[0], kernel)
            ly1, hy1, wy1 = _axis_span(py - s_end * ay, first_centre[1], spacing[1], ny, periodic[1], kernel)
            lz1, hz1, wz1 = _axis_span(pz - s_end * az, first_centre[2], spacing[2], nz, periodic[2], kernel)
            bx, by, bz = min(lx0, lx1), min(ly0, ly1), min(lz0, lz1)
            if max(hx0, hx1) - bx > 2 or max(hy0, hy1) - by > 2 or max(hz0, hz1) - bz > 2:
                count = 0  # longer than a cell: every point's corners as they come
                for k in range(points):
                    s = -extent + (2.0 * k + 1.0) * extent / points
                    count = _point_weights(px + s * ax, py + s * ay, pz + s * az, share, kernel, first_centre,
                                           spacing, shape, periodic, cells, weights, i, count)
                counts[i] = count
                continue
            for e in range(64):
                block[e] = 0.0
            for k in range(points):  # the end points first (their spans are known), then those between
                if k == 0:
                    lx, hx, wx, ly, hy, wy, lz, hz, wz = lx0, hx0, wx0, ly0, hy0, wy0, lz0, hz0, wz0
                elif k == 1:
                    lx, hx, wx, ly, hy, wy, lz, hz, wz = lx1, hx1, wx1, ly1, hy1, wy1, lz1, hz1, wz1
                else:
                    s = -extent + (2.0 * k - 1.0) * extent / points
                    lx, hx, wx = _axis_span(px + s * ax, first_centre[0], spacing[0], nx, periodic[0], kernel)
                    ly, hy, wy = _axis_span(py + s * ay, first_centre[1], spacing[1], ny, periodic[1], kernel)
                    lz, hz, wz = _axis_span(pz + s * az, first_centre[2], spacing[2], nz, periodic[2], kernel)
                # the point's corners at offsets 0/1, 0/4, 0/16 from its lower one (an upper index equal to the
                # lower, beyond the outermost centres, has weight 0: added, at the next offset, as 0)
                o = (lx - bx) + 4 * (ly - by) + 16 * (lz - bz)
                if per_point == 1:
                    block[o] += share * 1.0
                    continue
                ux, uy, uz = 1.0 - wx, 1.0 - wy, 1.0 - wz
                block[o] += share * (ux * uy * uz)
                block[o + 1] += share * (wx * uy * uz)
                block[o + 4] += share * (ux * wy * uz)
                block[o + 5] += share * (wx * wy * uz)
                block[o + 16] += share * (ux * uy * wz)
                block[o + 17] += share * (wx * uy * wz)
                block[o + 20] += share * (ux * wy * wz)
                block[o + 21] += share * (wx * wy * wz)
            count = 0
            for c in range(3):  # the nonzero entries, compacted without a branch
                iz = (bz + c) % nz if periodic[2] else bz + c
                for b in range(3):
                    iy = (by + b) % ny if periodic[1] else by + b
                    row = nx * (iy + ny * iz)
                    for a in range(3):
                        ix = (bx + a) % nx if periodic[0] else bx + a
                        w = block[a + 4 * b + 16 * c]
                        found_cells[count] = ix + row
                        found_weights[count] = w
                        count += w != 0.0
            for k in range(count):  # at most one entry per point and corner: within the row
                cells[i, k] = found_cells[k]
                weights[i, k] = found_weights[k]
            counts[i] = count
    return cells, weights, counts


@njit(cache=True, parallel=True)
def gather(field, cells, weights, counts, out):
    """``out[i] = sum_k weights[i, k] field[cells[i, k]]`` over row i's ``counts[i]`` entries: cell field
    (C, m) to particles (N, m)."""
    for i in numba.prange(cells.shape[0]):
        for c in range(field.shape[1]):
            total = 0.0
            for k in range(counts[i]):
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
def scatter(values, cells, weights, counts, out):
    """``out[cells[i, k]] += weights[i, k] values[i]`` over row i's ``counts[i]`` entries: particle values
    (N, m) to cells (C, m) — the transpose of ``gather``, so what particles receive and what cells give up
    sum to the same.

    Race-free in parallel: the particles are cut into ``SCATTER_CHUNKS`` fixed blocks, each deposited
    into its own copy of the cells, and the copies are added in block order, so the result does not
    depend on the number of threads (bit for bit)."""
    n = cells.shape[0]
    chunks = scatter_blocks(n)
    partial = np.zeros((chunks, out.shape[0], out.shape[1]))
    for chunk in numba.prange(chunks):
        block = partial[chunk]
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            for k in range(counts[i]):
                w = weights[i, k]
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
    the particles; ``scatter`` is its transpose, used to deposit particle quantities. Row i of
    ``cells``/``weights`` holds particle i's ``counts[i]`` distinct cells (``particle_weights``).
    ``refresh`` maps a new configuration into the same arrays (the bridge does it every coupling step:
    fresh arrays of a 32,500-rod bed cost their page faults, about a millisecond, each time).
    """

    def __init__(self, mesh, particles, kernel="trilinear", satellites=5):
        self.mesh = mesh
        self.kernel = {"trilinear": TRILINEAR, "nearest": NEAREST}[kernel]
        self.satellites = int(satellites)
        self._grid = (mesh.cell_centers[0], np.asarray(mesh.spacing, float), np.asarray(mesh.shape, np.int64),
                      np.asarray(mesh.periodic, np.bool_))
        self.cells = self.weights = self.counts = None
        self.refresh(particles)

    def fits(self, kernel: str, satellites: int, particles) -> bool:
        """Whether this map has ``kernel``'s weights and the points of ``satellites`` for ``particles``."""
        same_points = satellites == self.satellites or not np.any(particles.half_length > 0)
        return ({"trilinear": TRILINEAR, "nearest": NEAREST}[kernel] == self.kernel and same_points
                and self.cells.shape[0] == particles.count)

    def refresh(self, particles) -> "ParticleGridMap":
        """The weights of ``particles`` as they are now (the arrays reused while the row width holds)."""
        points = self.satellites if np.any(particles.half_length > 0) else 1
        shape = (particles.count, points * (8 if self.kernel == TRILINEAR else 1))
        if self.cells is None or self.cells.shape != shape:
            self.cells = np.empty(shape, np.int32)
            self.weights = np.empty(shape)
            self.counts = np.empty(shape[0], np.int32)
        particle_weights(particles.position, particles.axis, particles.radius, particles.half_length,
                         self.satellites, self.kernel, *self._grid, self.cells, self.weights, self.counts)
        return self

    def gather(self, field):
        values = np.asarray(field, float)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        out = np.empty((self.cells.shape[0], flat.shape[1]))
        gather(flat, self.cells, self.weights, self.counts, out)
        return out[:, 0] if values.ndim == 1 else out

    def scatter(self, values):
        values = np.asarray(values, float)
        flat = np.ascontiguousarray(values.reshape(len(values), -1))
        out = np.zeros((self.mesh.cell_count, flat.shape[1]))
        scatter(flat, self.cells, self.weights, self.counts, out)
        return out[:, 0] if values.ndim == 1 else out
