"""The hydrodynamic closures of Mema et al. (2020) (docs/equations.md §3, Table 1), each written once, as
compiled scalar functions of one particle.

A **law** takes one particle's slip ``(sx, sy, sz)`` (gas interstitial velocity minus particle velocity)
[m/s], its voidage ``eps``, its unit axis ``(ax, ay, az)`` and the ``shape`` vector (``shape_vector``:
cylinder diameter and total length [m], volume-equivalent diameter [m], fluid density [kg/m^3] and
viscosity [Pa s], and the spherocylinder's constants of ``shape_constants``) and returns the drag coefficient
``c`` [kg/s] with ``F_D = c u`` (``DRAG``), or the lift force [N] / the hydrodynamic torque [N m] as a
3-tuple (``FORCE``). Each law is compiled for exactly that signature. The registry (``closures.LAWS``)
names them, and the loops over the particles are written from it (``law_loops``), each law inlined by its
index; the numpy functions of ``closures`` are these same functions applied per particle; their ``py_func``
is the reference the tests run in plain Python. ``sanjeevi_padding_set`` and ``single_particle_set`` are
compositions (``closures.SETS``): a set of three laws from the same pieces, their shared state computed once.

The pieces the laws share (the slip Reynolds number, the incidence, the sphericities, C_D of Hoelzer &
Sommerfeld, Sanjeevi & Padding's F(Re, eps_s), Zastawny's form, the lift and torque directions) are
scalar functions here too, each with its formula and reference.

Choices on the points docs/equations.md flags as ambiguous (each pinned by a test in
tests/verification/test_closures.py):

- Particle Reynolds number: the *superficial* slip, ``Re = rho d_p eps |u| / mu`` (Di Felice 1994,
  CFDEMcoupling; Sanjeevi & Padding normalise by the superficial velocity too), floored at
  ``RE_FLOOR`` so that a particle at rest in the gas has finite coefficients and zero force.
- Crosswise and lengthwise sphericities: ``A_perp = (pi/4) d^2 + d L_rod sin(theta)`` and
  ``Phi_par = A_e / (A_p/2 - A_par)``; the extracted forms fail the sphere limit Phi = 1.
- Sanjeevi-Padding Eq. 17: the isolated drag enters as the product ``F_isol (1 - eps_s)^2``, which
  recovers the isolated particle at eps_s -> 0; Eq. 15 is normalised by the Stokes drag on the
  superficial slip, ``F_D = 3 pi mu d_p eps u F``.
- Table 2 lists e = f = 11.12 at 90 degrees; used as extracted.
"""
from __future__ import annotations

import math

import numpy as np
from numba import float64, njit, types

from .coefficients import GIDASPOW_SWITCH, RE_FLOOR, SP_DRAG, SP_TORQUE, Z_LIFT, Z_TORQUE

# indices into the shape vector: the particle and the fluid, then the spherocylinder's constants
# (``shape_constants``), computed once per particle shape rather than per particle
DIAMETER, LENGTH, D_P, RHO, MU, PHI, A_E, END, ROD_AREA, HALF_SURFACE = range(10)
SHAPE = float64[::1]
_ARGS = (float64, float64, float64, float64, float64, float64, float64, SHAPE)  # sx, sy, sz, eps, ax, ay, az, shape
DRAG = float64(*_ARGS)  # a drag law's signature: the coefficient c [kg/s]
FORCE = types.UniTuple(float64, 3)(*_ARGS)  # a lift or torque law's: the force [N] or torque [N m]


# --------------------------------------------------------------------------- shared pieces
@njit(cache=True, inline="always")
def slip_speed(sx, sy, sz):
    return math.sqrt(sx * sx + sy * sy + sz * sz)


@njit(cache=True, inline="always")
def reynolds(speed, eps, d_p, rho, mu):
    """Particle Reynolds number on the superficial slip, ``rho d_p eps |u| / mu``, floored at ``RE_FLOOR``."""
    return max(rho * d_p * eps * speed / mu, RE_FLOOR)


@njit(cache=True, inline="always")
def cos2(sx, sy, sz, ax, ay, az, speed):
    """cos^2 of the angle between axis and slip, clipped to [0, 1] (0 at zero slip)."""
    c = (ax * sx + ay * sy + az * sz) / max(speed, 1e-300)
    return min(max(c * c, 0.0), 1.0)


@njit(cache=True, inline="always")
def incidence(sx, sy, sz, ax, ay, az, speed):
    """The angle between axis and slip folded into [0, pi/2] [rad]: ``arccos(sqrt(cos2))``."""
    return math.acos(math.sqrt(cos2(sx, sy, sz, ax, ay, az, speed)))


