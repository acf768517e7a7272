"""Contact force kernels: per-contact results first, then one race-free reduction per particle.

``pair_forces`` evaluates every listed pair once (parallel over owner rows). The owner's side is
summed in its own row (``owner_sum``); the partner's side ``[-F, torque on partner]`` is stored in
a slot reserved for that pair inside the partner's own contiguous block of ``partner_result``
(``partner_slot`` maps pair slot -> block slot; each block slot has exactly one writer, so no races).
``gather_forces`` then adds, per particle, its owner sum, its contiguous partner block and its wall
contacts. The partner side is thus a scattered *store* in the pair kernel and a contiguous *load* in
the reduction (storing per-pair results and gathering them by a reverse index made every partner
read a dependent cache miss and cost twice as much). Newton's third law holds pair by pair by
construction: the partner's force is the exact negative of the owner's.

Walls are the six faces of the axis-aligned box that are not periodic. A spherocylinder touches a
wall at each end point that is within its radius of the wall (two contacts for a rod lying flat,
each with its own tangential history); a sphere has one end point.
"""
from __future__ import annotations

import math

from numba import njit, prange

from .contact_law import ZETA_N, ZETA_WALL, contact_force, kernel_constants, normal_damping
from .geometry import minimum_image, segment_parameters

# fast-math without 'nnan'/'ninf': FMA contraction, reciprocals, reassociation; NaN and Inf still
# propagate so a blown-up state is detected. Results stay deterministic for a given build.
FASTMATH = {"contract", "arcp", "nsz", "afn", "reassoc"}


@njit(cache=True, inline="always")
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, inline="always")
def _forget(history, slot, partner_slot, partner_result):
    """A listed pair that does not touch: clear its history and its partner result, once, when the
    contact ends (the flag in history column 3 says it existed)."""
    if history[slot, 3] != 0.0:
        for c in range(4):
            history[slot, c] = 0.0
        dest = partner_slot[slot]
        for c in range(6):
            partner_result[dest, c] = 0.0


@njit(cache=True, inline="always")
def _store_partner(partner_result, dest, fx, fy, fz, tx, ty, tz):
    """The partner's side of a pair: ``-F`` and the torque on the partner, in its own block's slot."""
    partner_result[dest, 0] = -fx
    partner_result[dest, 1] = -fy
    partner_result[dest, 2] = -fz
    partner_result[dest, 3] = tx
    partner_result[dest, 4] = ty
    partner_result[dest, 5] = tz


