"""The closures of ``closures.py`` as compiled per-particle kernels (the bridge's fast path).

Each registered law that has a kernel names it in its registration (``closures.register(...,
kernel="name")``, a function of this module, loaded at first use); the bridge calls ``Law.evaluate``,
which uses the kernel when there is one and the numpy function otherwise, so a law registered without a kernel still runs. The numpy functions in
``closures.py`` stay the reference: ``tests/test_kernels.py`` checks every kernel against them to
1e-12 on random slips, voidages and orientations.

A kernel is ``kernel(slip (N, 3), voidage (N,), axis (N, 3), shape (5,), out)`` with ``shape`` =
``(diameter, length, d_p, rho, mu)`` [m, m, m, kg/m^3, Pa s] (``ParticleShape.kernel_args``), writing
the drag coefficient ``c`` [kg/s] (``out`` (N,)), the lift [N] or the torque [N m] (``out`` (N, 3)),
in parallel over particles, one particle's whole evaluation in one iteration (no temporaries).
Formulas, validity and references are those of the numpy functions they mirror (named below).

Also here: the semi-implicit exchange of the bridge (``exchange_terms``: the particle response, the
gas coefficient and source, deposited with the interpolation weights in one race-free pass).
"""
from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit

from ..dem.particles import spherocylinder_volume
from .closures import SANJEEVI_PADDING_DRAG, SANJEEVI_PADDING_TORQUE, ZASTAWNY_LIFT, ZASTAWNY_TORQUE
from .interpolation import scatter_blocks

RE_FLOOR = 1e-12  # as closures._slip_state: finite coefficients (and zero force) at zero slip

# shape vector: indices into ``shape``
DIAMETER, LENGTH, D_P, RHO, MU = 0, 1, 2, 3, 4


# --------------------------------------------------------------------------- scalar pieces
@njit(cache=True, inline="always")
def _speed(slip, i):
    return math.sqrt(slip[i, 0] * slip[i, 0] + slip[i, 1] * slip[i, 1] + slip[i, 2] * slip[i, 2])


@njit(cache=True, inline="always")
def _reynolds(speed, eps, shape):
    """Superficial slip Reynolds number, floored (``closures.slip_reynolds``)."""
    return max(shape[RHO] * shape[D_P] * eps * speed / shape[MU], RE_FLOOR)


@njit(cache=True, inline="always")
def _cos2(slip, axis, i, speed):
    """cos^2 of the angle between axis and slip, clipped to [0, 1] (``closures._cos2``)."""
    c = (axis[i, 0] * slip[i, 0] + axis[i, 1] * slip[i, 1] + axis[i, 2] * slip[i, 2]) / max(speed, 1e-300)
    return min(max(c * c, 0.0), 1.0)


@njit(cache=True, inline="always")
def _hs_cd(re, phi, crosswise, lengthwise):
    """Hoelzer-Sommerfeld C_D (``closures.hoelzer_sommerfeld_cd``)."""
    return (8.0 / (re * math.sqrt(lengthwise)) + 16.0 / (re * math.sqrt(phi)) + 3.0 / (math.sqrt(re) * phi ** 0.75)
            + 0.42 * 10.0 ** (0.4 * max(-math.log10(phi), 0.0) ** 0.2) / crosswise)


@njit(cache=True, inline="always")
def _shape_constants(shape):
    """Sphericity, A_e, end area, rod area factor and half the surface of the spherocylinder."""
    d, length = shape[DIAMETER], shape[LENGTH]
    rod = length - d
    volume = np.pi / 4 * d ** 2 * rod + np.pi / 6 * d ** 3
    surface = np.pi * d * rod + np.pi * d ** 2
    d_p = (6 * volume / np.pi) ** (1 / 3)
    phi = np.pi ** (1 / 3) * (6 * volume) ** (2 / 3) / surface
    return phi, np.pi / 4 * d_p ** 2, np.pi / 4 * d ** 2, d * rod, surface / 2


@njit(cache=True, inline="always")
def _sphericities(cos2, shape):
    """Sphericity, crosswise and lengthwise sphericity at incidence ``arccos(sqrt(cos2))``
    (``closures.sphericities`` with ``closures.incidence_angle``)."""
    phi, a_e, end, rod_area, half_surface = _shape_constants(shape)
    theta = math.acos(math.sqrt(cos2))
    crosswise = a_e / (end + rod_area * abs(math.sin(theta)))
    lengthwise = a_e / (half_surface - (end + rod_area * abs(math.cos(theta))))
    return phi, crosswise, lengthwise