@njit(cache=True, inline="always")
def hs_cd(re, phi, crosswise, lengthwise):
    """Drag coefficient of an isolated non-spherical particle (Hoelzer & Sommerfeld 2008; Mema et al. Eq. 11):
    ``8/(Re sqrt(Phi_par)) + 16/(Re sqrt(Phi)) + 3/(sqrt(Re) Phi^(3/4)) + 0.42 10^(0.4 (-log Phi)^0.2) / Phi_perp``.
    For a sphere: 24/Re + 3/sqrt(Re) + 0.42. Valid for Re up to ~1e5 and 0.09 < Phi <= 1 (Phi > 1 by
    round-off is taken as 1 in the last term)."""
    return (8.0 / (re * math.sqrt(lengthwise)) + 16.0 / (re * math.sqrt(phi)) + 3.0 / (math.sqrt(re) * phi ** 0.75)
            + 0.42 * 10.0 ** (0.4 * max(-math.log10(phi), 0.0) ** 0.2) / crosswise)


@njit(cache=True, inline="always")
def shape_constants(diameter, length):
    """Of a spherocylinder of cylinder ``diameter`` and total ``length`` (``length == diameter``: a sphere):
    its sphericity ``Phi = pi^(1/3) (6 V)^(2/3) / A_p``, ``A_e = (pi/4) d_p^2``, the end area (pi/4) d^2,
    the rod's projected-area factor ``d L_rod`` and half its surface ``A_p / 2``; and ``d_p``, ``V``, ``A_p``."""
    rod = length - diameter
    volume = np.pi / 4 * diameter ** 2 * rod + np.pi / 6 * diameter ** 3
    surface = np.pi * diameter * rod + np.pi * diameter ** 2
    d_p = (6 * volume / np.pi) ** (1 / 3)
    phi = np.pi ** (1 / 3) * (6 * volume) ** (2 / 3) / surface
    return phi, np.pi / 4 * d_p ** 2, np.pi / 4 * diameter ** 2, diameter * rod, surface / 2, d_p, volume, surface


@njit(cache=True)
def shape_vector(diameter, length, rho, mu):
    """The shape vector every law reads: ``(diameter, length, d_p, rho, mu, Phi, A_e, (pi/4) d^2, d L_rod,
    A_p / 2)`` (indices ``DIAMETER`` ... ``HALF_SURFACE``)."""
    phi, a_e, end, rod_area, half_surface, d_p, _, _ = shape_constants(diameter, length)
    return np.array([diameter, length, d_p, rho, mu, phi, a_e, end, rod_area, half_surface])


@njit(cache=True, inline="always")
def sphericities(theta, phi, a_e, end, rod_area, half_surface):
    """Sphericity, crosswise and lengthwise sphericity (Hoelzer & Sommerfeld 2008; Mema et al. Eqs. 12-14) at
    the angle ``theta`` [rad] between axis and slip, from the constants of ``shape_constants``:
    ``Phi_perp = A_e / ((pi/4) d^2 + d L_rod |sin theta|)``, ``Phi_par = A_e / (A_p / 2 - ((pi/4) d^2 + d L_rod
    |cos theta|))``. All three are 1 for a sphere."""
    crosswise = a_e / (end + rod_area * abs(math.sin(theta)))
    lengthwise = a_e / (half_surface - (end + rod_area * abs(math.cos(theta))))
    return phi, crosswise, lengthwise


@njit(cache=True, inline="always")
def di_felice_exponent(re):
    """Voidage exponent of Di Felice (1994): ``chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2)`` (Eq. 10)."""
    return 3.7 - 0.65 * math.exp(-(1.5 - math.log10(re)) ** 2 / 2.0)


@njit(cache=True, inline="always")
def hs_coefficient(re, eps, d_p, mu, phi, crosswise, lengthwise):
    """Hoelzer-Sommerfeld with Di Felice's voidage function (Eq. 9): ``c = 1/2 C_D rho eps^(2 - chi) (pi/4)
    d_p^2 |u|`` with C_D and chi at the superficial Re, written with ``C_D Re`` so that it stays finite
    as Re -> 0 (Stokes limit ``3 pi mu d_p eps^(3 - chi)``)."""
    cd_re = hs_cd(re, phi, crosswise, lengthwise) * re
    return 0.5 * cd_re * mu / (d_p * eps) * eps ** (2.0 - di_felice_exponent(re)) * np.pi / 4 * d_p ** 2


