"""O(N) neighbour search: particles sorted by cell, half Verlet lists with a skin.

A pair (i, j), i < j, is listed in row i when the shortest distance between the axis segments
is below ``r_i + r_j + skin``. Because every point of a segment moves by at most
``|dx| + h |d axis|`` (centre displacement plus half length times the change of the unit axis),
the list stays complete until some particle's end points have moved by more than ``skin / 2``;
the integrator tracks that bound and asks for a rebuild.

The list is stored compactly (CSR): row i's partners are ``neighbours[row_start[i]:row_start[i+1]]``
(int32), and a pair's slot is its position in that flat array. Compact rows matter: with padded
fixed-width rows the per-step working set of a 32,500-particle bed overflowed the L3 cache and
every kernel became latency bound. Each contact's tangential history lives in its pair's slot; on
a rebuild the histories are carried over to the new slots (through the particle permutation of the
cell sort), with their sign flipped when the pair's owner changes. Each pair also gets a slot in
its partner's own (CSR) block of partner results (``build_partner_slots``), so forces are reduced
without write conflicts.
"""
from __future__ import annotations

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
        c = np.empty(3, dtype=np.int64)
        for d in range(3):
            k = int(np.floor((position[i, d] - box_lo[d]) / cell_size[d]))
            if k < 0:
                k = 0
            elif k >= n_cells[d]:
                k = n_cells[d] - 1
            c[d] = k
        cell_of[i] = (c[2] * n_cells[1] + c[1]) * n_cells[0] + c[0]


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
def _pair_within(i, j, position, axis, radius, half_length, box_length, periodic, skin):
    rx = minimum_image(position[i, 0] - position[j, 0], box_length[0], periodic[0])
    ry = minimum_image(position[i, 1] - position[j, 1], box_length[1], periodic[1])
    rz = minimum_image(position[i, 2] - position[j, 2], box_length[2], periodic[2])
    reach = radius[i] + half_length[i] + radius[j] + half_length[j] + skin
    if rx * rx + ry * ry + rz * rz >= reach * reach:
        return False
    s, t = segment_parameters(rx, ry, rz, axis[i, 0], axis[i, 1], axis[i, 2], half_length[i],
                              axis[j, 0], axis[j, 1], axis[j, 2], half_length[j])
    dx = rx + s * axis[i, 0] - t * axis[j, 0]
    dy = ry + s * axis[i, 1] - t * axis[j, 1]
    dz = rz + s * axis[i, 2] - t * axis[j, 2]
    cut = radius[i] + radius[j] + skin
    return dx * dx + dy * dy + dz * dz < cut * cut


@njit(cache=True, parallel=True)
def build_half_list(position, axis, radius, half_length, box_lo, box_length, periodic, cell_size,
                    n_cells, cell_of, start, skin, span, buffer, counts):
    """The half list in one pass: row i's partners j > i go to ``buffer[i, :]`` (a fixed
    capacity per row) in cell-scan order and ``counts[i]`` gets the row's length, which may exceed
    the capacity: the caller then enlarges ``buffer`` and calls again (``compact_rows`` copies the
    rows into the CSR list). One pass instead of a counting pass and a filling pass: each
    candidate pair is tested once.

    Scans the 27 cells around each particle's cell (wrapped on periodic axes, which need at
    least 3 cells so no cell is visited twice). Particles are sorted by cell, so within a cell only
    the indices above i are visited.
    """
    n = position.shape[0]
    capacity = buffer.shape[1]
    nx, ny, nz = n_cells[0], n_cells[1], n_cells[2]
    width = 2 * span + 1
    wrapped = periodic[0] and nx >= width  # a periodic x axis wraps each row of cells around
    for i in prange(n):
        c = cell_of[i]
        cx = c % nx
        cy = (c // nx) % ny
        cz = c // (nx * ny)
        count = 0
        for oz in range(-span, span + 1):
            kz = cz + oz
            if kz < 0 or kz >= nz:
                if not periodic[2] or nz < width:
                    continue
                kz %= nz
            for oy in range(-span, span + 1):
                ky = cy + oy
                if ky < 0 or ky >= ny:
                    if not periodic[1] or ny < width:
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
                        if _pair_within(i, j, position, axis, radius, half_length, box_length, periodic, skin):
                            if count < capacity:
                                buffer[i, count] = j
                            count += 1
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
def transfer_history(old_start, old_neighbours, old_history, new_start, new_neighbours, new_history, new_to_old):
    """Carry tangential histories from the old list to the new one.

    ``new_to_old[k]`` is the old row of new particle k. A pair found in the old row of the
    same owner keeps its history; one found in the partner's old row gets it negated (the
    history is the displacement of the owner relative to the partner; the contact flag in column 3
    is copied). New pairs start at 0.
    """
    n = new_start.shape[0] - 1
    for i in prange(n):
        oi = new_to_old[i]
        for slot in range(new_start[i], new_start[i + 1]):
            oj = new_to_old[new_neighbours[slot]]
            for c in range(4):
                new_history[slot, c] = 0.0
            found = False
            for src in range(old_start[oi], old_start[oi + 1]):
                if old_neighbours[src] == oj:
                    for c in range(4):
                        new_history[slot, c] = old_history[src, c]
                    found = True
                    break
            if not found:
                for src in range(old_start[oj], old_start[oj + 1]):
                    if old_neighbours[src] == oi:
                        for c in range(3):
                            new_history[slot, c] = -old_history[src, c]
                        new_history[slot, 3] = old_history[src, 3]  # the contact flag has no sign
                        break


@njit(cache=True)
def build_partner_slots(row_start, neighbours, partner_start, partner_slot):
    """Reserve, for every listed pair (slot ``s``, partner j), an entry in j's own block of the
    partner-result array: ``partner_slot[s]`` in ``[partner_start[j], partner_start[j+1])``.
    ``partner_start`` (len n + 1) gets the CSR offsets of the blocks."""
    n = row_start.shape[0] - 1
    partner_start[:] = 0
    for s in range(row_start[n]):
        partner_start[neighbours[s] + 1] += 1
    for j in range(n):
        partner_start[j + 1] += partner_start[j]
    fill = partner_start[:n].copy()
    for s in range(row_start[n]):
        j = neighbours[s]
        partner_slot[s] = fill[j]
        fill[j] += 1