@njit(cache=True, inline="always")
def _di_felice(re):
    return 3.7 - 0.65 * math.exp(-(1.5 - math.log10(re)) ** 2 / 2.0)


@njit(cache=True, inline="always")
def _hs_coefficient(re, eps, shape, phi, crosswise, lengthwise):
    """``closures.single_particle_drag_coefficient`` of one particle."""
    d_p, mu = shape[D_P], shape[MU]
    cd_re = _hs_cd(re, phi, crosswise, lengthwise) * re
    return 0.5 * cd_re * mu / (d_p * eps) * eps ** (2.0 - _di_felice(re)) * np.pi / 4 * d_p ** 2


_SP_ORDER = ("a1", "a2", "a3", "a4", "a5", "a", "b", "c", "d", "e", "f", "g")
SP_DRAG = np.array([[SANJEEVI_PADDING_DRAG[name][column] for name in _SP_ORDER] for column in (0, 1)])
SP_TORQUE = np.array([SANJEEVI_PADDING_TORQUE[name] for name in ("a", "b", "c", "d", "e")])
Z_LIFT = np.array(ZASTAWNY_LIFT)
Z_TORQUE = np.array(ZASTAWNY_TORQUE)


@njit(cache=True, inline="always")
def _sp_drag_at(re, es, column):
    """``closures.sanjeevi_padding_drag_at`` at incidence 0 (``column = 0``) or 90 degrees (1)."""
    a1, a2, a3, a4, a5 = SP_DRAG[column, 0], SP_DRAG[column, 1], SP_DRAG[column, 2], SP_DRAG[column, 3], SP_DRAG[column, 4]
    a, b, c, d = SP_DRAG[column, 5], SP_DRAG[column, 6], SP_DRAG[column, 7], SP_DRAG[column, 8]
    e, f, g = SP_DRAG[column, 9], SP_DRAG[column, 10], SP_DRAG[column, 11]
    cd_isol = (a1 / re + a2 / re ** a3) * math.exp(-a4 * re) + a5 * (1 - math.exp(-a4 * re))
    f_isol = cd_isol * re / 24.0
    f_eps = a * math.sqrt(es) / (1 - es) ** 2 + b * es / (1 - es) ** 2
    f_re_eps = re ** c * es ** d * (e * (1 - es) + f * es ** 3 / (1 - es)) + g * es * (1 - es) ** 2 * re
    return f_isol * (1 - es) ** 2 + f_eps + f_re_eps


@njit(cache=True, inline="always")
def _zastawny(re, alpha, k):
    return ((k[0] / re ** k[1] + k[2] / re ** k[3]) * math.sin(alpha) ** (k[4] + k[5] * re ** k[6])
            * math.cos(alpha) ** (k[7] + k[8] * re ** k[9]))


@njit(cache=True, inline="always")
def _lift_direction(slip, axis, i, out):
    """``closures.lift_direction``: sign(a.u) ((a x u) x u) / |(a x u) x u| into ``out[i]`` (zero where the
    axis is parallel or perpendicular to the slip)."""
    ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
    ux, uy, uz = slip[i, 0], slip[i, 1], slip[i, 2]
    au = ax * ux + ay * uy + az * uz
    cx, cy, cz = ay * uz - az * uy, az * ux - ax * uz, ax * uy - ay * ux  # a x u
    vx, vy, vz = cy * uz - cz * uy, cz * ux - cx * uz, cx * uy - cy * ux  # (a x u) x u
    norm = math.sqrt(vx * vx + vy * vy + vz * vz)
    if norm > 1e-300 and au != 0.0:
        s = 1.0 if au > 0 else -1.0
        out[i, 0], out[i, 1], out[i, 2] = s * vx / norm, s * vy / norm, s * vz / norm
    else:
        out[i, 0], out[i, 1], out[i, 2] = 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def _torque_direction(slip, axis, i, out):
    """``closures.torque_direction``: sign(u.a) (u x a) / |u x a| into ``out[i]``."""
    ax, ay, az = axis[i, 0], axis[i, 1], axis[i, 2]
    ux, uy, uz = slip[i, 0], slip[i, 1], slip[i, 2]
    ua = ux * ax + uy * ay + uz * az
    vx, vy, vz = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax
    norm = math.sqrt(vx * vx + vy * vy + vz * vz)
    if norm > 1e-300 and ua != 0.0:
        s = 1.0 if ua > 0 else -1.0
        out[i, 0], out[i, 1], out[i, 2] = s * vx / norm, s * vy / norm, s * vz / norm
    else:
        out[i, 0], out[i, 1], out[i, 2] = 0.0, 0.0, 0.0


