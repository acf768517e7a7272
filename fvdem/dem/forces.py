"""Contact force kernel: every listed pair once, both sides accumulated straight onto the particles,
race-free by blocks of cell layers.

``contact_forces`` walks the half list row by row. Row i's pairs add ``F`` and the torque on i to
particle i (summed in registers, written once per row) and ``-F`` and the torque on the partner
straight into the partner's ``force[j]``, ``torque[j]``; the row's wall contacts follow. Newton's third
law holds pair by pair by construction: the partner gets the exact negative of the owner's force.

**Why direct accumulation and no per-pair results.** An earlier design stored each pair's partner
side in a slot of the partner's own block and summed the blocks in a second, per-particle pass. On the
settled 32,500-sphere bed that pass cost 32-39 ns per particle for additions alone: the partner
results (6 floats per listed pair, 5 MB) were written, read for ownership and read back every step.
Accumulating in place touches only particle rows that the pair loop has just read (the partner's
position and velocity are in cache), and the two kernels become one (pair + gather 191-221 ns per
particle against 131-137 for the pairs alone in place, same process, 1 thread; docs/benchmarks.md).

**Why it is race-free.** Particles are sorted by cell (z-major), and a half list holds j > i with j at
most ``span`` cell layers above i. The rows are cut into blocks of whole cell layers, each at least
``span`` layers deep (``neighbours.contact_blocks``), so the partners of a row in block b lie in block
b or b + 1. Even blocks run in parallel, then odd ones: two blocks running at once are at least two
apart and write disjoint particles. Rows with a partner further away (across a periodic z boundary)
are *deferred* and run alone after both phases. The summation order is fixed by the blocks, not by the
thread count: results are bit-identical on any number of threads.

Walls are the six faces of the axis-aligned box that are not periodic. A spherocylinder touches a
wall at each end point that is within its radius of the wall (two contacts for a rod lying flat,
each with its own tangential history); a sphere has one end point.
"""
from __future__ import annotations

import math

from numba import njit, prange

from .contact_law import LAW_K_N, ZETA_N, ZETA_WALL, contact_force, kernel_constants, normal_damping, wall_constants
from .geometry import cross, minimum_image, segment_parameters

# fast-math without 'nnan'/'ninf': FMA contraction, reciprocals, reassociation; NaN and Inf still
# propagate so a blown-up state is detected. Results stay deterministic for a given build.
FASTMATH = {"contract", "arcp", "nsz", "afn", "reassoc"}


@njit(cache=True, inline="always")
def _forget(history, slot):
    """A listed pair that does not touch: clear its history once, when the contact ends (the flag in
    history column 3 says it existed)."""
    if history[slot, 3] != 0.0:
        for c in range(4):
            history[slot, c] = 0.0


@njit(cache=True, inline="always")
def _add_to_partner(force, torque, j, fx, fy, fz, tx, ty, tz):
    """The partner's side of a pair: ``-F`` and the torque ``t`` on the partner."""
    force[j, 0] -= fx
    force[j, 1] -= fy
    force[j, 2] -= fz
    torque[j, 0] += tx
    torque[j, 1] += ty
    torque[j, 2] += tz


@njit(cache=True, inline="always")
def _normal(dx, dy, dz, dist2, radius_sum):
    """Unit normal (partner to particle) and overlap [m] of a touching pair whose closest points are
    ``d`` apart (``dist2 = |d|^2 < radius_sum^2``)."""
    dist = math.sqrt(dist2)
    if dist > 1e-14 * radius_sum:
        inv = 1.0 / dist
        return dx * inv, dy * inv, dz * inv, radius_sum - dist
    return 0.0, 0.0, 1.0, radius_sum - dist  # coincident axes or centres: any direction is a normal


@njit(cache=True, inline="always")
def _pair_constants(i, j, ri, rj, mass, inertia, params, law, same, uniform, spheres):
    """``(eta_n, r_eff, inertia_eff)`` of pair (i, j): ``uniform`` (read once per row) when all particles
    are identical (``same``), else from the pair's masses, radii and smaller principal inertias
    (``spheres``: the transverse one, which the kicks use; a sphere's two differ only at round-off)."""
    if same:
        return uniform
    ii = inertia[i, 0] if spheres else min(inertia[i, 0], inertia[i, 1])
    ij = inertia[j, 0] if spheres else min(inertia[j, 0], inertia[j, 1])
    return (normal_damping(params[ZETA_N], mass[i] * mass[j] / (mass[i] + mass[j]), law[LAW_K_N]), ri * rj / (ri + rj),
            ii * ij / (ii + ij))