@njit(cache=True, inline="always")
def sp_drag_at(re, es, column):
    """Sanjeevi & Padding (2020) normalised drag ``F(Re, eps_s)`` at incidence 0 deg (``column = 0``) or
    90 deg (1) (Eqs. 17-21, Table 2): ``F_isol (1 - eps_s)^2 + F_eps + F_Re,eps`` with ``F_isol = C_d,isol
    Re / 24``, ``C_d,isol = (a1/Re + a2/Re^a3) exp(-a4 Re) + a5 (1 - exp(-a4 Re))``, ``F_eps = a sqrt(eps_s) /
    (1 - eps_s)^2 + b eps_s / (1 - eps_s)^2``, ``F_Re,eps = Re^c eps_s^d (e (1 - eps_s) + f eps_s^3 / (1 - eps_s))
    + g eps_s (1 - eps_s)^2 Re``."""
    return _sp_drag_logs(re, math.log(re), es, math.log(es), column)


@njit(cache=True, inline="always")
def _sp_drag_logs(re, ln_re, es, ln_es, column):
    """``sp_drag_at`` given also ``ln Re`` and ``ln eps_s``: each power an exponential, ``x^a = exp(a ln x)``,
    the logarithms shared by both incidences and the torque (a power costs about a logarithm and an
    exponential: the Sanjeevi-Padding set of a particle took 14 of them; ``eps_s = 0`` gives ``ln = -inf``
    and the powers, of positive exponents, 0 as before)."""
    a1, a2, a3, a4, a5 = SP_DRAG[column, 0], SP_DRAG[column, 1], SP_DRAG[column, 2], SP_DRAG[column, 3], SP_DRAG[column, 4]
    a, b, c, d = SP_DRAG[column, 5], SP_DRAG[column, 6], SP_DRAG[column, 7], SP_DRAG[column, 8]
    e, f, g = SP_DRAG[column, 9], SP_DRAG[column, 10], SP_DRAG[column, 11]
    decay = math.exp(-a4 * re)
    cd_isol = (a1 / re + a2 * math.exp(-a3 * ln_re)) * decay + a5 * (1 - decay)
    f_isol = cd_isol * re / 24.0
    f_eps = a * math.sqrt(es) / (1 - es) ** 2 + b * es / (1 - es) ** 2
    f_re_eps = math.exp(c * ln_re + d * ln_es) * (e * (1 - es) + f * es ** 3 / (1 - es)) + g * es * (1 - es) ** 2 * re
    return f_isol * (1 - es) ** 2 + f_eps + f_re_eps


@njit(cache=True, inline="always")
def zastawny(re, alpha, k):
    """Zastawny et al. (2012) form (Mema et al. Eq. 24; Table 3 for AR-4 spherocylinders), ``k`` = b1..b10
    (lift) or c1..c10 (torque): ``(k1/Re^k2 + k3/Re^k4) sin(alpha)^(k5 + k6 Re^k7) cos(alpha)^(k8 + k9 Re^k10)``."""
    return _zastawny_logs(math.log(re), math.log(math.sin(alpha)), math.log(math.cos(alpha)), k)


@njit(cache=True, inline="always")
def _zastawny_logs(ln_re, ln_sin, ln_cos, k):
    """``zastawny`` from ``ln Re``, ``ln sin(alpha)`` and ``ln cos(alpha)``: its six powers as four exponentials
    (``x^a = exp(a ln x)``; the two angle factors one exponential of a sum). At alpha = 0, ``ln sin = -inf``
    and the factor is 0, as the power was (both tables' angle exponents are positive)."""
    return ((k[0] * math.exp(-k[1] * ln_re) + k[2] * math.exp(-k[3] * ln_re))
            * math.exp((k[4] + k[5] * math.exp(k[6] * ln_re)) * ln_sin + (k[7] + k[8] * math.exp(k[9] * ln_re)) * ln_cos))


@njit(cache=True, inline="always")
def isolated_torque_magnitude(re):
    """``T_p,isol(Re)``, not given in Mema et al. (2020) (flagged): matching Eq. 30 to Eq. 27 at eps_s -> 0
    gives ``T_P,phi = C_T Re / 32``; with the sin phi cos phi dependence taken out at 45 degrees:
    ``T_p,isol = C_T,45(Re) Re / (32 sin 45 cos 45) = C_T,45 Re / 16``."""
    return _isolated_torque_logs(re, math.log(re))


LN_SIN_45 = math.log(math.sin(np.pi / 4))  # = ln cos(pi/4) = -ln(2)/2


@njit(cache=True, inline="always")
def _isolated_torque_logs(re, ln_re):
    """``isolated_torque_magnitude`` given also ``ln Re`` (``_zastawny_logs`` at 45 degrees)."""
    return _zastawny_logs(ln_re, LN_SIN_45, LN_SIN_45, Z_TORQUE) * re / 16.0


