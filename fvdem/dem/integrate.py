"""Time integration: velocity Verlet (kick-drift-kick) for translation and rotation.

Rotation is integrated as the world-frame angular momentum ``L`` (``dL/dt = T`` exactly) with the
orientation as a unit quaternion. The angular velocity follows from the body-frame diagonal
inertia, ``w = R I_body^-1 R^T L``; for an axisymmetric body with world axis ``a`` this is

    w = L / I_t + (1/I_a - 1/I_t) (L . a) a          (I_t transverse, I_a axial inertia)

which is Euler's equations in the body frame without forming R. The drift rotates the quaternion
by ``exp(w_mid dt)`` with ``w_mid`` evaluated at the half-rotated axis (second order); for a
torque-free axisymmetric body the axis then precesses about the fixed ``L`` at exactly
``|L| / I_t``, so angular momentum and kinetic energy are conserved to round-off.

Spheres (``half_length == 0``) skip the orientation update altogether.
"""
from __future__ import annotations

import math

from numba import njit, prange


@njit(cache=True, inline="always")
def _omega(lx, ly, lz, ax, ay, az, i_t, i_a):
    la = (lx * ax + ly * ay + lz * az) * (1.0 / i_a - 1.0 / i_t)
    return lx / i_t + la * ax, ly / i_t + la * ay, lz / i_t + la * az


@njit(cache=True, inline="always")
def _rotate(vx, vy, vz, wx, wy, wz, tau):
    """Rotate v by the rotation vector w * tau (Rodrigues)."""
    wn = math.sqrt(wx * wx + wy * wy + wz * wz)
    theta = wn * tau
    if theta == 0.0:
        return vx, vy, vz
    kx, ky, kz = wx / wn, wy / wn, wz / wn
    c = math.cos(theta)
    s = math.sin(theta)
    kv = kx * vx + ky * vy + kz * vz
    cx, cy, cz = ky * vz - kz * vy, kz * vx - kx * vz, kx * vy - ky * vx
    return (vx * c + cx * s + kx * kv * (1.0 - c),
            vy * c + cy * s + ky * kv * (1.0 - c),
            vz * c + cz * s + kz * kv * (1.0 - c))


@njit(cache=True, inline="always")
def _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
          external_torque, gravity, half_dt):
    inv_m = half_dt / mass[i]
    for c in range(3):
        velocity[i, c] += (contact_force[i, c] + external_force[i, c]) * inv_m + gravity[c] * half_dt
        angular_momentum[i, c] += (contact_torque[i, c] + external_torque[i, c]) * half_dt


