"""Time integration: velocity Verlet (kick-drift-kick) for translation and rotation.

Rotation is integrated as the world-frame angular momentum ``L`` (``dL/dt = T`` exactly) with the
orientation as a unit quaternion. The angular velocity follows from the body-frame diagonal
inertia, ``w = R I_body^-1 R^T L``; for an axisymmetric body with world axis ``a`` this is

    w = L / I_t + (1/I_a - 1/I_t) (L . a) a          (I_t transverse, I_a axial inertia)

which is Euler's equations in the body frame without forming R. The drift applies the exact
torque-free motion of a symmetric top for the (half-kicked) L: a precession about L by
``|L| dt / I_t`` times a spin about the body axis by ``(L.a)(1/I_a - 1/I_t) dt``. Torques enter
through the symmetric kicks of L (a second-order splitting); without torque, angular momentum is
kept exactly and kinetic energy to round-off.

Spheres (``half_length == 0``) skip the orientation update altogether.

Hydrodynamic drag, when the coupling bridge sets ``implicit_drag``, enters each half kick
implicitly (backward Euler on ``c (u - v)``): unconditionally stable whatever the ratio of the time
step to the particle response time ``m / c``.
"""
from __future__ import annotations

import math

from numba import njit, prange


# below this half angle [rad] the rotations use the series of cos x and sin x / x to x^6: the first term
# left out, x^8 / 8!, is under 7e-19 there, below a rounding of 1 (a drift's half angle is |w| dt / 2:
# 2.5e-3 for 100 rad/s at the default 5e-5 s step, so the library's sin and cos are all but never called)
SMALL_ANGLE = 0.02


@njit(cache=True, inline="always")
def half_angle_terms(x2):
    """``(cos x, sin x / x)`` of a half angle x given as ``x2 = x^2`` [rad^2]: the Taylor series to x^6
    below ``SMALL_ANGLE`` (round-off-exact there: no square root, sine or cosine), the library above."""
    if x2 < SMALL_ANGLE * SMALL_ANGLE:
        return (1.0 + x2 * (-1.0 / 2.0 + x2 * (1.0 / 24.0 + x2 * (-1.0 / 720.0))),
                1.0 + x2 * (-1.0 / 6.0 + x2 * (1.0 / 120.0 + x2 * (-1.0 / 5040.0))))
    x = math.sqrt(x2)
    return math.cos(x), math.sin(x) / x


@njit(cache=True, inline="always")
def _omega(lx, ly, lz, ax, ay, az, inv_t, inv_a):
    """``w = L / I_t + (1/I_a - 1/I_t) (L . a) a`` from the inverse inertias."""
    la = (lx * ax + ly * ay + lz * az) * (inv_a - inv_t)
    return lx * inv_t + la * ax, ly * inv_t + la * ay, lz * inv_t + la * az


@njit(cache=True, inline="always")
def _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
          external_torque, gravity, half_dt, drag_coefficient, fluid_velocity, drag_impulse, implicit_drag):
    inv_m = half_dt / mass[i]
    if implicit_drag:
        # v' = (v + h/2 (F/m + g) + q u) / (1 + q), q = h/2 c/m: backward Euler in the drag, stable for
        # any h / tau_p; the drag impulse actually applied, h/2 c (u - v'), is accumulated
        q = drag_coefficient[i] * inv_m
        scale = 1.0 / (1.0 + q)
        for c in range(3):
            v = (velocity[i, c] + ((contact_force[i, c] + external_force[i, c]) * inv_m + gravity[c] * half_dt)
                 + q * fluid_velocity[i, c]) * scale
            drag_impulse[i, c] += mass[i] * q * (fluid_velocity[i, c] - v)
            velocity[i, c] = v
    else:
        for c in range(3):
            velocity[i, c] += (contact_force[i, c] + external_force[i, c]) * inv_m + gravity[c] * half_dt
    for c in range(3):
        angular_momentum[i, c] += (contact_torque[i, c] + external_torque[i, c]) * half_dt


