"""Contact force kernels: per-contact results first, then one race-free reduction per particle.

``pair_forces`` evaluates every listed pair once (parallel over owner rows) and stores the force on
the owner and the torques on owner and partner in the pair's slot. ``gather_forces`` then sums, for
each particle, its own slots and (negated force, partner torque) the slots where it is partner,
and adds its wall contacts. Newton's third law holds pair by pair by construction.

Walls are the six faces of the axis-aligned box that are not periodic. A spherocylinder touches a
wall at each end point that is within its radius of the wall (two contacts for a rod lying flat,
each with its own tangential history); a sphere has one end point.
"""
from __future__ import annotations

import math

from numba import njit, prange

from .contact_law import contact_force
from .geometry import minimum_image, segment_parameters


@njit(cache=True, inline="always")
def _cross(ax, ay, az, bx, by, bz):
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, parallel=True)
def pair_forces(position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                neighbours, counts, history, pair_force, pair_torque_owner, pair_torque_partner,
                row_max_overlap, row_contacts, box_length, periodic, params):
    """Contact force and torques of every listed pair; fills the per-slot result arrays.

    ``history`` (4 columns, see ``contact_law``), ``pair_force`` etc. (3 columns) are flat ``(N * width, .)`` arrays indexed by slot
    ``i * width + k``. ``row_max_overlap[i]`` gets the largest overlap/diameter of row i and
    ``row_contacts[i]`` the number of touching pairs in row i.
    """
    n = position.shape[0]
    width = neighbours.shape[1]
    for i in prange(n):
        max_overlap = 0.0
        touching = 0
        ai0, ai1, ai2 = axis[i, 0], axis[i, 1], axis[i, 2]
        for k in range(counts[i]):
            j = neighbours[i, k]
            slot = i * width + k
            rx = minimum_image(position[i, 0] - position[j, 0], box_length[0], periodic[0])
            ry = minimum_image(position[i, 1] - position[j, 1], box_length[1], periodic[1])
            rz = minimum_image(position[i, 2] - position[j, 2], box_length[2], periodic[2])
            s, t = segment_parameters(rx, ry, rz, ai0, ai1, ai2, half_length[i],
                                      axis[j, 0], axis[j, 1], axis[j, 2], half_length[j])
            dx = rx + s * ai0 - t * axis[j, 0]
            dy = ry + s * ai1 - t * axis[j, 1]
            dz = rz + s * ai2 - t * axis[j, 2]
            dist2 = dx * dx + dy * dy + dz * dz
            radius_sum = radius[i] + radius[j]
            if dist2 >= radius_sum * radius_sum:
                for c in range(4):
                    history[slot, c] = 0.0
                for c in range(3):
                    pair_force[slot, c] = 0.0
                    pair_torque_owner[slot, c] = 0.0
                    pair_torque_partner[slot, c] = 0.0
                continue
            dist = math.sqrt(dist2)
            if dist > 1e-14 * radius_sum:
                nx, ny, nz = dx / dist, dy / dist, dz / dist
            else:  # coincident axes: any direction is a normal
                nx, ny, nz = 0.0, 0.0, 1.0
            overlap = radius_sum - dist
            # lever arms from each centre to the contact point (middle of the overlap)
            li = radius[i] - 0.5 * overlap
            lj = radius[j] - 0.5 * overlap
            lix, liy, liz = s * ai0 - li * nx, s * ai1 - li * ny, s * ai2 - li * nz
            ljx, ljy, ljz = t * axis[j, 0] + lj * nx, t * axis[j, 1] + lj * ny, t * axis[j, 2] + lj * nz
            wi0, wi1, wi2 = angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2]
            wj0, wj1, wj2 = angular_velocity[j, 0], angular_velocity[j, 1], angular_velocity[j, 2]
            ci = _cross(wi0, wi1, wi2, lix, liy, liz)
            cj = _cross(wj0, wj1, wj2, ljx, ljy, ljz)
            vx = velocity[i, 0] + ci[0] - velocity[j, 0] - cj[0]
            vy = velocity[i, 1] + ci[1] - velocity[j, 1] - cj[1]
            vz = velocity[i, 2] + ci[2] - velocity[j, 2] - cj[2]
            reduced_mass = mass[i] * mass[j] / (mass[i] + mass[j])
            r_eff = radius[i] * radius[j] / radius_sum
            ii = min(inertia[i, 0], inertia[i, 1])
            ij = min(inertia[j, 0], inertia[j, 1])
            inertia_eff = ii * ij / (ii + ij)
            fx, fy, fz, trx, tr_y, trz, f_n = contact_force(
                history, slot, overlap, nx, ny, nz, vx, vy, vz,
                wi0 - wj0, wi1 - wj1, wi2 - wj2, reduced_mass, r_eff, inertia_eff, params)
            pair_force[slot, 0] = fx
            pair_force[slot, 1] = fy
            pair_force[slot, 2] = fz
            ti = _cross(lix, liy, liz, fx, fy, fz)
            tj = _cross(ljx, ljy, ljz, -fx, -fy, -fz)
            pair_torque_owner[slot, 0] = ti[0] + trx
            pair_torque_owner[slot, 1] = ti[1] + tr_y
            pair_torque_owner[slot, 2] = ti[2] + trz
            pair_torque_partner[slot, 0] = tj[0] - trx
            pair_torque_partner[slot, 1] = tj[1] - tr_y
            pair_torque_partner[slot, 2] = tj[2] - trz
            touching += 1
            ratio = overlap / (2.0 * min(radius[i], radius[j]))
            if ratio > max_overlap:
                max_overlap = ratio
        row_max_overlap[i] = max_overlap
        row_contacts[i] = touching