@njit(cache=True, parallel=True)
def kick_drift(position, velocity, angular_momentum, angular_velocity, quaternion, axis, half_length,
               mass, inertia, contact_force, contact_torque, external_force, external_torque, gravity, dt,
               reference_position, reference_axis, displacement, track_orientation,
               predicted_velocity, predicted_angular_velocity):
    """Half kick, full drift; writes each particle's end-point displacement bound since the last
    neighbour-list build into ``displacement`` [m].

    Also writes the velocities predicted at the end of the step with the previous forces,
    ``v + dt/2 a_old`` (and likewise for rotation), which the contact law uses for damping and
    tangential sliding. Evaluating the dashpot at the half-step velocity instead (as LIGGGHTS does)
    lags it by dt/2 and biases the restitution by O(dt/t_c): -7 % at dt = t_c/17 for e = 0.43;
    the prediction makes the error second order.
    """
    n = position.shape[0]
    half_dt = 0.5 * dt
    for i in prange(n):
        _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
              external_torque, gravity, half_dt)
        inv_m = half_dt / mass[i]
        for c in range(3):
            predicted_velocity[i, c] = (velocity[i, c] + (contact_force[i, c] + external_force[i, c]) * inv_m
                                        + gravity[c] * half_dt)
        position[i, 0] += velocity[i, 0] * dt
        position[i, 1] += velocity[i, 1] * dt
        position[i, 2] += velocity[i, 2] * dt
        i_t = inertia[i, 0]
        i_a = inertia[i, 1]
        lx, ly, lz = angular_momentum[i, 0], angular_momentum[i, 1], angular_momentum[i, 2]
        px = lx + (contact_torque[i, 0] + external_torque[i, 0]) * half_dt
        py = ly + (contact_torque[i, 1] + external_torque[i, 1]) * half_dt
        pz = lz + (contact_torque[i, 2] + external_torque[i, 2]) * half_dt
        dx = position[i, 0] - reference_position[i, 0]
        dy = position[i, 1] - reference_position[i, 1]
        dz = position[i, 2] - reference_position[i, 2]
        moved = math.sqrt(dx * dx + dy * dy + dz * dz)
        if track_orientation and half_length[i] > 0.0:
            ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
            w0 = _omega(lx, ly, lz, ax, ay, az, i_t, i_a)
            mx, my, mz = _rotate(ax, ay, az, w0[0], w0[1], w0[2], half_dt)
            wx, wy, wz = _omega(lx, ly, lz, mx, my, mz, i_t, i_a)
            wn = math.sqrt(wx * wx + wy * wy + wz * wz)
            if wn > 0.0:
                half_angle = 0.5 * wn * dt
                sh = math.sin(half_angle) / wn
                rw, rx, ry, rz = math.cos(half_angle), wx * sh, wy * sh, wz * sh
                qw, qx, qy, qz = quaternion[i, 0], quaternion[i, 1], quaternion[i, 2], quaternion[i, 3]
                nw = rw * qw - rx * qx - ry * qy - rz * qz
                nx = rw * qx + rx * qw + ry * qz - rz * qy
                ny = rw * qy - rx * qz + ry * qw + rz * qx
                nz = rw * qz + rx * qy - ry * qx + rz * qw
                norm = 1.0 / math.sqrt(nw * nw + nx * nx + ny * ny + nz * nz)
                nw *= norm
                nx *= norm
                ny *= norm
                nz *= norm
                quaternion[i, 0], quaternion[i, 1], quaternion[i, 2], quaternion[i, 3] = nw, nx, ny, nz
                axis[i, 0] = 2.0 * (nx * nz + nw * ny)
                axis[i, 1] = 2.0 * (ny * nz - nw * nx)
                axis[i, 2] = 1.0 - 2.0 * (nx * nx + ny * ny)
            w = _omega(lx, ly, lz, axis[i, 0], axis[i, 1], axis[i, 2], i_t, i_a)
            angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2] = w
            w = _omega(px, py, pz, axis[i, 0], axis[i, 1], axis[i, 2], i_t, i_a)
            predicted_angular_velocity[i, 0] = w[0]
            predicted_angular_velocity[i, 1] = w[1]
            predicted_angular_velocity[i, 2] = w[2]
            ex = axis[i, 0] - reference_axis[i, 0]
            ey = axis[i, 1] - reference_axis[i, 1]
            ez = axis[i, 2] - reference_axis[i, 2]
            moved += half_length[i] * math.sqrt(ex * ex + ey * ey + ez * ez)
        else:
            angular_velocity[i, 0] = lx / i_t
            angular_velocity[i, 1] = ly / i_t
            angular_velocity[i, 2] = lz / i_t
            predicted_angular_velocity[i, 0] = px / i_t
            predicted_angular_velocity[i, 1] = py / i_t
            predicted_angular_velocity[i, 2] = pz / i_t
        displacement[i] = moved


@njit(cache=True, parallel=True)
def kick(velocity, angular_momentum, angular_velocity, axis, half_length, mass, inertia, contact_force,
         contact_torque, external_force, external_torque, gravity, dt, track_orientation):
    """Second half kick; refreshes the angular velocity from the new angular momentum."""
    n = velocity.shape[0]
    half_dt = 0.5 * dt
    for i in prange(n):
        _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
              external_torque, gravity, half_dt)
        lx, ly, lz = angular_momentum[i, 0], angular_momentum[i, 1], angular_momentum[i, 2]
        if track_orientation and half_length[i] > 0.0:
            w = _omega(lx, ly, lz, axis[i, 0], axis[i, 1], axis[i, 2], inertia[i, 0], inertia[i, 1])
            angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2] = w
        else:
            angular_velocity[i, 0] = lx / inertia[i, 0]
            angular_velocity[i, 1] = ly / inertia[i, 0]
            angular_velocity[i, 2] = lz / inertia[i, 0]