@njit(cache=True, inline="always")
def _rotate(i, lx, ly, lz, quaternion, axis, angular_velocity, reference_axis, half_length, inertia, half_dt):
    """The drift's rotation of rod i (angular momentum ``L`` held), its angular velocity refreshed;
    returns how far its end points moved by turning since the last list build (``h |a - a_ref|``)."""
    # exact free rotation with L held over the drift: precession about L by |L| dt / I_t
    # (world frame, left factor), spin about the body axis by (L.a)(1/I_a - 1/I_t) dt
    # (body frame, right factor); L.a is invariant under the precession. Half angles x enter
    # as x^2 (``half_angle_terms``): the precession's quaternion is (cos x, L k sin x / x) with
    # k = dt / (2 I_t), no |L| needed.
    inv_t = 1.0 / inertia[i, 0]
    inv_a = 1.0 / inertia[i, 1]
    k = half_dt * inv_t
    c, sinc = half_angle_terms((lx * lx + ly * ly + lz * lz) * (k * k))
    rw, rx, ry, rz = c, lx * k * sinc, ly * k * sinc, lz * k * sinc
    qw, qx, qy, qz = quaternion[i, 0], quaternion[i, 1], quaternion[i, 2], quaternion[i, 3]
    qw, qx, qy, qz = (rw * qw - rx * qx - ry * qy - rz * qz, rw * qx + rx * qw + ry * qz - rz * qy,
                      rw * qy - rx * qz + ry * qw + rz * qx, rw * qz + rx * qy - ry * qx + rz * qw)
    half_spin = (lx * axis[i, 0] + ly * axis[i, 1] + lz * axis[i, 2]) * (inv_a - inv_t) * half_dt
    bw, sinc = half_angle_terms(half_spin * half_spin)
    bz = half_spin * sinc
    qw, qx, qy, qz = qw * bw - qz * bz, qx * bw + qy * bz, qy * bw - qx * bz, qz * bw + qw * bz
    norm = 1.0 / math.sqrt(qw * qw + qx * qx + qy * qy + qz * qz)
    qw, qx, qy, qz = qw * norm, qx * norm, qy * norm, qz * norm
    quaternion[i, 0], quaternion[i, 1], quaternion[i, 2], quaternion[i, 3] = qw, qx, qy, qz
    axis[i, 0] = 2.0 * (qx * qz + qw * qy)
    axis[i, 1] = 2.0 * (qy * qz - qw * qx)
    axis[i, 2] = 1.0 - 2.0 * (qx * qx + qy * qy)
    w = _omega(lx, ly, lz, axis[i, 0], axis[i, 1], axis[i, 2], inv_t, inv_a)
    angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2] = w
    ex = axis[i, 0] - reference_axis[i, 0]
    ey = axis[i, 1] - reference_axis[i, 1]
    ez = axis[i, 2] - reference_axis[i, 2]
    return half_length[i] * math.sqrt(ex * ex + ey * ey + ez * ez)