@njit(cache=True, parallel=True)
def gather_forces(position, velocity, angular_velocity, axis, radius, half_length, mass, inertia,
                  counts, width, reverse, reverse_counts, pair_force, pair_torque_owner,
                  pair_torque_partner, wall_active, box_lo, box_hi, wall_history, params,
                  contact_force_out, contact_torque_out, row_max_overlap, row_wall_contacts):
    """Sum pair results per particle and add wall contacts (faces flagged in ``wall_active``:
    x-, x+, y-, y+, z-, z+). ``wall_history`` is flat ``(N * 12, 4)``: slot ``(i*6 + face)*2 + end``."""
    n = position.shape[0]
    for i in prange(n):
        fx = 0.0
        fy = 0.0
        fz = 0.0
        tx = 0.0
        ty = 0.0
        tz = 0.0
        base = i * width
        for k in range(counts[i]):
            slot = base + k
            fx += pair_force[slot, 0]
            fy += pair_force[slot, 1]
            fz += pair_force[slot, 2]
            tx += pair_torque_owner[slot, 0]
            ty += pair_torque_owner[slot, 1]
            tz += pair_torque_owner[slot, 2]
        for m in range(reverse_counts[i]):
            slot = reverse[i, m]
            fx -= pair_force[slot, 0]
            fy -= pair_force[slot, 1]
            fz -= pair_force[slot, 2]
            tx += pair_torque_partner[slot, 0]
            ty += pair_torque_partner[slot, 1]
            tz += pair_torque_partner[slot, 2]
        # walls
        wall_contacts = 0
        max_overlap = row_max_overlap[i]
        h = half_length[i]
        r = radius[i]
        n_ends = 2 if h > 0.0 else 1
        imin = min(inertia[i, 0], inertia[i, 1])
        for face in range(6):
            if not wall_active[face]:
                continue
            d = face // 2
            upper = face % 2 == 1
            for end in range(n_ends):
                sign = -1.0 if end == 0 else 1.0
                ex = sign * h * axis[i, 0]
                ey = sign * h * axis[i, 1]
                ez = sign * h * axis[i, 2]
                e_d = position[i, d] + (ex if d == 0 else (ey if d == 1 else ez))
                dist = box_hi[d] - e_d if upper else e_d - box_lo[d]
                slot = (i * 6 + face) * 2 + end
                overlap = r - dist
                if overlap <= 0.0:
                    for c in range(4):
                        wall_history[slot, c] = 0.0
                    continue
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
                    mass[i], r, imin, params)
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