@njit(cache=True, inline="always")
def _signed_unit(vx, vy, vz, dot):
    """``sign(dot) v / |v|``; zero where ``v`` or ``dot`` vanishes (the lift and torque directions)."""
    norm = math.sqrt(vx * vx + vy * vy + vz * vz)
    if norm > 1e-300 and dot != 0.0:
        s = 1.0 if dot > 0 else -1.0
        return s * vx / norm, s * vy / norm, s * vz / norm
    return 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def lift_direction(sx, sy, sz, ax, ay, az):
    """Unit lift direction (Eq. 23): ``sign(a.u) ((a x u) x u) / |(a x u) x u|``; zero where the axis is
    parallel or perpendicular to the slip. Unchanged when the axis is reversed."""
    cx, cy, cz = ay * sz - az * sy, az * sx - ax * sz, ax * sy - ay * sx  # a x u
    vx, vy, vz = cy * sz - cz * sy, cz * sx - cx * sz, cx * sy - cy * sx  # (a x u) x u
    return _signed_unit(vx, vy, vz, ax * sx + ay * sy + az * sz)


@njit(cache=True, inline="always")
def torque_direction(sx, sy, sz, ax, ay, az):
    """Unit torque direction (Eq. 28): ``sign(u.a) (u x a) / |u x a|``; unchanged when the axis is reversed."""
    return _signed_unit(sy * az - sz * ay, sz * ax - sx * az, sx * ay - sy * ax, sx * ax + sy * ay + sz * az)


@njit(cache=True, inline="always")
def non_spherical_factor(sx, sy, sz, ax, ay, az, speed, re, shape):
    """Shape correction of a sphere law for spherocylinders: the isolated Hoelzer-Sommerfeld C_D at the
    particle's incidence over the isolated sphere's at the same Re, ``C_D(Re, Phi, Phi_perp, Phi_par) /
    C_D(Re, 1, 1, 1)``; 1 for spheres and tends to 1 as l/d -> 1. An assumption (the crowding of rods is
    taken as the sphere's), not a fit to rod arrays."""
    if shape[LENGTH] <= shape[DIAMETER]:
        return 1.0
    theta = math.acos(math.sqrt(cos2(sx, sy, sz, ax, ay, az, speed)))
    phi, crosswise, lengthwise = sphericities(theta, shape[PHI], shape[A_E], shape[END], shape[ROD_AREA],
                                              shape[HALF_SURFACE])
    return hs_cd(re, phi, crosswise, lengthwise) / hs_cd(re, 1.0, 1.0, 1.0)


@njit(cache=True, inline="always")
def creeping(solids, eps):
    """Beetstra et al.'s creeping-flow terms ``10 phi / eps^2 + eps^2 (1 + 1.5 sqrt(phi))`` (Tang et al. keep them)."""
    return 10.0 * solids / eps ** 2 + eps ** 2 * (1.0 + 1.5 * math.sqrt(solids))


# Dense-suspension laws fitted to particle-resolved simulations of fixed random arrays of spheres, in one
# normalisation: ``F = F_D / (3 pi mu d_p U)``, the drag (the fluid-particle force less the share
# ``-V_p grad p`` of the mean pressure gradient: model A's drag) over the Stokes drag at the superficial
# slip ``U = eps |u|``, a function of the solids fraction ``phi = 1 - eps`` and ``Re = rho d_p U / mu``. The
# particle's coefficient is then ``c = 3 pi mu d_p eps F`` [kg/s]. A fit that reports the total force
# ``F_tot`` (pressure share included) converts by ``F = eps F_tot``.
@njit(cache=True, inline="always")
def beetstra_normalised(solids, re):
    """Beetstra, van der Hoef & Kuipers (2007), AIChE J. 53, 489, Eq. 15 (lattice-Boltzmann, random arrays
    of monodisperse spheres)::

        F = 10 phi / eps^2 + eps^2 (1 + 1.5 sqrt(phi))
            + 0.413 Re / (24 eps^2) (1/eps + 3 phi eps + 8.4 Re^-0.343) / (1 + 10^(3 phi) Re^(-(1 + 4 phi)/2))

    Fitted for 0.1 <= phi <= 0.6 and Re <= 1000. At phi -> 0 it tends to 1 + 0.413 Re/24 (1 + 8.4
    Re^-0.343) / (1 + Re^-0.5), its own single-sphere fit: Stokes' 1 at Re -> 0, within 6 % of
    Schiller-Naumann up to Re = 10 but 16 % above it at Re = 100 and 69 % at Re = 1000 (tests)."""
    eps = 1.0 - solids
    inertial = (0.413 * re / (24.0 * eps ** 2) * (1.0 / eps + 3.0 * solids * eps + 8.4 * re ** -0.343)
                / (1.0 + 10.0 ** (3.0 * solids) * re ** (-(1.0 + 4.0 * solids) / 2.0)))
    return creeping(solids, eps) + inertial


