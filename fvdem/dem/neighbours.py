"""O(N) neighbour search: particles sorted by cell, half Verlet lists with a skin.

A pair (i, j), i < j, is listed in row i when the shortest distance between the axis segments
is below ``r_i + r_j + skin``. Every point of a segment moves by at most as much as one of its end
points, ``max |dx +- h d axis|`` (centre displacement, half length, change of the unit axis), so the
list stays complete until some particle's end points have moved by more than ``skin / 2``; the
integrator tracks that bound and asks for a rebuild.

The list is stored compactly (CSR): row i's partners are ``neighbours[row_start[i]:row_start[i+1]]``
(int32), and a pair's slot is its position in that flat array. Compact rows matter: with padded
fixed-width rows the per-step working set of a 32,500-particle bed overflowed the L3 cache and
every kernel became latency bound. Each contact's tangential history lives in its pair's slot; on
a rebuild the histories are carried over to the new slots (through the particle permutation of the
cell sort), with their sign flipped when the pair's owner changes (``carry_history``). The rows are then cut into blocks
of cell layers (``contact_blocks``) in which the contact kernel adds both sides of a pair straight onto
the particles without write conflicts.
"""
from __future__ import annotations

import numba
import numpy as np
from numba import njit, prange

from .geometry import minimum_image, segment_parameters


@njit(cache=True)
def wrap_periodic(position, box_lo, box_length, periodic):
    """Map positions back into the box along periodic axes (in place)."""
    n = position.shape[0]
    for d in range(3):
        if periodic[d]:
            lo = box_lo[d]
            length = box_length[d]
            for i in range(n):
                position[i, d] = lo + (position[i, d] - lo) % length


@njit(cache=True)
def cell_indices(position, box_lo, cell_size, n_cells, cell_of):
    """Linear cell index of each particle (z-major, so sorting keeps vertical layers together).
    Positions outside the grid (e.g. overlapping a wall) are clamped to the boundary cells."""
    n = position.shape[0]
    for i in range(n):
        index = 0
        for d in range(2, -1, -1):  # z, y, x: z-major
            k = int(np.floor((position[i, d] - box_lo[d]) / cell_size[d]))
            if k < 0:
                k = 0
            elif k >= n_cells[d]:
                k = n_cells[d] - 1
            index = index * n_cells[d] + k
        cell_of[i] = index


@njit(cache=True, parallel=True)
def permute_wall_history(history, mask, order, new_history):
    """Wall histories (``(N * 12, 4)``, 12 slots per particle) in the particles' new order: only the
    particles with a wall contact (``mask`` bits set, old order) are copied, into ``new_history``
    zeroed beforehand (a zeroed array's untouched pages cost nothing)."""
    for k in prange(order.shape[0]):
        o = order[k]
        if mask[o] != 0:
            for s in range(12):
                for c in range(history.shape[1]):
                    new_history[k * 12 + s, c] = history[o * 12 + s, c]


@njit(cache=True)
def cell_starts(cell_of_sorted, total_cells):
    """Start offsets (total_cells + 1) of each cell in the sorted particle order."""
    start = np.zeros(total_cells + 1, dtype=np.int64)
    for i in range(cell_of_sorted.shape[0]):
        start[cell_of_sorted[i] + 1] += 1
    for c in range(total_cells):
        start[c + 1] += start[c]
    return start


@njit(cache=True, inline="always")
def _segments_within(rx, ry, rz, ri, hi, ai0, ai1, ai2, j, axis, radius, half_length, skin):
    """Whether the axis segments of i (separation ``r = x_i - x_j``, radius, half length, axis given)
    and j come closer than ``r_i + r_j + skin``."""
    s, t = segment_parameters(rx, ry, rz, ai0, ai1, ai2, hi, axis[j, 0], axis[j, 1], axis[j, 2], half_length[j])
    dx = rx + s * ai0 - t * axis[j, 0]
    dy = ry + s * ai1 - t * axis[j, 1]
    dz = rz + s * ai2 - t * axis[j, 2]
    cut = ri + radius[j] + skin
    return dx * dx + dy * dy + dz * dz < cut * cut