@njit(cache=True, inline="always")
def _pair_row(i, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia, row_start,
              neighbours, history, force, torque, box_length, periodic, params, law, uniform):
    """Row i of the half list, any shapes: the partners' sides added to ``force``/``torque``; returns
    row i's own sum ``(fx, fy, fz, tx, ty, tz)``, its largest overlap / diameter and its touching pairs.
    ``uniform = (eta_n, r_eff, inertia_eff)`` when all particles are identical (pair constants
    precomputed), else ``uniform[0] < 0``."""
    same = uniform[0] >= 0.0
    constants = (uniform[0], uniform[1], uniform[2])  # read once: the stores below might alias them
    lx, ly, lz = box_length[0], box_length[1], box_length[2]
    qx, qy, qz = periodic[0], periodic[1], periodic[2]
    max_overlap = 0.0  # identical particles: the largest overlap [m], divided by the diameter at the end
    touching = 0
    sfx = 0.0
    sfy = 0.0
    sfz = 0.0
    stx = 0.0
    sty = 0.0
    stz = 0.0
    # row i's own values, read once (the stores below might alias them for the compiler)
    px, py, pz = position[i, 0], position[i, 1], position[i, 2]
    ri, hi = radius[i], half_length[i]
    vix, viy, viz = velocity[i, 0], velocity[i, 1], velocity[i, 2]
    ai0, ai1, ai2 = axis[i, 0], axis[i, 1], axis[i, 2]
    wi0, wi1, wi2 = angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2]
    for slot in range(row_start[i], row_start[i + 1]):
        j = neighbours[slot]
        rx = minimum_image(px - position[j, 0], lx, qx)
        ry = minimum_image(py - position[j, 1], ly, qy)
        rz = minimum_image(pz - position[j, 2], lz, qz)
        aj0, aj1, aj2 = axis[j, 0], axis[j, 1], axis[j, 2]
        s, t = segment_parameters(rx, ry, rz, ai0, ai1, ai2, hi, aj0, aj1, aj2, half_length[j])
        dx = rx + s * ai0 - t * aj0
        dy = ry + s * ai1 - t * aj1
        dz = rz + s * ai2 - t * aj2
        dist2 = dx * dx + dy * dy + dz * dz
        rj = radius[j]
        radius_sum = ri + rj
        if dist2 >= radius_sum * radius_sum:
            _forget(history, slot)
            continue
        nx, ny, nz, overlap = _normal(dx, dy, dz, dist2, radius_sum)
        # lever arms from each centre to the contact point (middle of the overlap)
        li = ri - 0.5 * overlap
        lj = rj - 0.5 * overlap
        lix, liy, liz = s * ai0 - li * nx, s * ai1 - li * ny, s * ai2 - li * nz
        ljx, ljy, ljz = t * aj0 + lj * nx, t * aj1 + lj * ny, t * aj2 + lj * nz
        wj0, wj1, wj2 = angular_velocity[j, 0], angular_velocity[j, 1], angular_velocity[j, 2]
        ci = cross(wi0, wi1, wi2, lix, liy, liz)
        cj = cross(wj0, wj1, wj2, ljx, ljy, ljz)
        vx = vix + ci[0] - velocity[j, 0] - cj[0]
        vy = viy + ci[1] - velocity[j, 1] - cj[1]
        vz = viz + ci[2] - velocity[j, 2] - cj[2]
        eta_n, r_eff, inertia_eff = _pair_constants(i, j, ri, rj, mass, inertia, params, law, same, constants, False)
        fx, fy, fz, trx, tr_y, trz, f_n = contact_force(
            history, slot, overlap, nx, ny, nz, vx, vy, vz,
            wi0 - wj0, wi1 - wj1, wi2 - wj2, eta_n, r_eff, inertia_eff, law)
        ti = cross(lix, liy, liz, fx, fy, fz)
        tj = cross(ljx, ljy, ljz, -fx, -fy, -fz)
        sfx += fx
        sfy += fy
        sfz += fz
        stx += ti[0] + trx
        sty += ti[1] + tr_y
        stz += ti[2] + trz
        _add_to_partner(force, torque, j, fx, fy, fz, tj[0] - trx, tj[1] - tr_y, tj[2] - trz)
        touching += 1
        ratio = overlap if same else overlap / (2.0 * min(ri, rj))
        if ratio > max_overlap:
            max_overlap = ratio
    return sfx, sfy, sfz, stx, sty, stz, (max_overlap / (2.0 * ri) if same else max_overlap), touching


