"""Contact force law: linear spring-dashpot normal force, tangential spring with history and
Coulomb limit, constant-directional-torque rolling friction (Mema et al., 2020, Eqs. 3-5, Table 5).

Each sub-model is a small pure function; ``contact_force`` evaluates them in one visible order:

1. normal:      ``F_n = max(k_n delta - eta_n v_n, 0) n``                   (Eq. 3, never attractive)
2. damping:     ``eta_n = 2 zeta sqrt(m* k_n)`` with ``zeta`` chosen so that a free binary collision
                rebounds with restitution ``e`` exactly. Because the force is clipped at zero, the
                collision ends when the force vanishes (before the overlap does) and the textbook
                ``zeta = -ln e / sqrt(pi^2 + ln^2 e)`` (valid for the unclipped model) would give a
                lower ``e``. The exact relation for the clipped model (Schwager & Poeschel 2007,
                Granular Matter 9:465) is ``e = exp(-beta t_e)``, ``t_e = (pi - 2 atan(beta/w))/w``,
                ``beta = zeta w0``, ``w = w0 sqrt(1 - zeta^2)``; ``damping_ratio`` inverts it.
                The integrator evaluates the dashpot at the half-kicked velocity, which lags by dt/2
                and lowers the rebound by O(w0 dt) (-2 % at the paper's dt = t_c/14 for e = 0.43).
                ``calibrated_damping_ratio`` therefore solves for the ``zeta`` at which the
                *discrete* binary collision (``discrete_restitution``, a replica of the kernels'
                integrator) rebounds with ``e``, separately for particle pairs (m* = m/2) and
                walls (m* = m). The continuous value is its limit as dt -> 0.
3. tangential:  ``delta_t = int v_t dt`` since first contact, rotated into the current tangent
                plane (length kept); ``F_t = -k_t delta_t - eta_t v_t``; if ``|F_t| > mu |F_n|``
                then ``F_t`` is scaled to ``mu |F_n|`` and ``delta_t`` truncated to
                ``-(F_t + eta_t v_t) / k_t`` (Eqs. 4-5)
4. rolling:     constant directional torque ``T_r = -mu_r R* |F_n| w_roll / |w_roll|``, ``w_roll`` the
                relative angular velocity projected on the tangent plane, ``R*`` the reduced radius.
                Mema et al. (2020) lists ``mu_r = 0.46`` without a model; this is the standard CDT model
                (Ai et al. 2011, model A). The torque is capped so that it cannot reverse the
                relative rolling within one step (``|T_r| <= I* |w_roll| / dt``): no chattering.

Onset: the dashpot force jumps to ``eta_n |v_n|`` at first touch, which falls somewhere inside a
time step; velocity Verlet attributes the first contact sample's impulse to the window
``t +- dt/2``, so the impulse before (or after) the true touch time is lost (or counted twice). This
gives every impact a restitution error of first order in dt whose sign depends on where the touch
falls in the step (+-6 % at dt = t_c/14). On the first step of a contact the damping force is
therefore scaled by ``1/2 + phi``, ``phi = delta / (|v_n| dt)`` (clamped to [0, 1]) the fraction of
the step spent in contact, which makes the onset impulse exact to first order. Each contact's
history carries a fourth column, 1 while the contact exists, to know its first step.

Clipping matters for friction: with an attractive dashpot tail, friction would keep acting on
``|F_n|`` while the net normal impulse shrinks, and the tangential impulse of a sliding impact would
exceed ``mu`` times the normal impulse (by 9 % for e = 0.43). Clipped, ``J_t <= mu J_n`` holds exactly.
"""
from __future__ import annotations

import math
from types import MappingProxyType

import numpy as np
from numba import njit

HISTORY_COLUMNS = 4  # tangential displacement (3) and the "contact exists" flag

# The contact law's default parameters, written once: the case's [contact] keys (fvdem.case.schema.ContactConfig,
# which adds their units, ranges and docs) and ``system.ContactModel`` take their defaults from here
# (tests/verification/test_contact_law.py holds the three equal). The stiffness is the speed-accuracy front's
# (docs/speed-accuracy.md); Mema et al. (2020) Table 5 has 2e4 N/m with a DEM step of 1e-5 s.
DEFAULTS = MappingProxyType({
    "normal_stiffness": 800.0,  # k_n [N/m]
    "restitution": 0.43,  # e
    "friction": 0.46,  # mu
    "rolling_friction": 0.46,  # mu_r
    "tangential_stiffness_ratio": 2.0 / 7.0,  # k_t / k_n
    "tangential_damping_ratio": 1.0,  # eta_t / eta_n
    "wall_friction": None,  # particle-wall mu (None: the particles' friction)
    "wall_rolling_friction": None,  # particle-wall mu_r (None: the particles' rolling_friction)
})