@njit(cache=True, inline="always")
def _store_row(owner_sum, i, fx, fy, fz, tx, ty, tz):
    owner_sum[i, 0] = fx
    owner_sum[i, 1] = fy
    owner_sum[i, 2] = fz
    owner_sum[i, 3] = tx
    owner_sum[i, 4] = ty
    owner_sum[i, 5] = tz


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def pair_forces(position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                row_start, neighbours, history, partner_slot, owner_sum, partner_result, row_max_overlap,
                row_contacts, box_length, periodic, params, uniform):
    """Contact force and torques of every listed pair (any shapes; ``sphere_pair_forces`` is the same for
    spheres only, without the segment geometry).

    Row i's pairs are the slots ``row_start[i] .. row_start[i+1]`` of the CSR list ``neighbours``;
    ``history`` (4 columns, see ``contact_law``) is indexed by slot; ``owner_sum`` (N, 6) gets each row's ``[force, torque]`` sum;
    ``partner_result[partner_slot[slot]]`` gets ``[-force, torque on partner]``. Partner entries of
    non-touching pairs hold zeros: cleared once when a contact ends (a list rebuild starts from
    zeros), so steady non-contacts cost no writes. ``uniform = (eta_n, r_eff, inertia_eff)`` when all
    particles are identical (pair constants precomputed), else ``uniform[0] < 0``. ``row_max_overlap[i]`` gets the largest overlap/diameter of row i and
    ``row_contacts[i]`` the number of touching pairs in row i.
    """
    n = position.shape[0]
    law = kernel_constants(params)
    same = uniform[0] >= 0.0
    lx, ly, lz = box_length[0], box_length[1], box_length[2]
    qx, qy, qz = periodic[0], periodic[1], periodic[2]
    for i in prange(n):
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
                _forget(history, slot, partner_slot, partner_result)
                continue
            dist = math.sqrt(dist2)
            if dist > 1e-14 * radius_sum:
                inv = 1.0 / dist
                nx, ny, nz = dx * inv, dy * inv, dz * inv
            else:  # coincident axes: any direction is a normal
                nx, ny, nz = 0.0, 0.0, 1.0
            overlap = radius_sum - dist
            # lever arms from each centre to the contact point (middle of the overlap)
            li = ri - 0.5 * overlap
            lj = rj - 0.5 * overlap
            lix, liy, liz = s * ai0 - li * nx, s * ai1 - li * ny, s * ai2 - li * nz
            ljx, ljy, ljz = t * aj0 + lj * nx, t * aj1 + lj * ny, t * aj2 + lj * nz
            wj0, wj1, wj2 = angular_velocity[j, 0], angular_velocity[j, 1], angular_velocity[j, 2]
            ci = _cross(wi0, wi1, wi2, lix, liy, liz)
            cj = _cross(wj0, wj1, wj2, ljx, ljy, ljz)
            vx = vix + ci[0] - velocity[j, 0] - cj[0]
            vy = viy + ci[1] - velocity[j, 1] - cj[1]
            vz = viz + ci[2] - velocity[j, 2] - cj[2]
            if same:
                eta_n, r_eff, inertia_eff = uniform[0], uniform[1], uniform[2]
            else:
                eta_n = normal_damping(params[ZETA_N], mass[i] * mass[j] / (mass[i] + mass[j]), law[0])
                r_eff = ri * rj / radius_sum
                ii = min(inertia[i, 0], inertia[i, 1])
                ij = min(inertia[j, 0], inertia[j, 1])
                inertia_eff = ii * ij / (ii + ij)
            fx, fy, fz, trx, tr_y, trz, f_n = contact_force(
                history, slot, overlap, nx, ny, nz, vx, vy, vz,
                wi0 - wj0, wi1 - wj1, wi2 - wj2, eta_n, r_eff, inertia_eff, law)
            ti = _cross(lix, liy, liz, fx, fy, fz)
            tj = _cross(ljx, ljy, ljz, -fx, -fy, -fz)
            sfx += fx
            sfy += fy
            sfz += fz
            stx += ti[0] + trx
            sty += ti[1] + tr_y
            stz += ti[2] + trz
            _store_partner(partner_result, partner_slot[slot], fx, fy, fz, tj[0] - trx, tj[1] - tr_y, tj[2] - trz)
            touching += 1
            ratio = overlap if same else overlap / (2.0 * min(ri, rj))
            if ratio > max_overlap:
                max_overlap = ratio
        _store_row(owner_sum, i, sfx, sfy, sfz, stx, sty, stz)
        row_max_overlap[i] = max_overlap / (2.0 * ri) if same else max_overlap
        row_contacts[i] = touching


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def sphere_pair_forces(position, velocity, angular_velocity, radius, mass, inertia, row_start, neighbours, history,
                       partner_slot, owner_sum, partner_result, row_max_overlap, row_contacts, box_length, periodic,
                       params, uniform):
    """``pair_forces`` for spheres: the same contacts and results (to round-off: tested against it),
    with the contact point on the line of centres, so no segment geometry and the lever arms
    ``-l_i n`` and ``l_j n`` folded into the velocity and the torques. 15-25 % faster on the settled
    32,500-sphere bed (docs/benchmarks.md)."""
    n = position.shape[0]
    law = kernel_constants(params)
    same = uniform[0] >= 0.0
    lx, ly, lz = box_length[0], box_length[1], box_length[2]
    qx, qy, qz = periodic[0], periodic[1], periodic[2]
    for i in prange(n):
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
                _forget(history, slot, partner_slot, partner_result)
                continue
            dist = math.sqrt(dist2)
            if dist > 1e-14 * radius_sum:
                inv = 1.0 / dist
                nx, ny, nz = dx * inv, dy * inv, dz * inv
            else:  # coincident centres: any direction is a normal
                nx, ny, nz = 0.0, 0.0, 1.0
            overlap = radius_sum - dist
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
            if same:
                eta_n, r_eff, inertia_eff = uniform[0], uniform[1], uniform[2]
            else:
                eta_n = normal_damping(params[ZETA_N], mass[i] * mass[j] / (mass[i] + mass[j]), law[0])
                r_eff = ri * rj / radius_sum
                inertia_eff = inertia[i, 0] * inertia[j, 0] / (inertia[i, 0] + inertia[j, 0])
            fx, fy, fz, trx, tr_y, trz, f_n = contact_force(
                history, slot, overlap, nx, ny, nz, vx, vy, vz,
                wi0 - wj0, wi1 - wj1, wi2 - wj2, eta_n, r_eff, inertia_eff, law)
            # torques: (-l_i n) x F on i, (l_j n) x (-F) on j, both -l (n x F)
            cx, cy, cz = _cross(nx, ny, nz, fx, fy, fz)
            sfx += fx
            sfy += fy
            sfz += fz
            stx += trx - li * cx
            sty += tr_y - li * cy
            stz += trz - li * cz
            _store_partner(partner_result, partner_slot[slot], fx, fy, fz, -lj * cx - trx, -lj * cy - tr_y,
                           -lj * cz - trz)
            touching += 1
            ratio = overlap if same else overlap / (2.0 * min(ri, rj))
            if ratio > max_overlap:
                max_overlap = ratio
        _store_row(owner_sum, i, sfx, sfy, sfz, stx, sty, stz)
        row_max_overlap[i] = max_overlap / (2.0 * ri) if same else max_overlap
        row_contacts[i] = touching