# --------------------------------------------------------------------------- drag kernels
@njit(cache=True, parallel=True)
def hoelzer_sommerfeld_drag(slip, voidage, axis, shape, out):
    """``closures._hoelzer_sommerfeld``: Hoelzer-Sommerfeld with Di Felice's voidage function."""
    sphere = shape[LENGTH] <= shape[DIAMETER]
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        re = _reynolds(speed, voidage[i], shape)
        if sphere:
            out[i] = _hs_coefficient(re, voidage[i], shape, 1.0, 1.0, 1.0)
        else:
            phi, crosswise, lengthwise = _sphericities(_cos2(slip, axis, i, speed), shape)
            out[i] = _hs_coefficient(re, voidage[i], shape, phi, crosswise, lengthwise)
    return out


@njit(cache=True, parallel=True)
def sanjeevi_padding_drag(slip, voidage, axis, shape, out):
    """``closures.multi_particle_drag_coefficient``: Sanjeevi & Padding 2020, Eqs. 15-21."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        re = _reynolds(speed, eps, shape)
        cos2 = _cos2(slip, axis, i, speed)
        f0 = _sp_drag_at(re, 1.0 - eps, 0)
        f90 = _sp_drag_at(re, 1.0 - eps, 1)
        out[i] = 3 * np.pi * shape[MU] * shape[D_P] * eps * (f0 + (f90 - f0) * (1.0 - cos2))
    return out


@njit(cache=True, parallel=True)
def gidaspow_drag(slip, voidage, axis, shape, out):
    """``closures._gidaspow``: Ergun below voidage 0.8 (with the sphericity), Wen-Yu above."""
    sphericity = _shape_constants(shape)[0] if shape[LENGTH] > shape[DIAMETER] else 1.0
    d_p, rho, mu = shape[D_P], shape[RHO], shape[MU]
    volume = np.pi / 6.0 * d_p ** 3
    d = sphericity * d_p
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        re = _reynolds(speed, eps, shape)
        if eps < 0.8:
            out[i] = volume * (150.0 * (1.0 - eps) * mu / (eps * d ** 2) + 1.75 * rho * speed / d)
        else:
            cd_re = 24.0 * (1.0 + 0.15 * re ** 0.687) if re < 1000.0 else 0.44 * re
            out[i] = volume * (0.75 * cd_re * mu / d_p ** 2 * eps ** -2.65)
    return out


@njit(cache=True, inline="always")
def _non_spherical_factor(slip, axis, i, speed, re, shape):
    """``closures.non_spherical_factor``: isolated HS C_D at the incidence over the sphere's."""
    if shape[LENGTH] <= shape[DIAMETER]:
        return 1.0
    phi, crosswise, lengthwise = _sphericities(_cos2(slip, axis, i, speed), shape)
    return _hs_cd(re, phi, crosswise, lengthwise) / _hs_cd(re, 1.0, 1.0, 1.0)


@njit(cache=True, inline="always")
def _creeping(phi, eps):
    return 10.0 * phi / eps ** 2 + eps ** 2 * (1.0 + 1.5 * math.sqrt(phi))


@njit(cache=True, parallel=True)
def beetstra_drag(slip, voidage, axis, shape, out):
    """``closures.beetstra_normalised`` (Beetstra, van der Hoef & Kuipers 2007, Eq. 15), times the
    shape factor for rods."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        re = _reynolds(speed, eps, shape)
        phi = 1.0 - eps
        inertial = (0.413 * re / (24.0 * eps ** 2) * (1.0 / eps + 3.0 * phi * eps + 8.4 * re ** -0.343)
                    / (1.0 + 10.0 ** (3.0 * phi) * re ** (-(1.0 + 4.0 * phi) / 2.0)))
        f = _creeping(phi, eps) + inertial
        out[i] = 3.0 * np.pi * shape[MU] * shape[D_P] * eps * f * _non_spherical_factor(slip, axis, i, speed, re, shape)
    return out


@njit(cache=True, parallel=True)
def tenneti_drag(slip, voidage, axis, shape, out):
    """``closures.tenneti_normalised`` (Tenneti, Garg & Subramaniam 2011, Eqs. 9-12; F = eps F_tot),
    times the shape factor for rods."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        re = _reynolds(speed, eps, shape)
        phi = 1.0 - eps
        total = ((1.0 + 0.15 * re ** 0.687) / eps ** 3 + 5.81 * phi / eps ** 3 + 0.48 * phi ** (1.0 / 3.0) / eps ** 4
                 + phi ** 3 * re * (0.95 + 0.61 * phi ** 3 / eps ** 2))
        out[i] = (3.0 * np.pi * shape[MU] * shape[D_P] * eps * (eps * total)
                  * _non_spherical_factor(slip, axis, i, speed, re, shape))
    return out


