"""O(N) neighbour search: particles sorted by cell, half Verlet lists with a skin.

A pair (i, j), i < j, is listed in row i when the shortest distance between the axis segments
is below ``r_i + r_j + skin``. Because every point of a segment moves by at most
``|dx| + h |d axis|`` (centre displacement plus half length times the change of the unit axis),
the list stays complete until some particle's end points have moved by more than ``skin / 2``;
the integrator tracks that bound and asks for a rebuild.

Rows are fixed-width (``max_neighbours`` columns, grown when needed). Each contact's
tangential history lives in the slot of its pair; on a rebuild the histories are carried over
to the new slots (through the particle permutation of the cell sort), with their sign flipped
when the pair's owner changes. Each pair also gets a slot in its partner's own block of partner
results (``build_partner_slots``), so forces are reduced without write conflicts.
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
                    n_cells, cell_of, start, skin, neighbours, counts, fill):
    """Count (``fill=False``) or fill (``fill=True``) row i with partners j > i.

    Scans the 27 cells around each particle's cell (wrapped on periodic axes, which need at
    least 3 cells so no cell is visited twice). Returns nothing; ``counts`` gets row lengths.
    """
    n = position.shape[0]
    nx, ny, nz = n_cells[0], n_cells[1], n_cells[2]
    for i in prange(n):
        c = cell_of[i]
        cx = c % nx
        cy = (c // nx) % ny
        cz = c // (nx * ny)
        count = 0
        for oz in range(-1, 2):
            kz = cz + oz
            if kz < 0 or kz >= nz:
                if not periodic[2] or nz < 3:
                    continue
                kz %= nz
            for oy in range(-1, 2):
                ky = cy + oy
                if ky < 0 or ky >= ny:
                    if not periodic[1] or ny < 3:
                        continue
                    ky %= ny
                for ox in range(-1, 2):
                    kx = cx + ox
                    if kx < 0 or kx >= nx:
                        if not periodic[0] or nx < 3:
                            continue
                        kx %= nx
                    cell = (kz * ny + ky) * nx + kx
                    for j in range(start[cell], start[cell + 1]):
                        if j <= i:
                            continue
                        if _pair_within(i, j, position, axis, radius, half_length, box_length, periodic, skin):
                            if fill:
                                neighbours[i, count] = j
                            count += 1
        counts[i] = count


@njit(cache=True, parallel=True)
def transfer_history(old_neighbours, old_counts, old_history, new_neighbours, new_counts, new_history,
                     new_to_old, old_width, new_width):
    """Carry tangential histories from the old list to the new one.

    ``new_to_old[k]`` is the old row of new particle k. A pair found in the old row of the
    same owner keeps its history; one found in the partner's old row gets it negated (the
    history is the displacement of the owner relative to the partner; the contact flag in column 3
    is copied). New pairs start at 0.
    """
    n = new_counts.shape[0]
    old_of_new = new_to_old
    for i in prange(n):
        oi = old_of_new[i]
        for k in range(new_counts[i]):
            oj = old_of_new[new_neighbours[i, k]]
            slot = i * new_width + k
            for c in range(4):
                new_history[slot, c] = 0.0
            found = False
            for m in range(old_counts[oi]):
                if old_neighbours[oi, m] == oj:
                    src = oi * old_width + m
                    for c in range(4):
                        new_history[slot, c] = old_history[src, c]
                    found = True
                    break
            if not found:
                for m in range(old_counts[oj]):
                    if old_neighbours[oj, m] == oi:
                        src = oj * old_width + m
                        for c in range(3):
                            new_history[slot, c] = -old_history[src, c]
                        new_history[slot, 3] = old_history[src, 3]  # the contact flag has no sign
                        break


@njit(cache=True)
def build_partner_slots(neighbours, counts, partner_counts, partner_slot):
    """Reserve, for every listed pair (slot ``i * width + k``, partner j), an entry in j's own block
    of the partner-result array: ``partner_slot[slot] = j * partner_width + m``. ``partner_counts[j]``
    gets the number of pairs in which j is the partner; ``partner_width`` is their maximum.
    Returns ``partner_width``."""
    n = counts.shape[0]
    width = neighbours.shape[1]
    partner_counts[:] = 0
    for i in range(n):
        for k in range(counts[i]):
            partner_counts[neighbours[i, k]] += 1
    partner_width = max(1, partner_counts.max()) if n else 1
    partner_counts[:] = 0
    for i in range(n):
        for k in range(counts[i]):
            j = neighbours[i, k]
            partner_slot[i * width + k] = j * partner_width + partner_counts[j]
            partner_counts[j] += 1
    return partner_width