@njit(cache=True, parallel=True, fastmath=FASTMATH)
def gather_forces(position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                  owner_sum, partner_result, partner_start, wall_active, box_lo, box_hi, wall_history,
                  wall_mask, params,
                  contact_force_out, contact_torque_out, row_max_overlap, row_wall_contacts):
    """Per particle: owner sum plus its partner block (``partner_result[partner_start[i]:
    partner_start[i+1]]``, contiguous) plus wall contacts (faces flagged in ``wall_active``:
    x-, x+, y-, y+, z-, z+). ``wall_history`` is flat ``(N * 12, 4)``: slot ``(i*6 + face)*2 + end``;
    bit ``face*2 + end`` of ``wall_mask[i]`` is set while that slot holds a contact, so particles
    away from walls cost one integer read instead of twelve history rows."""
    n = position.shape[0]
    law = kernel_constants(params)
    ax_lo, ax_hi, ay_lo, ay_hi, az_lo, az_hi = (wall_active[0], wall_active[1], wall_active[2], wall_active[3],
                                                wall_active[4], wall_active[5])
    xlo, ylo, zlo = box_lo[0], box_lo[1], box_lo[2]
    xhi, yhi, zhi = box_hi[0], box_hi[1], box_hi[2]
    for i in prange(n):
        fx = owner_sum[i, 0]
        fy = owner_sum[i, 1]
        fz = owner_sum[i, 2]
        tx = owner_sum[i, 3]
        ty = owner_sum[i, 4]
        tz = owner_sum[i, 5]
        for slot in range(partner_start[i], partner_start[i + 1]):
            fx += partner_result[slot, 0]
            fy += partner_result[slot, 1]
            fz += partner_result[slot, 2]
            tx += partner_result[slot, 3]
            ty += partner_result[slot, 4]
            tz += partner_result[slot, 5]
        # walls
        wall_contacts = 0
        max_overlap = row_max_overlap[i]
        mask = wall_mask[i]
        h = half_length[i]
        r = radius[i]
        reach = r + h
        x, y, z = position[i, 0], position[i, 1], position[i, 2]
        if mask == 0 and not ((ax_lo and x - xlo < reach) or (ax_hi and xhi - x < reach)
                              or (ay_lo and y - ylo < reach) or (ay_hi and yhi - y < reach)
                              or (az_lo and z - zlo < reach) or (az_hi and zhi - z < reach)):
            # out of every wall's reach with no wall history to clear: most particles (the face
            # loop below cost twice the partner sums for them)
            contact_force_out[i, 0] = fx
            contact_force_out[i, 1] = fy
            contact_force_out[i, 2] = fz
            contact_torque_out[i, 0] = tx
            contact_torque_out[i, 1] = ty
            contact_torque_out[i, 2] = tz
            row_wall_contacts[i] = 0
            continue
        n_ends = 2 if h > 0.0 else 1
        imin = min(inertia[i, 0], inertia[i, 1])
        for face in range(6):
            if not wall_active[face]:
                continue
            d = face // 2
            upper = face % 2 == 1
            gap = box_hi[d] - position[i, d] if upper else position[i, d] - box_lo[d]
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
                dist = box_hi[d] - e_d if upper else e_d - box_lo[d]
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
                c = _cross(angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2], lx, ly, lz)
                vx = velocity[i, 0] + c[0]
                vy = velocity[i, 1] + c[1]
                vz = velocity[i, 2] + c[2]
                wfx, wfy, wfz, trx, tr_y, trz, f_n = contact_force(
                    wall_history, slot, overlap, nx, ny, nz, vx, vy, vz,
                    angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2],
                    normal_damping(params[ZETA_WALL], mass[i], law[0]), r, imin, law)
                fx += wfx
                fy += wfy
                fz += wfz
                t = _cross(lx, ly, lz, wfx, wfy, wfz)
                tx += t[0] + trx
                ty += t[1] + tr_y
                tz += t[2] + trz
                wall_contacts += 1
                if overlap / (2.0 * r) > max_overlap:
                    max_overlap = overlap / (2.0 * r)
        contact_force_out[i, 0] = fx
        contact_force_out[i, 1] = fy
        contact_force_out[i, 2] = fz
        contact_torque_out[i, 0] = tx
        contact_torque_out[i, 1] = ty
        contact_torque_out[i, 2] = tz
        row_max_overlap[i] = max_overlap
        row_wall_contacts[i] = wall_contacts
        wall_mask[i] = mask