@njit(cache=True, inline="always")
def _kick_and_move(i, kicks, position, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
                   external_torque, gravity, dt, half_dt, drag_coefficient, fluid_velocity, drag_impulse, implicit_drag,
                   reference_position):
    """Particle i's half kick(s) and translation; returns how far its centre moved since the last list build."""
    for _ in range(kicks):
        _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
              external_torque, gravity, half_dt, drag_coefficient, fluid_velocity, drag_impulse, implicit_drag)
    position[i, 0] += velocity[i, 0] * dt
    position[i, 1] += velocity[i, 1] * dt
    position[i, 2] += velocity[i, 2] * dt
    dx = position[i, 0] - reference_position[i, 0]
    dy = position[i, 1] - reference_position[i, 1]
    dz = position[i, 2] - reference_position[i, 2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@njit(cache=True, parallel=True)
def kick_drift(position, velocity, angular_momentum, angular_velocity, quaternion, axis, half_length,
               mass, inertia, contact_force, contact_torque, external_force, external_torque, gravity, dt,
               reference_position, reference_axis, displacement, track_orientation, drag_coefficient,
               fluid_velocity, drag_impulse, implicit_drag, kicks=1):
    """Half kick, full drift; writes each particle's end-point displacement bound since the last
    neighbour-list build into ``displacement`` [m]. The contact law then sees the half-kicked
    velocities (the dashpot lags by dt/2: see ``contact_law`` for how the damping is calibrated).

    ``kicks = 2``: first the previous step's second half kick (``kick`` without its angular-velocity
    refresh, which the drift redoes), then this step's first, both with the forces of now: the two
    passes over the particles between two force evaluations become one, with the same arithmetic in
    the same order (bit-identical to ``kick`` then ``kick_drift``; ``DEMSystem.step`` uses it inside a
    run of steps).

    Extrapolating the velocities to the end of the step for the dashpot was tried and rejected: it
    makes binary restitution second order in dt but is anti-dissipative for the stiff modes of
    multi-contact packs (a pile of 60 rods kept 1e-8 J of jitter instead of decaying to 1e-11 J).
    """
    n = position.shape[0]
    half_dt = 0.5 * dt
    # two loops, not one with a branch on ``track_orientation`` inside: the rods' rotation made the loop
    # too large for the compiler to split it, and the spheres' drift cost half as much again
    if track_orientation:
        for i in prange(n):
            moved = _kick_and_move(i, kicks, position, velocity, angular_momentum, mass, contact_force, contact_torque,
                                   external_force, external_torque, gravity, dt, half_dt, drag_coefficient,
                                   fluid_velocity, drag_impulse, implicit_drag, reference_position)
            lx, ly, lz = angular_momentum[i, 0], angular_momentum[i, 1], angular_momentum[i, 2]
            if half_length[i] > 0.0:
                moved += _rotate(i, lx, ly, lz, quaternion, axis, angular_velocity, reference_axis, half_length,
                                 inertia, half_dt)
            else:
                angular_velocity[i, 0] = lx / inertia[i, 0]
                angular_velocity[i, 1] = ly / inertia[i, 0]
                angular_velocity[i, 2] = lz / inertia[i, 0]
            displacement[i] = moved
    else:  # spheres: the transverse inertia
        for i in prange(n):
            moved = _kick_and_move(i, kicks, position, velocity, angular_momentum, mass, contact_force, contact_torque,
                                   external_force, external_torque, gravity, dt, half_dt, drag_coefficient,
                                   fluid_velocity, drag_impulse, implicit_drag, reference_position)
            i_t = inertia[i, 0]
            angular_velocity[i, 0] = angular_momentum[i, 0] / i_t
            angular_velocity[i, 1] = angular_momentum[i, 1] / i_t
            angular_velocity[i, 2] = angular_momentum[i, 2] / i_t
            displacement[i] = moved


@njit(cache=True, parallel=True)
def kick(velocity, angular_momentum, angular_velocity, axis, half_length, mass, inertia, contact_force,
         contact_torque, external_force, external_torque, gravity, dt, track_orientation, drag_coefficient,
         fluid_velocity, drag_impulse, implicit_drag):
    """Second half kick; refreshes the angular velocity from the new angular momentum."""
    n = velocity.shape[0]
    half_dt = 0.5 * dt
    for i in prange(n):
        _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
              external_torque, gravity, half_dt, drag_coefficient, fluid_velocity, drag_impulse, implicit_drag)
        lx, ly, lz = angular_momentum[i, 0], angular_momentum[i, 1], angular_momentum[i, 2]
        if track_orientation and half_length[i] > 0.0:
            w = _omega(lx, ly, lz, axis[i, 0], axis[i, 1], axis[i, 2], 1.0 / inertia[i, 0], 1.0 / inertia[i, 1])
            angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2] = w
        else:
            angular_velocity[i, 0] = lx / inertia[i, 0]
            angular_velocity[i, 1] = ly / inertia[i, 0]
            angular_velocity[i, 2] = lz / inertia[i, 0]