# The parameter vector kernels take (``contact_parameters``): its entries by name
K_N, K_T, ZETA_N, ETA_T_OVER_ETA_N, FRICTION, ROLLING_FRICTION, DT, ZETA_WALL, WALL_FRICTION, WALL_ROLLING_FRICTION = \
    range(10)
PARAMETER_COUNT = 10
# The constants a kernel reads once from that vector (``kernel_constants``, the ``law`` tuple of
# ``contact_force``): its entries by name
LAW_K_N, LAW_K_T, LAW_INV_K_T, LAW_ETA_T_RATIO, LAW_FRICTION, LAW_ROLLING_FRICTION, LAW_DT, LAW_INV_DT = range(8)


def _collision_in_units_of_w0(zeta: float):
    """``(w0 t_e, e)`` of a clipped linear spring-dashpot collision with damping ratio ``zeta``
    (time in units of 1/w0). Underdamped, critically and overdamped branches."""
    if zeta == 0.0:
        return math.pi, 1.0
    if zeta < 1.0:
        w = math.sqrt(1.0 - zeta * zeta)
        t_end = (math.pi - 2.0 * math.atan(zeta / w)) / w
        return t_end, math.exp(-zeta * t_end)
    if zeta == 1.0:
        zeta = 1.0 + 1e-9
    g = math.sqrt(zeta * zeta - 1.0)
    r1, r2 = -zeta + g, -zeta - g
    # force ~ xi + 2 zeta xi' vanishes where exp((r1 - r2) t) = (1 + 2 zeta r2) / (1 + 2 zeta r1)
    t_end = math.log((1.0 + 2.0 * zeta * r2) / (1.0 + 2.0 * zeta * r1)) / (r1 - r2)
    velocity = (r1 * math.exp(r1 * t_end) - r2 * math.exp(r2 * t_end)) / (2.0 * g)
    return t_end, -velocity


def restitution_of_damping(zeta: float) -> float:
    """Restitution of a free binary collision with the clipped linear dashpot of damping ratio ``zeta``."""
    return _collision_in_units_of_w0(zeta)[1]


def _solve_decreasing(function, target: float, upper: float, iterations: int) -> float:
    """Root of ``function(x) = target`` on x >= 0 for a decreasing ``function`` (bisection; the
    bracket ``[0, upper]`` is doubled until it holds the root)."""
    lo, hi = 0.0, upper
    doublings = 0
    while function(hi) > target:
        hi *= 2.0
        doublings += 1
        if doublings > 12:
            raise ValueError(f"no damping ratio up to {hi:.3g} reaches the target {target:.3g}")
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if function(mid) > target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def damping_ratio(restitution: float) -> float:
    """Damping ratio ``zeta`` of the clipped linear spring-dashpot that gives restitution
    ``e`` in (0, 1] (bisection on the exact, monotone ``restitution_of_damping``)."""
    if restitution >= 1.0:
        return 0.0
    return _solve_decreasing(restitution_of_damping, restitution, 1.0, 200)


def collision_time(normal_stiffness: float, reduced_mass: float, restitution: float) -> float:
    """Duration [s] of a free binary collision (until the clipped force vanishes)."""
    zeta = damping_ratio(restitution)
    return _collision_in_units_of_w0(zeta)[0] / math.sqrt(normal_stiffness / reduced_mass)


def discrete_restitution(zeta: float, step: float, phase: float) -> float:
    """Restitution of a free binary collision integrated as the kernels do (velocity Verlet, dashpot on
    the half-kicked velocity, force clipped at zero, onset-corrected first step), dimensionless:
    time in units of 1/w0, ``step = w0 dt``; the touch falls at ``phase`` (0-1) of a step."""
    w = 1.0  # approach speed, d(overlap)/dt
    overlap = -step * (1.0 + phase)
    force = 0.0
    touching = False
    for _ in range(100_000):
        w_half = w - 0.5 * step * force
        overlap += step * w_half
        if overlap > 0.0:
            onset = 1.0
            if not touching:
                touching = True
                if w_half > 0.0:
                    onset = 0.5 + min(overlap / (w_half * step), 1.0)
            force = max(overlap + 2.0 * zeta * w_half * onset, 0.0)
        else:
            force = 0.0
            if touching:
                return -(w_half - 0.5 * step * force)
        w = w_half - 0.5 * step * force
    raise RuntimeError("collision did not end")