@njit(cache=True, inline="always")
def _sphere_row(i, position, velocity, angular_velocity, radius, mass, inertia, row_start, neighbours, history,
                force, torque, box_length, periodic, params, law, uniform):
    """``_pair_row`` for spheres: the same contacts and results (to round-off: tested against it),
    with the contact point on the line of centres, so no segment geometry and the lever arms
    ``-l_i n`` and ``l_j n`` folded into the velocity and the torques. 15-25 % faster on the settled
    32,500-sphere bed (docs/benchmarks.md)."""
    same = uniform[0] >= 0.0
    constants = (uniform[0], uniform[1], uniform[2])  # read once: the stores below might alias them
    lx, ly, lz = box_length[0], box_length[1], box_length[2]
    qx, qy, qz = periodic[0], periodic[1], periodic[2]
    max_overlap = 0.0  # identical particles: the largest overlap [m], divided by the diameter at the end
    touching = 0
    sfx = 0.0
    sfy = 0.0
    sfz = 0.0
    stx = 0.0
    sty = 0.0
    stz = 0.0
    px, py, pz = position[i, 0], position[i, 1], position[i, 2]
    ri = radius[i]
    vix, viy, viz = velocity[i, 0], velocity[i, 1], velocity[i, 2]
    wi0, wi1, wi2 = angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2]
    for slot in range(row_start[i], row_start[i + 1]):
        j = neighbours[slot]
        dx = minimum_image(px - position[j, 0], lx, qx)
        dy = minimum_image(py - position[j, 1], ly, qy)
        dz = minimum_image(pz - position[j, 2], lz, qz)
        dist2 = dx * dx + dy * dy + dz * dz
        rj = radius[j]
        radius_sum = ri + rj
        if dist2 >= radius_sum * radius_sum:
            _forget(history, slot)
            continue
        nx, ny, nz, overlap = _normal(dx, dy, dz, dist2, radius_sum)
        li = ri - 0.5 * overlap
        lj = rj - 0.5 * overlap
        wj0, wj1, wj2 = angular_velocity[j, 0], angular_velocity[j, 1], angular_velocity[j, 2]
        # contact-point velocity v_i + w_i x (-l_i n) - v_j - w_j x (l_j n) = v_i - v_j - (l_i w_i + l_j w_j) x n
        sx = li * wi0 + lj * wj0
        sy = li * wi1 + lj * wj1
        sz = li * wi2 + lj * wj2
        vx = vix - velocity[j, 0] - (sy * nz - sz * ny)
        vy = viy - velocity[j, 1] - (sz * nx - sx * nz)
        vz = viz - velocity[j, 2] - (sx * ny - sy * nx)
        eta_n, r_eff, inertia_eff = _pair_constants(i, j, ri, rj, mass, inertia, params, law, same, constants, True)
        fx, fy, fz, trx, tr_y, trz, f_n = contact_force(
            history, slot, overlap, nx, ny, nz, vx, vy, vz,
            wi0 - wj0, wi1 - wj1, wi2 - wj2, eta_n, r_eff, inertia_eff, law)
        # torques: (-l_i n) x F on i, (l_j n) x (-F) on j, both -l (n x F)
        cx, cy, cz = cross(nx, ny, nz, fx, fy, fz)
        sfx += fx
        sfy += fy
        sfz += fz
        stx += trx - li * cx
        sty += tr_y - li * cy
        stz += trz - li * cz
        _add_to_partner(force, torque, j, fx, fy, fz, -lj * cx - trx, -lj * cy - tr_y, -lj * cz - trz)
        touching += 1
        ratio = overlap if same else overlap / (2.0 * min(ri, rj))
        if ratio > max_overlap:
            max_overlap = ratio
    return sfx, sfy, sfz, stx, sty, stz, (max_overlap / (2.0 * ri) if same else max_overlap), touching