@njit(cache=True, inline="always")
def tenneti_normalised(solids, re):
    """Tenneti, Garg & Subramaniam (2011), Int. J. Multiph. Flow 37, 1072, Eqs. 9-12 (immersed-boundary DNS,
    random fixed arrays of spheres). Their force includes the pressure share (``F_tot``)::

        F_tot = F_isol / eps^3 + 5.81 phi / eps^3 + 0.48 phi^(1/3) / eps^4 + phi^3 Re (0.95 + 0.61 phi^3 / eps^2)

    with Schiller-Naumann's ``F_isol = 1 + 0.15 Re^0.687``; returned as the drag ``F = eps F_tot``. Fitted
    for 0.1 <= phi <= 0.5 and 0.01 <= Re <= 300; at phi -> 0 it is Schiller-Naumann's isolated sphere."""
    eps = 1.0 - solids
    total = ((1.0 + 0.15 * re ** 0.687) / eps ** 3 + 5.81 * solids / eps ** 3 + 0.48 * solids ** (1.0 / 3.0) / eps ** 4
             + solids ** 3 * re * (0.95 + 0.61 * solids ** 3 / eps ** 2))
    return eps * total


@njit(cache=True, inline="always")
def tang_normalised(solids, re):
    """Tang, Peters, Kuipers, Kriebitzsch & van der Hoef (2015), AIChE J. 61, 688, Eq. 20 (immersed-boundary
    DNS, random fixed arrays of spheres; Beetstra's creeping-flow terms kept)::

        F = 10 phi / eps^2 + eps^2 (1 + 1.5 sqrt(phi))
            + Re [0.11 phi (1 + phi) - 0.00456 / eps^4 + (0.169 eps + 0.0644 / eps^4) Re^-0.343]

    Fitted for 0.1 <= phi <= 0.6 and 50 <= Re <= 1000. At phi -> 0: 1 + Re (0.2334 Re^-0.343 - 0.00456),
    on Schiller-Naumann's isolated sphere at Re = 1000 but 18-19 % above it at Re = 50-100 (tests)."""
    eps = 1.0 - solids
    return creeping(solids, eps) + re * (0.11 * solids * (1.0 + solids) - 0.00456 / eps ** 4
                                         + (0.169 * eps + 0.0644 / eps ** 4) * re ** -0.343)


@njit(cache=True, inline="always")
def gidaspow_coefficient(eps, speed, re, d_p, rho, mu, sphericity):
    """Gidaspow (1994), as in MFiX's GIDASPOW and CFDEMcoupling's GidaspowDrag, as the two-fluid interphase
    coefficient ``beta`` [kg/(m^3 s)] per particle, ``c = beta V_p / eps_s``:

    - ``eps < 0.8``, Ergun (1952): ``beta = 150 eps_s^2 mu / (eps (Phi d_p)^2) + 1.75 eps_s rho |u| / (Phi d_p)``
      (``Phi`` the sphericity: Ergun's equivalent diameter ``Phi d_p``). In model A a uniform fixed bed then
      has exactly Ergun's pressure gradient.
    - ``eps >= 0.8``, Wen & Yu (1966): ``beta = 3/4 C_D eps eps_s rho |u| eps^(-2.65) / d_p`` with Schiller-
      Naumann's ``C_D = 24/Re_s (1 + 0.15 Re_s^0.687)`` (0.44 above Re_s = 1000) on the superficial slip;
      at ``eps -> 1`` the isolated sphere's drag ``1/2 C_D rho (pi/4) d_p^2 |u| u``.

    The switch at 0.8 is discontinuous (about a factor 2 at moderate Re), as in the original."""
    volume = np.pi / 6.0 * d_p ** 3
    d = sphericity * d_p
    if eps < GIDASPOW_SWITCH:
        return volume * (150.0 * (1.0 - eps) * mu / (eps * d ** 2) + 1.75 * rho * speed / d)
    cd_re = 24.0 * (1.0 + 0.15 * re ** 0.687) if re < 1000.0 else 0.44 * re  # C_D Re_s, finite at Re -> 0
    return volume * (0.75 * cd_re * mu / d_p ** 2 * eps ** -2.65)