def calibrated_damping_ratio(restitution: float, step: float, phases: int = 8) -> float:
    """Damping ratio for which the discrete binary collision at ``step = w0 dt`` rebounds with
    ``restitution`` on average over touch phases (bisection, monotone in zeta)."""
    if restitution >= 1.0:
        return 0.0
    if step < 1e-3:  # over 3,000 steps per collision: the continuous-time ratio is exact to ~1e-4
        return damping_ratio(restitution)
    grid = [(k + 0.5) / phases for k in range(phases)]

    def mean_e(zeta):
        return sum(discrete_restitution(zeta, step, ph) for ph in grid) / phases

    try:
        return _solve_decreasing(mean_e, restitution, 2.0 * damping_ratio(restitution) + 0.5, 60)
    except ValueError:
        raise ValueError(f"restitution {restitution:g} cannot be reached with {math.pi / step:.3g} steps per "
                         "half oscillation of the contact spring: the DEM time step is too large (use at "
                         "most 1/10 of the collision time)") from None


def contact_parameters(normal_stiffness, tangential_stiffness, restitution, tangential_damping_factor,
                       friction, rolling_friction, dt, mass, wall_friction=None, wall_rolling_friction=None) -> np.ndarray:
    """Pack the contact law's parameters into the float vector that kernels take. The damping
    ratios are calibrated for particles of ``mass`` [kg] at time step ``dt`` [s]. ``wall_friction`` and
    ``wall_rolling_friction``: the particle-wall coefficients (None: the particle-particle ones)."""
    p = np.zeros(PARAMETER_COUNT)
    p[K_N] = normal_stiffness
    p[K_T] = tangential_stiffness
    p[ZETA_N] = calibrated_damping_ratio(restitution, dt * math.sqrt(normal_stiffness / (0.5 * mass)))
    p[ZETA_WALL] = calibrated_damping_ratio(restitution, dt * math.sqrt(normal_stiffness / mass))
    p[ETA_T_OVER_ETA_N] = tangential_damping_factor
    p[FRICTION] = friction
    p[ROLLING_FRICTION] = rolling_friction
    p[DT] = dt
    p[WALL_FRICTION] = friction if wall_friction is None else wall_friction
    p[WALL_ROLLING_FRICTION] = rolling_friction if wall_rolling_friction is None else wall_rolling_friction
    return p


@njit(cache=True, inline="always")
def normal_force(delta, v_n, k_n, eta_n):
    """Normal force magnitude [N] along n, pushing the particle away; clipped at zero (no attraction)."""
    return max(k_n * delta - eta_n * v_n, 0.0)


@njit(cache=True, inline="always")
def normal_damping(zeta, reduced_mass, k_n):
    """Dashpot coefficient ``eta_n`` [kg/s] from damping ratio and reduced mass [kg]."""
    return 2.0 * zeta * math.sqrt(reduced_mass * k_n)


@njit(cache=True, inline="always")
def kernel_constants(params):
    """The parameter vector as scalars, read once before a kernel's loops rather than once per contact
    (numba cannot keep an array's values in registers across stores to other arrays, which might
    alias it): ``(k_n, k_t, 1/k_t, eta_t/eta_n, mu, mu_r, dt, 1/dt)``, in the order of the ``LAW_*`` indices."""
    return (params[K_N], params[K_T], 1.0 / params[K_T], params[ETA_T_OVER_ETA_N], params[FRICTION],
            params[ROLLING_FRICTION], params[DT], 1.0 / params[DT])


@njit(cache=True, inline="always")
def wall_constants(law, params):
    """The particle-wall law's constants: the pair constants ``law`` (``kernel_constants``) with the walls'
    sliding and rolling friction of ``params``."""
    return (law[LAW_K_N], law[LAW_K_T], law[LAW_INV_K_T], law[LAW_ETA_T_RATIO], params[WALL_FRICTION],
            params[WALL_ROLLING_FRICTION], law[LAW_DT], law[LAW_INV_DT])