@njit(cache=True, inline="always")
def _wall_contacts(i, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                   wall_active, bounds, wall_history, wall_mask, params, law):
    """Particle i's contacts with the active walls (faces x-, x+, y-, y+, z-, z+; ``bounds`` their
    positions as scalars ``(x-, x+, y-, y+, z-, z+)``, -inf / +inf where inactive; ``bounds[face]`` for a
    face's position): returns
    ``(fx, fy, fz, tx, ty, tz, largest overlap / diameter, contacts)``. ``wall_history`` is flat
    ``(N * 12, 4)``: slot ``(i*6 + face)*2 + end``; bit ``face*2 + end`` of ``wall_mask[i]`` is set while
    that slot holds a contact, so particles away from walls cost one integer read instead of twelve
    history rows."""
    fx = fy = fz = tx = ty = tz = 0.0
    max_overlap = 0.0
    wall_contacts = 0
    mask = wall_mask[i]
    h = half_length[i]
    r = radius[i]
    reach = r + h
    x, y, z = position[i, 0], position[i, 1], position[i, 2]
    if (mask == 0 and x - bounds[0] >= reach and bounds[1] - x >= reach and y - bounds[2] >= reach
            and bounds[3] - y >= reach and z - bounds[4] >= reach and bounds[5] - z >= reach):
        # out of every wall's reach with no wall history to clear: most particles (the face loop
        # below cost twice a particle's force sums for them)
        return fx, fy, fz, tx, ty, tz, max_overlap, wall_contacts
    n_ends = 2 if h > 0.0 else 1
    imin = min(inertia[i, 0], inertia[i, 1])
    wall_law = wall_constants(law, params)  # the pair law with the walls' sliding and rolling friction
    for face in range(6):
        if not wall_active[face]:
            continue
        d = face // 2
        upper = face % 2 == 1
        gap = bounds[face] - position[i, d] if upper else position[i, d] - bounds[face]
        if gap >= r + h:  # out of reach of this wall: clear stale histories only
            if mask & (3 << (2 * face)):
                for end in range(2):
                    slot = (i * 6 + face) * 2 + end
                    for c in range(4):
                        wall_history[slot, c] = 0.0
                mask &= ~(3 << (2 * face))
            continue
        for end in range(n_ends):
            sign = -1.0 if end == 0 else 1.0
            ex = sign * h * axis[i, 0]
            ey = sign * h * axis[i, 1]
            ez = sign * h * axis[i, 2]
            e_d = position[i, d] + (ex if d == 0 else (ey if d == 1 else ez))
            dist = bounds[face] - e_d if upper else e_d - bounds[face]
            slot = (i * 6 + face) * 2 + end
            overlap = r - dist
            bit = 1 << (2 * face + end)
            if overlap <= 0.0:
                if mask & bit:
                    for c in range(4):
                        wall_history[slot, c] = 0.0
                    mask &= ~bit
                continue
            mask |= bit
            nd = -1.0 if upper else 1.0
            nx = nd if d == 0 else 0.0
            ny = nd if d == 1 else 0.0
            nz = nd if d == 2 else 0.0
            lever = r - 0.5 * overlap
            lx, ly, lz = ex - lever * nx, ey - lever * ny, ez - lever * nz
            c = cross(angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2], lx, ly, lz)
            vx = velocity[i, 0] + c[0]
            vy = velocity[i, 1] + c[1]
            vz = velocity[i, 2] + c[2]
            wfx, wfy, wfz, trx, tr_y, trz, f_n = contact_force(
                wall_history, slot, overlap, nx, ny, nz, vx, vy, vz,
                angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2],
                normal_damping(params[ZETA_WALL], mass[i], law[LAW_K_N]), r, imin, wall_law)
            fx += wfx
            fy += wfy
            fz += wfz
            t = cross(lx, ly, lz, wfx, wfy, wfz)
            tx += t[0] + trx
            ty += t[1] + tr_y
            tz += t[2] + trz
            wall_contacts += 1
            if overlap / (2.0 * r) > max_overlap:
                max_overlap = overlap / (2.0 * r)
    wall_mask[i] = mask
    return fx, fy, fz, tx, ty, tz, max_overlap, wall_contacts