@njit(cache=True, parallel=True)
def build_half_list(position, axis, radius, half_length, box_lo, box_length, periodic, cell_size,
                    n_cells, cell_of, start, skin, span, spheres, extent, buffer, counts, scratch):
    """The half list in one pass: row i's partners j > i go to ``buffer[i, :]`` (a fixed
    capacity per row) in cell-scan order and ``counts[i]`` gets the row's length, which may exceed
    the capacity: the caller then enlarges ``buffer`` and calls again (``compact_rows`` copies the
    rows into the CSR list). One pass instead of a counting pass and a filling pass: each
    candidate pair is tested once. ``spheres``: every particle is a sphere, so a pair is listed when
    its centres are closer than ``r_i + r_j + skin`` (no segment geometry: a rebuild of the settled
    32,500-sphere bed 180-240 ns per particle against 230-290). Otherwise the candidates within the
    bounding spheres' reach (``extent``: the largest ``r + h`` of any particle, so that the scan reads
    the positions only) are first collected without a branch into the calling thread's row of
    ``scratch`` (at least one more column than a particle has candidates), then given the segment
    tests, the centre of j against i's segment (``r_i + r_j + h_j + skin``, a capsule about i: a point-segment
    distance) and then the segment-segment distance, each test compacting its survivors without a
    branch. On a fluidized 32,500-rod bed (skin 2.7 mm; about 150 candidates, 45 within reach and 7 listed
    per rod) the collection cost 370 ns per rod and the tests 750 as branches, 375 without (the same
    list; docs/benchmarks.md). A row is complete when ``counts[i] < buffer.shape[1]``.

    Scans the ``(2 span + 1)^3`` cells around each particle's cell (wrapped on periodic axes, which
    need at least ``2 span + 1`` cells so no cell is visited twice). Particles are sorted by cell, so
    within a cell only the indices above i are visited.
    """
    n = position.shape[0]
    capacity = buffer.shape[1]
    nx, ny, nz = n_cells[0], n_cells[1], n_cells[2]
    lx, ly, lz = box_length[0], box_length[1], box_length[2]
    qx, qy, qz = periodic[0], periodic[1], periodic[2]
    width = 2 * span + 1
    wrapped = qx and nx >= width  # a periodic x axis wraps each row of cells around
    for i in prange(n):
        c = cell_of[i]
        cx = c % nx
        cy = (c // nx) % ny
        cz = c // (nx * ny)
        # row i's own values, read once (the buffer stores might alias them for the compiler)
        px, py, pz = position[i, 0], position[i, 1], position[i, 2]
        ri, hi = radius[i], half_length[i]
        ai0, ai1, ai2 = axis[i, 0], axis[i, 1], axis[i, 2]
        outer = ri + hi + skin
        thread = numba.get_thread_id()
        count = 0
        candidates = 0  # within the bounding spheres' reach, in scratch[thread, :candidates]
        for oz in range(-span, span + 1):
            kz = cz + oz
            if kz < 0 or kz >= nz:
                if not qz or nz < width:
                    continue
                kz %= nz
            for oy in range(-span, span + 1):
                ky = cy + oy
                if ky < 0 or ky >= ny:
                    if not qy or ny < width:
                        continue
                    ky %= ny
                row = (kz * ny + ky) * nx
                # the row's cells: one range of the sorted particles (they are contiguous), or one
                # cell at a time where the row wraps around
                for k in range(width if wrapped else 1):
                    if wrapped:
                        first = last = row + (cx - span + k) % nx
                    else:
                        first = row + max(cx - span, 0)
                        last = row + min(cx + span, nx - 1)
                    for j in range(max(start[first], i + 1), start[last + 1]):
                        rx = minimum_image(px - position[j, 0], lx, qx)
                        ry = minimum_image(py - position[j, 1], ly, qy)
                        rz = minimum_image(pz - position[j, 2], lz, qz)
                        if spheres:
                            cut = ri + radius[j] + skin
                            if rx * rx + ry * ry + rz * rz < cut * cut:
                                if count < capacity:
                                    buffer[i, count] = j
                                count += 1
                        else:  # kept (the slot not overwritten) when within reach: no branch
                            reach = outer + extent
                            scratch[thread, candidates] = j
                            candidates += rx * rx + ry * ry + rz * rz < reach * reach
        # the candidates within reach through two tests, each compacting its survivors in place without a
        # branch (their outcomes fall either way at random: as branches they cost about as much as the tests)
        kept = 0
        for k in range(candidates):
            j = scratch[thread, k]
            rx = minimum_image(px - position[j, 0], lx, qx)
            ry = minimum_image(py - position[j, 1], ly, qy)
            rz = minimum_image(pz - position[j, 2], lz, qz)
            # j's centre within r_i + r_j + h_j + skin of i's segment: necessary for the segments to come
            # within r_i + r_j + skin, and a third of the segment test's cost
            u = min(max(-(rx * ai0 + ry * ai1 + rz * ai2), -hi), hi)
            cx, cy, cz = rx + u * ai0, ry + u * ai1, rz + u * ai2
            cut = ri + radius[j] + half_length[j] + skin
            scratch[thread, kept] = j
            kept += cx * cx + cy * cy + cz * cz < cut * cut
        last = capacity - 1
        for k in range(kept):
            j = scratch[thread, k]
            rx = minimum_image(px - position[j, 0], lx, qx)
            ry = minimum_image(py - position[j, 1], ly, qy)
            rz = minimum_image(pz - position[j, 2], lz, qz)
            # written at the row's next slot (the last while the row overflows: then ``counts`` tells the
            # caller to widen the buffer and call again) and kept when the segments come close enough
            buffer[i, min(count, last)] = j
            count += _segments_within(rx, ry, rz, ri, hi, ai0, ai1, ai2, j, axis, radius, half_length, skin)
        counts[i] = count


@njit(cache=True, parallel=True)
def compact_rows(buffer, counts, row_start, neighbours):
    """Copy the first ``counts[i]`` entries of each buffer row into ``neighbours[row_start[i]:]``."""
    for i in prange(counts.shape[0]):
        base = row_start[i]
        for k in range(counts[i]):
            neighbours[base + k] = buffer[i, k]


@njit(cache=True)
def row_offsets(counts):
    """CSR offsets (len n + 1) from row lengths."""
    start = np.zeros(counts.shape[0] + 1, np.int64)
    for i in range(counts.shape[0]):
        start[i + 1] = start[i] + counts[i]
    return start


@njit(cache=True, parallel=True)
def carry_history(old_start, old_neighbours, old_history, new_start, new_neighbours, new_history, old_to_new):
    """Carry tangential histories from the old list to the new one (``new_history`` zeroed beforehand).

    Only a pair whose contact flag (history column 3) is set has a history: a listed pair that does not
    touch holds zeros (``forces._forget``). So each such old pair is looked up in the new list, in the row
    of its new owner (the lower of its particles' new indices; ``old_to_new[k]`` is old particle k's new
    row), and its history copied there, negated (columns 0-2) when the owner changed: the history is the
    displacement of the owner relative to the partner. Pairs no longer listed (none that touch: the list
    is complete) are dropped, new pairs keep their zeros. The same histories as searching every new slot's
    pair in the old rows, for about a third of the listed pairs: a fluidized rod has 2-3 touching pairs of
    7 listed. Each new slot receives at most one old pair, so the rows run in parallel without conflicts.
    """
    for oi in prange(old_start.shape[0] - 1):
        ni = old_to_new[oi]
        for src in range(old_start[oi], old_start[oi + 1]):
            if old_history[src, 3] == 0.0:
                continue
            nj = old_to_new[old_neighbours[src]]
            owner, partner, sign = (ni, nj, 1.0) if ni < nj else (nj, ni, -1.0)
            for slot in range(new_start[owner], new_start[owner + 1]):
                if new_neighbours[slot] == partner:
                    for c in range(3):
                        new_history[slot, c] = sign * old_history[src, c]
                    new_history[slot, 3] = old_history[src, 3]  # the contact flag has no sign
                    break


@njit(cache=True)
def contact_blocks(row_start, neighbours, cell_of, cells_per_layer, span, target_blocks):
    """Cut the rows of a half list into blocks that the contact kernel runs race-free (``forces``).

    Particles are sorted by cell, z-major (``cell_of`` non-decreasing). A block is a run of whole cell
    layers at least ``span`` layers deep, closed once it holds about ``1 / target_blocks`` of the
    listed pairs, so the partners of a row (j > i, at most ``span`` layers above) lie in its own block
    or the next. A row with a partner beyond the next block (a pair across a periodic z boundary) is
    flagged ``deferred``: the kernel runs those rows alone, after the blocks. The cut depends on the
    list only, never on the thread count.

    Returns ``(block_start, deferred, deferred_rows)``: block offsets into the rows (len blocks + 1),
    a flag per row (uint8) and the flagged rows (int64).
    """
    n = row_start.shape[0] - 1
    target = max(1, row_start[n] // max(target_blocks, 1))
    starts = np.empty(n + 2, np.int64)
    starts[0] = 0
    blocks = 0
    first_layer = cell_of[0] // cells_per_layer if n else 0
    for i in range(1, n):
        layer = cell_of[i] // cells_per_layer
        if (layer != cell_of[i - 1] // cells_per_layer and layer - first_layer >= span
                and row_start[i] - row_start[starts[blocks]] >= target):
            blocks += 1
            starts[blocks] = i
            first_layer = layer
    blocks += 1
    starts[blocks] = n
    block_start = starts[:blocks + 1].copy()
    deferred = np.zeros(n, np.uint8)
    count = 0
    for b in range(blocks):
        limit = block_start[min(b + 2, blocks)]
        for i in range(block_start[b], block_start[b + 1]):
            for slot in range(row_start[i], row_start[i + 1]):
                j = neighbours[slot]
                if j < i or j >= limit:
                    deferred[i] = 1
                    count += 1
                    break
    deferred_rows = np.empty(count, np.int64)
    k = 0
    for i in range(n):
        if deferred[i]:
            deferred_rows[k] = i
            k += 1
    return block_start, deferred, deferred_rows