@njit(cache=True, inline="always")
def _hoelzer_sommerfeld_rod(re, eps, theta, shape):
    """``hs_coefficient`` of a spherocylinder at incidence ``theta`` (its sphericities, ``sphericities``)."""
    phi, crosswise, lengthwise = sphericities(theta, shape[PHI], shape[A_E], shape[END], shape[ROD_AREA],
                                              shape[HALF_SURFACE])
    return hs_coefficient(re, eps, shape[D_P], shape[MU], phi, crosswise, lengthwise)


# --------------------------------------------------------------------------- drag laws (DRAG)
@njit(DRAG, cache=True, inline="always")
def hoelzer_sommerfeld_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """Hoelzer & Sommerfeld (2008) with Di Felice's (1994) voidage function (``hs_coefficient``), the
    sphericities at the particle's incidence for spherocylinders. Any Re; the voidage function eps 0.4-1."""
    speed = slip_speed(sx, sy, sz)
    re = reynolds(speed, eps, shape[D_P], shape[RHO], shape[MU])
    if shape[LENGTH] <= shape[DIAMETER]:
        return hs_coefficient(re, eps, shape[D_P], shape[MU], 1.0, 1.0, 1.0)
    return _hoelzer_sommerfeld_rod(re, eps, incidence(sx, sy, sz, ax, ay, az, speed), shape)


@njit(cache=True, inline="always")
def _sanjeevi_padding_state(sx, sy, sz, eps, ax, ay, az, shape):
    """What Sanjeevi & Padding's three laws share: slip speed, Re and its logarithm, cos^2 of the incidence and F
    at 0 and 90 deg."""
    speed = slip_speed(sx, sy, sz)
    re = reynolds(speed, eps, shape[D_P], shape[RHO], shape[MU])
    c2 = cos2(sx, sy, sz, ax, ay, az, speed)
    ln_re, es = math.log(re), 1.0 - eps
    ln_es = math.log(es)
    return speed, re, ln_re, c2, _sp_drag_logs(re, ln_re, es, ln_es, 0), _sp_drag_logs(re, ln_re, es, ln_es, 1)


@njit(cache=True, inline="always")
def _sin_cos(c2):
    """``sin(phi) cos(phi)`` of the incidence ``phi = arccos(sqrt(cos^2))`` in [0, pi/2] (``incidence``), from
    cos^2 alone: ``sqrt(cos^2 (1 - cos^2))`` (no arccos, sine or cosine)."""
    return math.sqrt(c2 * (1.0 - c2))


@njit(cache=True, inline="always")
def _sanjeevi_padding_drag(eps, c2, f0, f90, shape):
    """Eqs. 15-16: ``c = 3 pi mu d_p eps F_phi``, ``F_phi = F_0 + (F_90 - F_0) sin^2 phi``."""
    return 3 * np.pi * shape[MU] * shape[D_P] * eps * (f0 + (f90 - f0) * (1.0 - c2))


@njit(cache=True, inline="always")
def _sanjeevi_padding_lift(sx, sy, sz, eps, ax, ay, az, speed, sin_cos, f0, f90, shape):
    """Eqs. 25-26: ``F_L = 3 pi mu d_p eps |u| (F_90 - F_0) sin phi cos phi`` along ``lift_direction``
    (``sin_cos = sin phi cos phi``, ``_sin_cos``)."""
    f_l = (f90 - f0) * sin_cos
    magnitude = 3 * np.pi * shape[MU] * shape[D_P] * eps * speed * f_l
    x, y, z = lift_direction(sx, sy, sz, ax, ay, az)
    return x * magnitude, y * magnitude, z * magnitude


@njit(cache=True, inline="always")
def _sanjeevi_padding_torque(sx, sy, sz, eps, ax, ay, az, speed, re, ln_re, sin_cos, shape):
    """Eqs. 30-33, Table 4: ``T = 2 pi mu d_p^2 eps |u| T_P,mag sin phi cos phi`` along ``torque_direction``,
    ``T_P,mag = T_p,isol (1 - eps_s)^2 + Re^a eps_s^b [c (1 - eps_s) + d eps_s^3/(1 - eps_s)] + e eps_s
    (1 - eps_s)^2 Re`` (``isolated_torque_magnitude``); ``ln_re = ln Re``, ``sin_cos = sin phi cos phi``."""
    es = 1.0 - eps
    t_mag = (_isolated_torque_logs(re, ln_re) * (1 - es) ** 2
             + math.exp(SP_TORQUE[0] * ln_re + SP_TORQUE[1] * math.log(es))
             * (SP_TORQUE[2] * (1 - es) + SP_TORQUE[3] * es ** 3 / (1 - es))
             + SP_TORQUE[4] * es * (1 - es) ** 2 * re)
    magnitude = 2 * np.pi * shape[MU] * shape[D_P] ** 2 * eps * speed * t_mag * sin_cos
    x, y, z = torque_direction(sx, sy, sz, ax, ay, az)
    return x * magnitude, y * magnitude, z * magnitude


