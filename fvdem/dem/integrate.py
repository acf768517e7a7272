"""Time integration: velocity Verlet (kick-drift-kick) for translation and rotation.

Rotation is integrated as the world-frame angular momentum ``L`` (``dL/dt = T`` exactly) with the
orientation as the world-frame symmetry axis ``a``. The angular velocity follows from the body-frame
diagonal inertia, ``w = R I_body^-1 R^T L``; for an axisymmetric body this is

    w = L / I_t + (1/I_a - 1/I_t) (L . a) a          (I_t transverse, I_a axial inertia)

which is Euler's equations in the body frame without forming R. ``(L, a)`` is the whole rotational
state of an axisymmetric body: the angle of spin about its own axis enters neither ``w`` nor any force,
so it is not tracked (``ParticleArrays.quaternion`` derives an orientation from the axis). The drift
applies the exact torque-free motion of a symmetric top for the (half-kicked) L: its spin about the body
axis leaves the axis where it is, and its precession turns the axis about L by ``|L| dt / I_t``. Torques
enter through the symmetric kicks of L (a second-order splitting); without torque, angular momentum is
kept exactly and kinetic energy to round-off.

Spheres (``half_length == 0``) skip the orientation update altogether.

Hydrodynamic drag, when the coupling bridge sets ``implicit_drag``, enters each half kick
implicitly (backward Euler on ``c (u - v)``): unconditionally stable whatever the ratio of the time
step to the particle response time ``m / c``.
"""
from __future__ import annotations

import math

from numba import njit, prange

from .geometry import cross


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
def _rotate(i, lx, ly, lz, axis, angular_velocity, reference_axis, half_length, inertia, half_dt):
    """The drift's rotation of rod i (angular momentum ``L`` held), its angular velocity refreshed;
    returns how far its upper end point moved by turning since the last list build, ``h (a - a_ref)``.

    The axis precesses about L by ``|L| dt / I_t``: turned by the unit quaternion ``(c, v)``,
    ``c = cos x``, ``v = L k sin x / x`` of the half angle ``x = |L| k``, ``k = dt / (2 I_t)`` (the half
    angle enters as x^2, ``half_angle_terms``: no |L| needed), as ``a + 2 c (v x a) + 2 v x (v x a)``; then
    one Newton step ``a (3 - |a|^2) / 2`` holds ``|a| = 1`` to round-off. A quaternion of the whole
    orientation (precession and spin, renormalised, the axis read back from it) made the fluidized rods'
    ``kick_drift`` cost 57-58 ns per rod against 40-41 now (docs/benchmarks.md)."""
    inv_t = 1.0 / inertia[i, 0]
    inv_a = 1.0 / inertia[i, 1]
    k = half_dt * inv_t
    c, sinc = half_angle_terms((lx * lx + ly * ly + lz * lz) * (k * k))
    ks = k * sinc
    vx, vy, vz = lx * ks, ly * ks, lz * ks
    ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
    cx, cy, cz = cross(vx, vy, vz, ax, ay, az)
    tx, ty, tz = 2.0 * cx, 2.0 * cy, 2.0 * cz  # 2 v x a
    ax += c * tx + (vy * tz - vz * ty)
    ay += c * ty + (vz * tx - vx * tz)
    az += c * tz + (vx * ty - vy * tx)
    g = 1.5 - 0.5 * (ax * ax + ay * ay + az * az)
    ax, ay, az = ax * g, ay * g, az * g
    axis[i, 0], axis[i, 1], axis[i, 2] = ax, ay, az
    w = _omega(lx, ly, lz, ax, ay, az, inv_t, inv_a)
    angular_velocity[i, 0], angular_velocity[i, 1], angular_velocity[i, 2] = w
    h = half_length[i]
    return h * (ax - reference_axis[i, 0]), h * (ay - reference_axis[i, 1]), h * (az - reference_axis[i, 2])


@njit(cache=True, inline="always")
def _kick_and_move(i, kicks, position, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
                   external_torque, gravity, dt, half_dt, drag_coefficient, fluid_velocity, drag_impulse, implicit_drag,
                   reference_position):
    """Particle i's half kick(s) and translation; returns how far its centre moved since the last list build
    (the vector)."""
    for _ in range(kicks):
        _kick(i, velocity, angular_momentum, mass, contact_force, contact_torque, external_force,
              external_torque, gravity, half_dt, drag_coefficient, fluid_velocity, drag_impulse, implicit_drag)
    position[i, 0] += velocity[i, 0] * dt
    position[i, 1] += velocity[i, 1] * dt
    position[i, 2] += velocity[i, 2] * dt
    return (position[i, 0] - reference_position[i, 0], position[i, 1] - reference_position[i, 1],
            position[i, 2] - reference_position[i, 2])


@njit(cache=True, parallel=True)
def kick_drift(position, velocity, angular_momentum, angular_velocity, axis, half_length,
               mass, inertia, contact_force, contact_torque, external_force, external_torque, gravity, dt,
               reference_position, reference_axis, displacement, track_orientation, drag_coefficient,
               fluid_velocity, drag_impulse, implicit_drag, kicks=1):
    """Half kick, full drift; writes how far each particle's axis segment has moved at most since the last
    neighbour-list build into ``displacement`` [m]: a point ``s`` of the segment moved by ``d + s e`` (``d``
    the centre's displacement, ``e`` the axis's change), largest at an end point (it is convex in s), so
    the bound is ``max |d +- h e| = sqrt(|d|^2 + h^2 |e|^2 + 2 h |d . e|)``; ``|d| + h |e|``, the bound used
    before, is up to 41 % larger (d and e at right angles), and rebuilt the rods' list earlier than needed.
    The contact law then sees the half-kicked
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
            dx, dy, dz = _kick_and_move(i, kicks, position, velocity, angular_momentum, mass, contact_force,
                                        contact_torque, external_force, external_torque, gravity, dt, half_dt,
                                        drag_coefficient, fluid_velocity, drag_impulse, implicit_drag,
                                        reference_position)
            lx, ly, lz = angular_momentum[i, 0], angular_momentum[i, 1], angular_momentum[i, 2]
            moved2 = dx * dx + dy * dy + dz * dz
            if half_length[i] > 0.0:
                ex, ey, ez = _rotate(i, lx, ly, lz, axis, angular_velocity, reference_axis, half_length, inertia,
                                     half_dt)
                moved2 += ex * ex + ey * ey + ez * ez + 2.0 * abs(dx * ex + dy * ey + dz * ez)
            else:
                angular_velocity[i, 0] = lx / inertia[i, 0]
                angular_velocity[i, 1] = ly / inertia[i, 0]
                angular_velocity[i, 2] = lz / inertia[i, 0]
            displacement[i] = math.sqrt(moved2)
    else:  # spheres: the transverse inertia
        for i in prange(n):
            dx, dy, dz = _kick_and_move(i, kicks, position, velocity, angular_momentum, mass, contact_force,
                                        contact_torque, external_force, external_torque, gravity, dt, half_dt,
                                        drag_coefficient, fluid_velocity, drag_impulse, implicit_drag,
                                        reference_position)
            i_t = inertia[i, 0]
            angular_velocity[i, 0] = angular_momentum[i, 0] / i_t
            angular_velocity[i, 1] = angular_momentum[i, 1] / i_t
            angular_velocity[i, 2] = angular_momentum[i, 2] / i_t
            displacement[i] = math.sqrt(dx * dx + dy * dy + dz * dz)


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