@njit(cache=True, inline="always")
def _row(i, spheres, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia, row_start,
         neighbours, history, wall_active, bounds, wall_history, wall_mask, box_length, periodic, params,
         law, uniform, force, torque, row_max_overlap, row_contacts, row_wall_contacts):
    """Row i's pairs and particle i's walls, accumulated onto ``force``/``torque``. At most 30 arguments
    (a call with more cannot be inlined; docs/ARCHITECTURE.md, "Why the DEM kernels take their arrays one
    by one")."""
    if spheres:
        fx, fy, fz, tx, ty, tz, pair_overlap, touching = _sphere_row(
            i, position, velocity, angular_velocity, radius, mass, inertia, row_start, neighbours, history,
            force, torque, box_length, periodic, params, law, uniform)
    else:
        fx, fy, fz, tx, ty, tz, pair_overlap, touching = _pair_row(
            i, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia, row_start,
            neighbours, history, force, torque, box_length, periodic, params, law, uniform)
    wfx, wfy, wfz, wtx, wty, wtz, wall_overlap, walls = _wall_contacts(
        i, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia, wall_active, bounds,
        wall_history, wall_mask, params, law)
    force[i, 0] += fx + wfx
    force[i, 1] += fy + wfy
    force[i, 2] += fz + wfz
    torque[i, 0] += tx + wtx
    torque[i, 1] += ty + wty
    torque[i, 2] += tz + wtz
    row_max_overlap[i] = max(pair_overlap, wall_overlap)
    row_contacts[i] = touching
    row_wall_contacts[i] = walls


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def contact_forces(spheres, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                   row_start, neighbours, history, block_start, deferred, deferred_rows, wall_active, box_lo,
                   box_hi, wall_history, wall_mask, box_length, periodic, params, uniform,
                   force, torque, row_max_overlap, row_contacts, row_wall_contacts):
    """Contact force [N] and torque [N m] on every particle into ``force``, ``torque`` (N, 3): listed
    pairs and walls (faces flagged in ``wall_active``).

    Row i's pairs are the slots ``row_start[i] .. row_start[i+1]`` of the CSR half list ``neighbours``;
    ``history`` (4 columns, see ``contact_law``) is indexed by slot. ``spheres``: all particles are
    spheres (the sphere path, no segment geometry). The rows are cut into ``block_start`` blocks
    (``neighbours.contact_blocks``): even blocks run in parallel, then odd ones, then the rows flagged in
    ``deferred`` (listed in ``deferred_rows``) one after another. ``row_max_overlap[i]`` gets the
    largest overlap/diameter of particle i's row and walls, ``row_contacts[i]`` and
    ``row_wall_contacts[i]`` its touching pairs and wall contacts.
    """
    n = position.shape[0]
    law = kernel_constants(params)
    bounds = (box_lo[0] if wall_active[0] else -math.inf, box_hi[0] if wall_active[1] else math.inf,
              box_lo[1] if wall_active[2] else -math.inf, box_hi[1] if wall_active[3] else math.inf,
              box_lo[2] if wall_active[4] else -math.inf, box_hi[2] if wall_active[5] else math.inf)
    for i in prange(n):
        for c in range(3):
            force[i, c] = 0.0
            torque[i, c] = 0.0
    blocks = block_start.shape[0] - 1
    late = deferred_rows.shape[0]
    # Pass 0 runs the even blocks side by side, pass 1 the odd ones, pass 2 the deferred rows one after another
    # (its one iteration). One call of ``_row`` for the three: numba inlines it once (inlined in the parallel
    # loop and again after it, it took a third more compilation; the same results bit for bit).
    for parity in range(3):
        count = (blocks - parity + 1) // 2 if parity < 2 else min(late, 1)
        for k in prange(count):
            if parity < 2:
                start, stop = block_start[2 * k + parity], block_start[2 * k + parity + 1]
            else:
                start, stop = 0, late
            for m in range(start, stop):
                if parity < 2:
                    i = m
                    if deferred[i]:
                        continue
                else:
                    i = deferred_rows[m]
                _row(i, spheres, position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                     row_start, neighbours, history, wall_active, bounds, wall_history, wall_mask,
                     box_length, periodic, params, law, uniform, force, torque, row_max_overlap, row_contacts,
                     row_wall_contacts)