@njit(DRAG, cache=True, inline="always")
def sanjeevi_padding_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """Sanjeevi & Padding (2020), Eqs. 15-16 (``_sanjeevi_padding_drag``), F at 0 and 90 deg from
    ``sp_drag_at``, phi the angle between axis and slip. Re 0.1-1000, eps_s 0-0.35, AR 4."""
    _, _, _, c2, f0, f90 = _sanjeevi_padding_state(sx, sy, sz, eps, ax, ay, az, shape)
    return _sanjeevi_padding_drag(eps, c2, f0, f90, shape)


@njit(DRAG, cache=True, inline="always")
def gidaspow_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """Gidaspow (``gidaspow_coefficient``) with the spherocylinder's sphericity in Ergun's diameter."""
    speed = slip_speed(sx, sy, sz)
    re = reynolds(speed, eps, shape[D_P], shape[RHO], shape[MU])
    sphericity = shape[PHI] if shape[LENGTH] > shape[DIAMETER] else 1.0
    return gidaspow_coefficient(eps, speed, re, shape[D_P], shape[RHO], shape[MU], sphericity)


@njit(cache=True, inline="always")
def _dense(normalised, sx, sy, sz, eps, ax, ay, az, shape):
    """``c = 3 pi mu d_p eps F(phi, Re)`` of a dense-suspension law for the volume-equivalent sphere, times
    ``non_spherical_factor`` for spherocylinders."""
    speed = slip_speed(sx, sy, sz)
    re = reynolds(speed, eps, shape[D_P], shape[RHO], shape[MU])
    f = normalised(1.0 - eps, re)
    return (3.0 * np.pi * shape[MU] * shape[D_P] * eps * f
            * non_spherical_factor(sx, sy, sz, ax, ay, az, speed, re, shape))


@njit(DRAG, cache=True, inline="always")
def beetstra_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """``beetstra_normalised`` as a coefficient (``_dense``)."""
    return _dense(beetstra_normalised, sx, sy, sz, eps, ax, ay, az, shape)


@njit(DRAG, cache=True, inline="always")
def tenneti_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """``tenneti_normalised`` as a coefficient (``_dense``)."""
    return _dense(tenneti_normalised, sx, sy, sz, eps, ax, ay, az, shape)


@njit(DRAG, cache=True, inline="always")
def tang_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """``tang_normalised`` as a coefficient (``_dense``)."""
    return _dense(tang_normalised, sx, sy, sz, eps, ax, ay, az, shape)


@njit(DRAG, cache=True, inline="always")
def no_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """No drag."""
    return 0.0


# --------------------------------------------------------------------------- lift and torque laws (FORCE)
@njit(cache=True, inline="always")
def _zastawny_state(sx, sy, sz, eps, ax, ay, az, shape):
    """Slip speed, Re and incidence of one particle (what Zastawny's laws and the HS drag share)."""
    speed = slip_speed(sx, sy, sz)
    return speed, reynolds(speed, eps, shape[D_P], shape[RHO], shape[MU]), incidence(sx, sy, sz, ax, ay, az, speed)


@njit(cache=True, inline="always")
def _zastawny_lift(sx, sy, sz, ax, ay, az, speed, re, alpha, shape):
    """``1/2 C_L rho (pi/4) d_p^2 |u|^2`` along ``lift_direction``, ``C_L`` Zastawny's form with b1..b10."""
    magnitude = 0.5 * zastawny(re, alpha, Z_LIFT) * shape[RHO] * np.pi / 4 * shape[D_P] ** 2 * speed ** 2
    x, y, z = lift_direction(sx, sy, sz, ax, ay, az)
    return x * magnitude, y * magnitude, z * magnitude


@njit(cache=True, inline="always")
def _zastawny_torque(sx, sy, sz, ax, ay, az, speed, re, alpha, shape):
    """``1/2 C_T rho (pi/8) d_p^3 |u|^2`` along ``torque_direction``, ``C_T`` Zastawny's form with c1..c10."""
    magnitude = 0.5 * zastawny(re, alpha, Z_TORQUE) * shape[RHO] * np.pi / 8 * shape[D_P] ** 3 * speed ** 2
    x, y, z = torque_direction(sx, sy, sz, ax, ay, az)
    return x * magnitude, y * magnitude, z * magnitude