@njit(cache=True, inline="always")
def tangential_force(history, row, nx, ny, nz, vtx, vty, vtz, f_n, k_t, inv_k_t, eta_t, mu, dt):
    """Tangential spring-dashpot with Coulomb limit; updates ``history[row, :3]`` (the tangential
    displacement, m) in place and returns the force (3 floats) [N]. ``inv_k_t = 1 / k_t``."""
    hx = history[row, 0]
    hy = history[row, 1]
    hz = history[row, 2]
    # rotate the stored displacement into the current tangent plane, keeping its length
    h_len2 = hx * hx + hy * hy + hz * hz
    if h_len2 > 0.0:
        hn = hx * nx + hy * ny + hz * nz
        hx -= hn * nx
        hy -= hn * ny
        hz -= hn * nz
        new_len2 = hx * hx + hy * hy + hz * hz
        if new_len2 > 0.0:
            scale = math.sqrt(h_len2 / new_len2)
            hx *= scale
            hy *= scale
            hz *= scale
    hx += vtx * dt
    hy += vty * dt
    hz += vtz * dt
    fx = -k_t * hx - eta_t * vtx
    fy = -k_t * hy - eta_t * vty
    fz = -k_t * hz - eta_t * vtz
    f_t2 = fx * fx + fy * fy + fz * fz
    f_max = mu * f_n
    if f_t2 > f_max * f_max:  # sliding (squares compared: no square root while the contact sticks)
        scale = f_max / math.sqrt(f_t2)
        fx *= scale
        fy *= scale
        fz *= scale
        hx = -(fx + eta_t * vtx) * inv_k_t
        hy = -(fy + eta_t * vty) * inv_k_t
        hz = -(fz + eta_t * vtz) * inv_k_t
    history[row, 0] = hx
    history[row, 1] = hy
    history[row, 2] = hz
    return fx, fy, fz


@njit(cache=True, inline="always")
def rolling_torque(nx, ny, nz, wx, wy, wz, f_n, mu_r, r_eff, inertia_eff, inv_dt):
    """Constant directional rolling-friction torque [N m] on the particle, from the relative
    angular velocity ``w`` [rad/s] of particle minus partner: ``-min(mu_r R* F_n, I* |w_r| / dt)``
    along ``w_r / |w_r|`` (one division: ``-min(mu_r R* F_n / |w_r|, I* / dt) w_r``)."""
    wn = wx * nx + wy * ny + wz * nz
    rx = wx - wn * nx
    ry = wy - wn * ny
    rz = wz - wn * nz
    w_roll2 = rx * rx + ry * ry + rz * rz
    if w_roll2 == 0.0 or mu_r == 0.0:
        return 0.0, 0.0, 0.0
    s = -min(mu_r * r_eff * f_n / math.sqrt(w_roll2), inertia_eff * inv_dt)
    return s * rx, s * ry, s * rz


@njit(cache=True, inline="always")
def contact_force(history, row, delta, nx, ny, nz, vx, vy, vz, wx, wy, wz,
                  eta_n, r_eff, inertia_eff, law):
    """Total contact force on the particle [N] and its rolling torque [N m].

    ``history[row]`` holds the tangential displacement [m] and the contact flag (see module doc).
    ``delta`` overlap [m]; ``eta_n`` the dashpot coefficient [kg/s] (``normal_damping``);
    ``r_eff`` reduced radius [m]; ``inertia_eff`` reduced rolling inertia [kg m^2];
    ``n`` unit normal from partner to particle; ``v`` relative velocity of
    the particle's contact point [m/s]; ``w`` relative angular velocity [rad/s]; ``law`` the
    constants of ``kernel_constants``. Returns ``(fx, fy, fz, tx, ty, tz, f_n)`` with ``f_n >= 0``
    the normal force magnitude.
    """
    k_n, k_t, inv_k_t, eta_t_ratio = law[LAW_K_N], law[LAW_K_T], law[LAW_INV_K_T], law[LAW_ETA_T_RATIO]
    mu, mu_r, dt, inv_dt = law[LAW_FRICTION], law[LAW_ROLLING_FRICTION], law[LAW_DT], law[LAW_INV_DT]
    v_n = vx * nx + vy * ny + vz * nz
    onset = 1.0
    if history[row, 3] == 0.0:  # first step of this contact
        history[row, 3] = 1.0
        if v_n < 0.0:
            onset = 0.5 + min(delta / (-v_n * dt), 1.0)
    f_n = normal_force(delta, v_n, k_n, eta_n * onset)
    ftx, fty, ftz = tangential_force(history, row, nx, ny, nz, vx - v_n * nx, vy - v_n * ny, vz - v_n * nz,
                                     f_n, k_t, inv_k_t, eta_n * eta_t_ratio, mu, dt)
    trx, try_, trz = rolling_torque(nx, ny, nz, wx, wy, wz, f_n, mu_r, r_eff, inertia_eff, inv_dt)
    return f_n * nx + ftx, f_n * ny + fty, f_n * nz + ftz, trx, try_, trz, f_n