@njit(cache=True, parallel=True)
def tang_drag(slip, voidage, axis, shape, out):
    """``closures.tang_normalised`` (Tang et al. 2015, Eq. 20), times the shape factor for rods."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        re = _reynolds(speed, eps, shape)
        phi = 1.0 - eps
        f = _creeping(phi, eps) + re * (0.11 * phi * (1.0 + phi) - 0.00456 / eps ** 4
                                        + (0.169 * eps + 0.0644 / eps ** 4) * re ** -0.343)
        out[i] = 3.0 * np.pi * shape[MU] * shape[D_P] * eps * f * _non_spherical_factor(slip, axis, i, speed, re, shape)
    return out


@njit(cache=True, parallel=True)
def slip_reynolds(slip, voidage, shape, out):
    """Superficial slip Reynolds numbers (floored), for the validity-range warnings."""
    for i in numba.prange(slip.shape[0]):
        out[i] = _reynolds(_speed(slip, i), voidage[i], shape)
    return out


# --------------------------------------------------------------------------- lift and torque kernels
@njit(cache=True, inline="always")
def _scale_row(out, i, factor):
    out[i, 0] *= factor
    out[i, 1] *= factor
    out[i, 2] *= factor


@njit(cache=True, parallel=True)
def _zastawny_form(slip, voidage, axis, shape, out, table, torque):
    """The Zastawny form's force ``1/2 C_L rho (pi/4) d_p^2 |u|^2`` along the lift direction, or its
    torque ``1/2 C_T rho (pi/8) d_p^3 |u|^2`` along the torque direction (``torque``), ``C`` from
    ``table`` (Table 3's b1..b10 or c1..c10)."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        re = _reynolds(speed, voidage[i], shape)
        alpha = math.acos(math.sqrt(_cos2(slip, axis, i, speed)))
        if torque:
            magnitude = 0.5 * _zastawny(re, alpha, table) * shape[RHO] * np.pi / 8 * shape[D_P] ** 3 * speed ** 2
            _torque_direction(slip, axis, i, out)
        else:
            magnitude = 0.5 * _zastawny(re, alpha, table) * shape[RHO] * np.pi / 4 * shape[D_P] ** 2 * speed ** 2
            _lift_direction(slip, axis, i, out)
        _scale_row(out, i, magnitude)
    return out


@njit(cache=True)
def zastawny_lift(slip, voidage, axis, shape, out):
    """``closures.single_particle_lift``: 1/2 C_L rho (pi/4) d_p^2 |u|^2 along the lift direction."""
    return _zastawny_form(slip, voidage, axis, shape, out, Z_LIFT, False)


@njit(cache=True)
def zastawny_torque(slip, voidage, axis, shape, out):
    """``closures.single_particle_torque``: 1/2 C_T rho (pi/8) d_p^3 |u|^2 along the torque direction."""
    return _zastawny_form(slip, voidage, axis, shape, out, Z_TORQUE, True)


@njit(cache=True, parallel=True)
def sanjeevi_padding_lift(slip, voidage, axis, shape, out):
    """``closures.multi_particle_lift`` (Sanjeevi & Padding 2020, Eqs. 25-26)."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        re = _reynolds(speed, eps, shape)
        phi = math.acos(math.sqrt(_cos2(slip, axis, i, speed)))
        f_l = (_sp_drag_at(re, 1.0 - eps, 1) - _sp_drag_at(re, 1.0 - eps, 0)) * math.sin(phi) * math.cos(phi)
        magnitude = 3 * np.pi * shape[MU] * shape[D_P] * eps * speed * f_l
        _lift_direction(slip, axis, i, out)
        _scale_row(out, i, magnitude)
    return out


@njit(cache=True, parallel=True)
def sanjeevi_padding_torque(slip, voidage, axis, shape, out):
    """``closures.multi_particle_torque`` (Sanjeevi & Padding 2020, Eqs. 30-33, Table 4)."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        es = 1.0 - eps
        re = _reynolds(speed, eps, shape)
        isolated = _zastawny(re, np.pi / 4, Z_TORQUE) * re / 16.0
        t_mag = (isolated * (1 - es) ** 2
                 + re ** SP_TORQUE[0] * es ** SP_TORQUE[1] * (SP_TORQUE[2] * (1 - es) + SP_TORQUE[3] * es ** 3 / (1 - es))
                 + SP_TORQUE[4] * es * (1 - es) ** 2 * re)
        phi = math.acos(math.sqrt(_cos2(slip, axis, i, speed)))
        magnitude = 2 * np.pi * shape[MU] * shape[D_P] ** 2 * eps * speed * t_mag * math.sin(phi) * math.cos(phi)
        _torque_direction(slip, axis, i, out)
        _scale_row(out, i, magnitude)
    return out


# --------------------------------------------------------------------------- the semi-implicit exchange
@njit(cache=True, parallel=True)
def exchange_terms(mass, c, velocity, force, gravity, lift, substep, substeps, dt, cells, weights,
                   beta_out, source_out):
    """The bridge's semi-implicit exchange, per particle and deposited in one pass (``bridge`` step 3):
    ``R = (1 + h c / 2m)^(-2n)``, ``k = (1 - R) m / (c dt) - 1`` (0 where c = 0), coefficient
    ``m (1 - R) / dt``, exchanged momentum rate ``coefficient v - m k a - F_L`` with ``a = F / m + g``
    (``F`` contact + external force); their interpolation-weighted sums go to ``beta_out`` (C,) and
    ``source_out`` (C, 3) (not yet divided by the cell volumes). ``lift`` may be (0, 3): none.
    Race-free like ``interpolation.scatter``: fixed particle blocks into private copies, added in
    block order."""
    n = cells.shape[0]
    chunks = scatter_blocks(n)
    ncell = beta_out.shape[0]
    partial = np.zeros((chunks, ncell, 4))
    has_lift = lift.shape[0] == n
    for chunk in numba.prange(chunks):
        block = partial[chunk]
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            m, ci = mass[i], c[i]
            q = 0.5 * substep * ci / m
            one_minus_r = -math.expm1(-2.0 * substeps * math.log1p(q))
            x = ci * substep * substeps / m
            k = one_minus_r / x - 1.0 if x > 0 else 0.0
            coefficient = m * one_minus_r / dt
            e0 = coefficient * velocity[i, 0] - m * k * (force[i, 0] / m + gravity[0])
            e1 = coefficient * velocity[i, 1] - m * k * (force[i, 1] / m + gravity[1])
            e2 = coefficient * velocity[i, 2] - m * k * (force[i, 2] / m + gravity[2])
            if has_lift:
                e0 -= lift[i, 0]
                e1 -= lift[i, 1]
                e2 -= lift[i, 2]
            for j in range(cells.shape[1]):
                w = weights[i, j]
                if w != 0.0:
                    cell = cells[i, j]
                    block[cell, 0] += w * coefficient
                    block[cell, 1] += w * e0
                    block[cell, 2] += w * e1
                    block[cell, 3] += w * e2
    for cell in numba.prange(ncell):
        for chunk in range(chunks):
            beta_out[cell] += partial[chunk, cell, 0]
            for d in range(3):
                source_out[cell, d] += partial[chunk, cell, d + 1]
    return beta_out, source_out


# --------------------------------------------------------------------------- fused closure sets
@njit(cache=True, parallel=True)
def sanjeevi_padding_all(slip, voidage, axis, shape, c_out, lift_out, torque_out):
    """Sanjeevi & Padding's drag, lift and torque in one pass (``closures.FUSED``): the three kernels
    above share the slip speed, Re, incidence and the drag at 0 and 90 degrees; the same expressions,
    so the same numbers as ``sanjeevi_padding_drag``, ``_lift`` and ``_torque`` one by one."""
    for i in numba.prange(slip.shape[0]):
        speed = _speed(slip, i)
        eps = voidage[i]
        es = 1.0 - eps
        re = _reynolds(speed, eps, shape)
        cos2 = _cos2(slip, axis, i, speed)
        f0 = _sp_drag_at(re, es, 0)
        f90 = _sp_drag_at(re, es, 1)
        c_out[i] = 3 * np.pi * shape[MU] * shape[D_P] * eps * (f0 + (f90 - f0) * (1.0 - cos2))
        phi = math.acos(math.sqrt(cos2))
        f_l = (f90 - f0) * math.sin(phi) * math.cos(phi)
        magnitude = 3 * np.pi * shape[MU] * shape[D_P] * eps * speed * f_l
        _lift_direction(slip, axis, i, lift_out)
        _scale_row(lift_out, i, magnitude)
        isolated = _zastawny(re, np.pi / 4, Z_TORQUE) * re / 16.0
        t_mag = (isolated * (1 - es) ** 2
                 + re ** SP_TORQUE[0] * es ** SP_TORQUE[1] * (SP_TORQUE[2] * (1 - es) + SP_TORQUE[3] * es ** 3 / (1 - es))
                 + SP_TORQUE[4] * es * (1 - es) ** 2 * re)
        magnitude = 2 * np.pi * shape[MU] * shape[D_P] ** 2 * eps * speed * t_mag * math.sin(phi) * math.cos(phi)
        _torque_direction(slip, axis, i, torque_out)
        _scale_row(torque_out, i, magnitude)
    return c_out, lift_out, torque_out


# --------------------------------------------------------------------------- the bridge's per-particle glue
@njit(cache=True, parallel=True)
def slip_at_particles(at_particles, velocity, minimum_voidage, fixed, voidage_out, slip_out):
    """From the gathered ``(voidage, u_x, u_y, u_z)`` rows: the voidage clipped to
    ``[minimum_voidage, 1]`` and the slip ``u - v`` (``u`` itself for fixed particles), written into
    ``voidage_out`` (N,) and ``slip_out`` (N, 3). The numpy form: ``np.clip(at[:, 0], minimum, 1)``,
    ``at[:, 1:] - v``."""
    for i in numba.prange(at_particles.shape[0]):
        voidage_out[i] = min(max(at_particles[i, 0], minimum_voidage), 1.0)
        for d in range(3):
            slip_out[i, d] = at_particles[i, 1 + d] if fixed else at_particles[i, 1 + d] - velocity[i, d]
    return voidage_out, slip_out


@njit(cache=True, inline="always")
def _sum_blocks(partial):
    """The rows of the per-block partial sums ``partial`` (blocks, k) added in block order (k,)."""
    total = np.zeros(partial.shape[1])
    for chunk in range(partial.shape[0]):
        for d in range(partial.shape[1]):
            total[d] += partial[chunk, d]
    return total


@njit(cache=True, parallel=True)
def particle_forces(at_particles, pressure_gradient_force, radius, half_length, mean_gradient, lift, explicit_drag,
                    fluid_velocity_out, external_out):
    """The gas's forces on the particles held over a coupling interval, from the gathered rows
    ``(u_x, u_y, u_z[, dp/dx, dp/dy, dp/dz])``: ``fluid_velocity_out = u`` and ``external_out =
    -V_p grad p + V_p G + F_L + F_D,explicit`` (``V_p`` the spherocylinder volume; ``G`` the imposed mean
    pressure gradient; ``lift`` / ``explicit_drag`` may be (0, 3): none). Returns the pressure part's
    sum over the particles, ``sum(-V_p grad p + V_p G)`` (3,), summed in fixed particle blocks, so the
    same on any number of threads."""
    n = at_particles.shape[0]
    chunks = scatter_blocks(n)
    partial = np.zeros((chunks, 3))
    has_lift = lift.shape[0] == n
    has_explicit = explicit_drag.shape[0] == n
    for chunk in numba.prange(chunks):
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            volume = spherocylinder_volume(radius[i], half_length[i])
            for d in range(3):
                fluid_velocity_out[i, d] = at_particles[i, d]
                f = 0.0
                if pressure_gradient_force:
                    f -= volume * at_particles[i, 3 + d]
                f += volume * mean_gradient[d]
                partial[chunk, d] += f
                if has_lift:
                    f += lift[i, d]
                if has_explicit:
                    f += explicit_drag[i, d]
                external_out[i, d] = f
    return _sum_blocks(partial)


@njit(cache=True, parallel=True)
def column_sums(values):
    """``values.sum(axis=0)`` of an (N, 3) array, summed in fixed particle blocks (the same on any number
    of threads; numpy's strided axis-0 sum cost 0.37 ms on 32,500 rows)."""
    n = values.shape[0]
    chunks = scatter_blocks(n)
    partial = np.zeros((chunks, values.shape[1]))
    for chunk in numba.prange(chunks):
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            for d in range(values.shape[1]):
                partial[chunk, d] += values[i, d]
    return _sum_blocks(partial)