@njit(FORCE, cache=True, inline="always")
def zastawny_lift(sx, sy, sz, eps, ax, ay, az, shape):
    """Single-particle lift (Mema et al. Eqs. 22-24): ``1/2 C_L rho (pi/4) d_p^2 |u|^2`` along
    ``lift_direction``, ``C_L`` Zastawny's form with Table 3's b1..b10 (AR-4, isolated, Re 0.1-1000)."""
    speed, re, alpha = _zastawny_state(sx, sy, sz, eps, ax, ay, az, shape)
    return _zastawny_lift(sx, sy, sz, ax, ay, az, speed, re, alpha, shape)


@njit(FORCE, cache=True, inline="always")
def zastawny_torque(sx, sy, sz, eps, ax, ay, az, shape):
    """Single-particle torque (Mema et al. Eqs. 27-29): ``1/2 C_T rho (pi/8) d_p^3 |u|^2`` along
    ``torque_direction``, ``C_T`` Zastawny's form with Table 3's c1..c10 (AR-4, isolated, Re 0.1-1000)."""
    speed, re, alpha = _zastawny_state(sx, sy, sz, eps, ax, ay, az, shape)
    return _zastawny_torque(sx, sy, sz, ax, ay, az, speed, re, alpha, shape)


@njit(FORCE, cache=True, inline="always")
def sanjeevi_padding_lift(sx, sy, sz, eps, ax, ay, az, shape):
    """Sanjeevi & Padding (2020) lift (Eqs. 25-26, ``_sanjeevi_padding_lift``; normalised like the drag, on
    the superficial slip; the extracted Eq. 26 shows no eps: identical at eps -> 1). Re 0.1-1000, eps_s
    0-0.35, AR 4."""
    speed, _, _, c2, f0, f90 = _sanjeevi_padding_state(sx, sy, sz, eps, ax, ay, az, shape)
    return _sanjeevi_padding_lift(sx, sy, sz, eps, ax, ay, az, speed, _sin_cos(c2), f0, f90, shape)


@njit(FORCE, cache=True, inline="always")
def sanjeevi_padding_torque(sx, sy, sz, eps, ax, ay, az, shape):
    """Sanjeevi & Padding (2020) torque (Eqs. 30-33, Table 4, ``_sanjeevi_padding_torque``). Re 0.1-1000,
    eps_s 0-0.35, AR 4."""
    speed = slip_speed(sx, sy, sz)
    re = reynolds(speed, eps, shape[D_P], shape[RHO], shape[MU])
    return _sanjeevi_padding_torque(sx, sy, sz, eps, ax, ay, az, speed, re, math.log(re),
                                    _sin_cos(cos2(sx, sy, sz, ax, ay, az, speed)), shape)


@njit(FORCE, cache=True, inline="always")
def no_force(sx, sy, sz, eps, ax, ay, az, shape):
    """No lift or torque."""
    return 0.0, 0.0, 0.0


# --------------------------------------------------------------------------- sets of laws in one evaluation
@njit(cache=True, inline="always")
def sanjeevi_padding_set(sx, sy, sz, eps, ax, ay, az, shape):
    """Sanjeevi & Padding's drag, lift and torque of one particle, their shared state computed once
    (the same pieces as the three laws: the same numbers): ``(c, lift x, y, z, torque x, y, z)``."""
    speed, re, ln_re, c2, f0, f90 = _sanjeevi_padding_state(sx, sy, sz, eps, ax, ay, az, shape)
    sin_cos = _sin_cos(c2)
    lx, ly, lz = _sanjeevi_padding_lift(sx, sy, sz, eps, ax, ay, az, speed, sin_cos, f0, f90, shape)
    tx, ty, tz = _sanjeevi_padding_torque(sx, sy, sz, eps, ax, ay, az, speed, re, ln_re, sin_cos, shape)
    return _sanjeevi_padding_drag(eps, c2, f0, f90, shape), lx, ly, lz, tx, ty, tz


@njit(cache=True, inline="always")
def single_particle_set(sx, sy, sz, eps, ax, ay, az, shape):
    """Hoelzer-Sommerfeld's drag and Zastawny's lift and torque of one spherocylinder, their shared state
    (slip speed, Re, incidence) computed once (the same pieces as the three laws: the same numbers)."""
    speed, re, alpha = _zastawny_state(sx, sy, sz, eps, ax, ay, az, shape)
    lx, ly, lz = _zastawny_lift(sx, sy, sz, ax, ay, az, speed, re, alpha, shape)
    tx, ty, tz = _zastawny_torque(sx, sy, sz, ax, ay, az, speed, re, alpha, shape)
    return _hoelzer_sommerfeld_rod(re, eps, alpha, shape), lx, ly, lz, tx, ty, tz
