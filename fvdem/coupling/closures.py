"""Hydrodynamic closures of Mema et al. (2020) (docs/equations.md §3, Table 1) as pure functions.

Each function takes local, per-particle quantities as numpy arrays (or floats) and returns forces,
coefficients or directions; none keeps state. Notation: ``u`` the slip velocity (gas interstitial
velocity minus particle velocity) [m/s], ``eps`` the local voidage, ``d_p`` the volume-equivalent
diameter [m], ``rho`` and ``mu`` the gas density [kg/m^3] and viscosity [Pa s], ``axis`` the unit
particle axis, ``theta`` / ``phi`` the angle between axis and slip [rad].

Choices on the points docs/equations.md flags as ambiguous (each pinned by a test in
tests/test_closures.py):

- Particle Reynolds number: the *superficial* slip, ``Re = rho d_p eps |u| / mu`` (Di Felice 1994,
  CFDEMcoupling; Sanjeevi & Padding normalise by the superficial velocity too).
- Crosswise and lengthwise sphericities: ``A_perp = (pi/4) d^2 + d L_rod sin(theta)`` and
  ``Phi_par = A_e / (A_p/2 - A_par)``; the extracted forms fail the sphere limit Phi = 1.
- Sanjeevi-Padding Eq. 17: the isolated drag enters as the product ``F_isol (1 - eps_s)^2``, which
  recovers the isolated particle at eps_s -> 0; Eq. 15 is normalised by the Stokes drag on the
  superficial slip, ``F_D = 3 pi mu d_p eps u F``.
- Table 2 lists e = f = 11.12 at 90 degrees; used as extracted.
"""
from __future__ import annotations

import numpy as np

from ..correlations import ergun_beta_per_solids  # noqa: F401  (also fvdem.coupling.closures.ergun_beta_per_solids)


# --------------------------------------------------------------------------- shape
def spherocylinder_shape(diameter, length):
    """Volume-equivalent diameter [m], volume [m^3] and surface [m^2] of a spherocylinder of cylinder
    ``diameter`` and total ``length`` (caps included; ``length == diameter`` is a sphere)."""
    rod = np.asarray(length, float) - diameter
    volume = np.pi / 4 * diameter ** 2 * rod + np.pi / 6 * diameter ** 3
    surface = np.pi * diameter * rod + np.pi * diameter ** 2
    return (6 * volume / np.pi) ** (1 / 3), volume, surface


def sphericities(diameter, length, theta):
    """Sphericity, crosswise and lengthwise sphericity (Hoelzer & Sommerfeld 2008; Mema et al. (2020) Eqs. 12-14)
    of a spherocylinder at angle ``theta`` [rad] between its axis and the slip velocity.

    ``Phi = pi^(1/3) (6 V)^(2/3) / A_p``; ``Phi_perp = A_e / ((pi/4) d^2 + d L_rod sin theta)``;
    ``Phi_par = A_e / (A_p / 2 - ((pi/4) d^2 + d L_rod cos theta))``, ``A_e = (pi/4) d_p^2``.
    All three are 1 for a sphere.
    """
    d_p, volume, surface = spherocylinder_shape(diameter, length)
    rod = np.asarray(length, float) - diameter
    a_e = np.pi / 4 * d_p ** 2
    phi = np.pi ** (1 / 3) * (6 * volume) ** (2 / 3) / surface
    crosswise = a_e / (np.pi / 4 * diameter ** 2 + diameter * rod * np.abs(np.sin(theta)))
    lengthwise = a_e / (surface / 2 - (np.pi / 4 * diameter ** 2 + diameter * rod * np.abs(np.cos(theta))))
    return phi, crosswise, lengthwise


# --------------------------------------------------------------------------- single-particle drag
def hoelzer_sommerfeld_cd(reynolds, phi, crosswise, lengthwise):
    """Drag coefficient of an isolated non-spherical particle (Hoelzer & Sommerfeld 2008; Eq. 11):
    ``8/(Re sqrt(Phi_par)) + 16/(Re sqrt(Phi)) + 3/(sqrt(Re) Phi^(3/4)) + 0.42 10^(0.4 (-log Phi)^0.2) / Phi_perp``.
    For a sphere: 24/Re + 3/sqrt(Re) + 0.42. Valid for Re up to ~1e5 and 0.09 < Phi <= 1."""
    re = np.asarray(reynolds, float)
    return (8.0 / (re * np.sqrt(lengthwise)) + 16.0 / (re * np.sqrt(phi)) + 3.0 / (np.sqrt(re) * phi ** 0.75)
            + 0.42 * 10.0 ** (0.4 * np.maximum(-np.log10(phi), 0.0) ** 0.2) / crosswise)  # Phi > 1 by round-off


def di_felice_exponent(reynolds):
    """Voidage exponent of Di Felice (1994): ``chi = 3.7 - 0.65 exp(-(1.5 - log10 Re)^2 / 2)`` (Eq. 10)."""
    return 3.7 - 0.65 * np.exp(-(1.5 - np.log10(reynolds)) ** 2 / 2.0)


def slip_reynolds(slip_speed, voidage, d_p, rho, mu):
    """Particle Reynolds number on the superficial slip: ``rho d_p eps |u| / mu`` (flagged choice)."""
    return rho * d_p * voidage * slip_speed / mu


def _slip_state(slip, voidage, d_p, rho, mu):
    """Slip vectors (N, 3), their magnitudes and the slip Reynolds numbers (floored at 1e-12 so that
    a particle at rest in the gas gives finite coefficients and zero force)."""
    slip = np.atleast_2d(slip)
    speed = np.linalg.norm(slip, axis=1)
    return slip, speed, np.maximum(slip_reynolds(speed, voidage, d_p, rho, mu), 1e-12)


def single_particle_drag_coefficient(slip, voidage, d_p, rho, mu, phi=1.0, crosswise=1.0, lengthwise=1.0):
    """Drag coefficient ``c`` [kg/s] (N,) with ``F = c u`` of Hoelzer-Sommerfeld with Di Felice's
    voidage function (Eq. 9): ``c = 1/2 C_D rho eps^(2 - chi) (pi/4) d_p^2 |u|`` with C_D and chi at the
    superficial Re. Spheres: ``phi = crosswise = lengthwise = 1``. Finite at zero slip (Stokes limit
    ``3 pi mu d_p eps^(3 - chi)``)."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    cd_re = hoelzer_sommerfeld_cd(re, phi, crosswise, lengthwise) * re  # C_D Re stays finite as Re -> 0
    return 0.5 * cd_re * mu / (d_p * voidage) * voidage ** (2.0 - di_felice_exponent(re)) * np.pi / 4 * d_p ** 2


def single_particle_drag(slip, voidage, d_p, rho, mu, phi=1.0, crosswise=1.0, lengthwise=1.0):
    """Drag force [N] (N, 3): ``single_particle_drag_coefficient`` times the slip (Eq. 9)."""
    slip = np.atleast_2d(slip)
    return single_particle_drag_coefficient(slip, voidage, d_p, rho, mu, phi, crosswise, lengthwise)[:, None] * slip


# --------------------------------------------------------------------------- Gidaspow (Ergun / Wen-Yu)
GIDASPOW_SWITCH = 0.8  # voidage below which Ergun applies, above it Wen-Yu (Gidaspow 1994)


def gidaspow_drag_coefficient(slip, voidage, d_p, rho, mu, sphericity=1.0):
    """Drag coefficient ``c`` [kg/s] (N,) with ``F = c u`` of Gidaspow (1994), as in MFiX's GIDASPOW and
    CFDEMcoupling's GidaspowDrag: not one of Mema et al.'s closures, an alternative for dense beds.

    Written as the two-fluid interphase coefficient ``beta`` [kg/(m^3 s)] per particle,
    ``c = beta V_p / eps_s``:

    - ``eps < 0.8``, Ergun (1952): ``beta = 150 eps_s^2 mu / (eps (Phi d_p)^2) + 1.75 eps_s rho |u| / (Phi d_p)``.
      In model A (``-eps grad p`` in the gas) a uniform fixed bed then has exactly Ergun's pressure gradient
      ``150 eps_s^2 mu U / (eps^3 (Phi d_p)^2) + 1.75 eps_s rho U^2 / (eps^3 Phi d_p)``, ``U = eps |u|``.
      ``Phi`` is the sphericity (1 for spheres; Ergun's equivalent diameter ``Phi d_p`` for other shapes).
    - ``eps >= 0.8``, Wen & Yu (1966): ``beta = 3/4 C_D eps eps_s rho |u| eps^(-2.65) / d_p`` with Schiller-
      Naumann's ``C_D = 24/Re_s (1 + 0.15 Re_s^0.687)`` (0.44 above Re_s = 1000) on the superficial slip
      ``Re_s = rho d_p eps |u| / mu``; at ``eps -> 1`` the isolated sphere's drag ``1/2 C_D rho (pi/4) d_p^2 |u| u``.

    The switch at 0.8 is discontinuous (a jump of about a factor 2 at moderate Re), as in the original.
    """
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    eps = np.broadcast_to(np.asarray(voidage, float), speed.shape)
    volume = np.pi / 6.0 * d_p ** 3
    ergun_per_solids = ergun_beta_per_solids(eps, speed, sphericity * d_p, rho, mu)
    cd_re = np.where(re < 1000.0, 24.0 * (1.0 + 0.15 * re ** 0.687), 0.44 * re)  # C_D Re_s, finite at Re -> 0
    wen_yu_per_solids = 0.75 * cd_re * mu / d_p ** 2 * eps ** -2.65  # 3/4 C_D eps rho |u| / d_p = 3/4 C_D Re_s mu / d_p^2
    return volume * np.where(eps < GIDASPOW_SWITCH, ergun_per_solids, wen_yu_per_solids)


# --------------------------------------------------------------------------- dense-suspension drag (particle-resolved fits)
# Laws fitted to particle-resolved simulations of fixed random arrays of spheres, in one normalisation:
# ``F = F_D / (3 pi mu d_p U)``, the drag (the fluid-particle force less the share ``-V_p grad p`` of the
# mean pressure gradient: model A's drag) over the Stokes drag at the superficial slip ``U = eps |u|``,
# as a function of the solids fraction ``phi = 1 - eps`` and ``Re = rho d_p U / mu``. The particle's
# coefficient is then ``c = 3 pi mu d_p eps F`` [kg/s] with ``F_D = c u``. A fit that reports the total
# force ``F_tot`` (pressure share included) converts by ``F = eps F_tot`` (in a fixed bed
# ``-grad p = n F_tot`` and ``F_tot = F_D + phi F_tot / n n``).

_RANGE_WARNED: set = set()


def reset_range_warnings() -> None:
    """Forget which out-of-range uses were warned about (each is warned once per process)."""
    _RANGE_WARNED.clear()


def warn_outside_range(name: str, reynolds, solids, re_range, solids_range) -> None:
    """Warn once per law and bound when a law is evaluated outside the (Re, phi) range it was fitted on,
    with the range and the extreme value met."""
    import warnings
    re, phi = np.asarray(reynolds, float), np.asarray(solids, float)
    if not re.size:
        return
    for quantity, values, (low, high) in (("Re", re, re_range), ("solids fraction", phi, solids_range)):
        for bound, limit, extreme, outside in (("below", low, values.min(), values.min() < low),
                                               ("above", high, values.max(), values.max() > high)):
            key = (name, quantity, bound)
            if outside and key not in _RANGE_WARNED:
                _RANGE_WARNED.add(key)
                warnings.warn(f"drag law {name!r} used at {quantity} {extreme:.3g}, {bound} its fitted range "
                              f"{low:g}-{high:g} (further uses outside it are not warned)", RuntimeWarning,
                              stacklevel=4)


def dense_drag_coefficient(normalised, slip, voidage, d_p, rho, mu):
    """``c = 3 pi mu d_p eps F(phi, Re)`` [kg/s] (N,) of a dense-suspension law ``normalised(phi, Re)``
    (the normalisation above) at the interstitial slip ``slip`` (N, 3) [m/s]. Finite at zero slip."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    eps = np.broadcast_to(np.asarray(voidage, float), speed.shape)
    return 3.0 * np.pi * mu * d_p * eps * normalised(1.0 - eps, re)


def non_spherical_factor(particle, slip, voidage, axis):
    """Shape correction of a sphere law for spherocylinders: the ratio of the isolated non-spherical
    drag coefficient at the particle's incidence to the isolated sphere's at the same Re (Hoelzer &
    Sommerfeld 2008, Eq. 11 with the sphericities of Eqs. 12-14), ``C_D(Re, Phi, Phi_perp, Phi_par) /
    C_D(Re, 1, 1, 1)``; the sphere law is evaluated for the volume-equivalent sphere and multiplied by
    it. 1 for spheres, and tends to 1 as l/d -> 1. An assumption (the crowding of rods is taken as the
    sphere's), not a fit to rod arrays."""
    slip, speed, re = _slip_state(slip, voidage, particle.equivalent_diameter, particle.density, particle.viscosity)
    if particle.is_sphere:
        return np.ones(len(speed))
    phi, crosswise, lengthwise = sphericities(particle.diameter, particle.length, incidence_angle(axis, slip))
    return hoelzer_sommerfeld_cd(re, phi, crosswise, lengthwise) / hoelzer_sommerfeld_cd(re, 1.0, 1.0, 1.0)


def beetstra_normalised(solids, reynolds):
    """Beetstra, van der Hoef & Kuipers (2007), AIChE J. 53, 489, Eq. 15 (lattice-Boltzmann, random
    arrays of monodisperse spheres), in the normalisation above::

        F = 10 phi / eps^2 + eps^2 (1 + 1.5 sqrt(phi))
            + 0.413 Re / (24 eps^2) (1/eps + 3 phi eps + 8.4 Re^-0.343) / (1 + 10^(3 phi) Re^(-(1 + 4 phi)/2))

    Fitted for 0.1 <= phi <= 0.6 and Re <= 1000. At phi -> 0 it tends to 1 + 0.413 Re/24 (1 + 8.4
    Re^-0.343) / (1 + Re^-0.5), its own single-sphere fit: Stokes' 1 at Re -> 0, within 6 % of
    Schiller-Naumann up to Re = 10 but 16 % above it at Re = 100 and 69 % at Re = 1000 (tests)."""
    phi, re = np.asarray(solids, float), np.asarray(reynolds, float)
    eps = 1.0 - phi
    low = 10.0 * phi / eps ** 2 + eps ** 2 * (1.0 + 1.5 * np.sqrt(phi))
    inertial = (0.413 * re / (24.0 * eps ** 2) * (1.0 / eps + 3.0 * phi * eps + 8.4 * re ** -0.343)
                / (1.0 + 10.0 ** (3.0 * phi) * re ** (-(1.0 + 4.0 * phi) / 2.0)))
    return low + inertial


# --------------------------------------------------------------------------- multi-particle (Sanjeevi & Padding 2020)
SANJEEVI_PADDING_DRAG = {  # Table 2: (phi = 0 deg, phi = 90 deg)
    "a": (2.0, 3.0), "b": (11.3, 17.2), "c": (0.69, 0.79), "d": (0.77, 3.0), "e": (0.42, 11.12),
    "f": (4.84, 11.12), "g": (0.0, 0.57),
    "a1": (24.48, 31.89), "a2": (3.965, 5.519), "a3": (0.41, 0.229), "a4": (0.0005, 0.0032), "a5": (0.15, 1.089),
}
SANJEEVI_PADDING_TORQUE = {"a": 0.82, "b": 1.44, "c": 1.07, "d": 5.48, "e": 0.223}  # Table 4


def sanjeevi_padding_drag_at(reynolds, solids, column):
    """Normalised drag ``F(Re, eps_s)`` at incidence 0 deg (``column = 0``) or 90 deg (``column = 1``)
    (Eqs. 17-21): ``F_isol (1 - eps_s)^2 + F_eps + F_Re,eps`` with ``F_isol = C_d,isol Re / 24``."""
    k = {name: values[column] for name, values in SANJEEVI_PADDING_DRAG.items()}
    re = np.asarray(reynolds, float)
    es = np.asarray(solids, float)
    cd_isol = (k["a1"] / re + k["a2"] / re ** k["a3"]) * np.exp(-k["a4"] * re) + k["a5"] * (1 - np.exp(-k["a4"] * re))
    f_isol = cd_isol * re / 24.0
    f_eps = k["a"] * np.sqrt(es) / (1 - es) ** 2 + k["b"] * es / (1 - es) ** 2
    f_re_eps = re ** k["c"] * es ** k["d"] * (k["e"] * (1 - es) + k["f"] * es ** 3 / (1 - es)) + k["g"] * es * (1 - es) ** 2 * re
    return f_isol * (1 - es) ** 2 + f_eps + f_re_eps


def multi_particle_drag_coefficient(slip, voidage, axis, d_p, rho, mu):
    """Drag coefficient ``c`` [kg/s] (N,) with ``F = c u`` of Sanjeevi & Padding 2020 (Eqs. 15-16):
    ``c = 3 pi mu d_p eps F_phi``, ``F_phi = F_0 + (F_90 - F_0) sin^2 phi``, phi the angle between
    axis and slip."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    solids = 1.0 - voidage
    cos2 = _cos2(axis, slip, speed)
    f0 = sanjeevi_padding_drag_at(re, solids, 0)
    f90 = sanjeevi_padding_drag_at(re, solids, 1)
    f_phi = f0 + (f90 - f0) * (1.0 - cos2)
    return 3 * np.pi * mu * d_p * voidage * f_phi


def multi_particle_drag(slip, voidage, axis, d_p, rho, mu):
    """Drag force [N] (N, 3): ``multi_particle_drag_coefficient`` times the slip."""
    slip = np.atleast_2d(slip)
    return multi_particle_drag_coefficient(slip, voidage, axis, d_p, rho, mu)[:, None] * slip


def _cos2(axis, slip, speed):
    axis = np.atleast_2d(axis)
    c = np.einsum("ij,ij->i", axis, slip) / np.maximum(speed, 1e-300)
    return np.clip(c * c, 0.0, 1.0)


# --------------------------------------------------------------------------- lift and torque directions
def lift_direction(axis, slip):
    """Unit lift direction (Eq. 23): ``sign(a.u) ((a x u) x u) / |(a x u) x u|``; zero where the axis is
    parallel or perpendicular to the slip. Unchanged when the axis is reversed."""
    axis, slip = np.atleast_2d(axis), np.atleast_2d(slip)
    au = np.einsum("ij,ij->i", axis, slip)
    v = np.cross(np.cross(axis, slip), slip)
    norm = np.linalg.norm(v, axis=1)
    out = np.zeros_like(v)
    ok = (norm > 1e-300) & (au != 0)
    out[ok] = np.sign(au[ok])[:, None] * v[ok] / norm[ok, None]
    return out


def torque_direction(axis, slip):
    """Unit torque direction (Eq. 28): ``sign(u.a) (u x a) / |u x a|``; unchanged when the axis is reversed."""
    axis, slip = np.atleast_2d(axis), np.atleast_2d(slip)
    ua = np.einsum("ij,ij->i", slip, axis)
    v = np.cross(slip, axis)
    norm = np.linalg.norm(v, axis=1)
    out = np.zeros_like(v)
    ok = (norm > 1e-300) & (ua != 0)
    out[ok] = np.sign(ua[ok])[:, None] * v[ok] / norm[ok, None]
    return out


# --------------------------------------------------------------------------- lift and torque magnitudes
ZASTAWNY_LIFT = (1.884, 0.1324, 0.001668, -0.8159, 0.8562, 0.003624, 0.6598, -0.2621, 0.8021, 0.04384)  # b1..b10
ZASTAWNY_TORQUE = (-2.283, -0.01145, 4.09, -0.01395, 0.3406, 0.3609, 0.1355, 0.2356, 0.3612, 0.1358)  # c1..c10


def incidence_angle(axis, slip):
    """Angle between the particle axis and the slip, folded into [0, pi/2] [rad]."""
    axis, slip = np.atleast_2d(axis), np.atleast_2d(slip)
    speed = np.linalg.norm(slip, axis=1)
    return np.arccos(np.sqrt(_cos2(axis, slip, speed)))


def zastawny_coefficient(reynolds, alpha, k):
    """Zastawny et al. (2012) form (Eq. 24; Table 3 for AR-4 spherocylinders):
    ``(k1/Re^k2 + k3/Re^k4) sin(alpha)^(k5 + k6 Re^k7) cos(alpha)^(k8 + k9 Re^k10)``."""
    re = np.asarray(reynolds, float)
    return ((k[0] / re ** k[1] + k[2] / re ** k[3]) * np.sin(alpha) ** (k[4] + k[5] * re ** k[6])
            * np.cos(alpha) ** (k[7] + k[8] * re ** k[9]))


def single_particle_lift(slip, voidage, axis, d_p, rho, mu):
    """Lift force [N] (Eqs. 22-24): ``1/2 C_L rho (pi/4) d_p^2 |u|^2`` along ``lift_direction``."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    cl = zastawny_coefficient(re, incidence_angle(axis, slip), ZASTAWNY_LIFT)
    return (0.5 * cl * rho * np.pi / 4 * d_p ** 2 * speed ** 2)[:, None] * lift_direction(axis, slip)


def single_particle_torque(slip, voidage, axis, d_p, rho, mu):
    """Hydrodynamic torque [N m] (Eqs. 27-29): ``1/2 C_T rho (pi/8) d_p^3 |u|^2`` along ``torque_direction``."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    ct = zastawny_coefficient(re, incidence_angle(axis, slip), ZASTAWNY_TORQUE)
    return (0.5 * ct * rho * np.pi / 8 * d_p ** 3 * speed ** 2)[:, None] * torque_direction(axis, slip)


def multi_particle_lift(slip, voidage, axis, d_p, rho, mu):
    """Lift force [N] of Sanjeevi & Padding 2020 (Eqs. 25-26): ``F_L,phi = (F_90 - F_0) sin phi cos phi``,
    ``F_L = 3 pi mu d_p eps |u| F_L,phi`` along ``lift_direction`` (normalised like the drag, on the
    superficial slip; the extracted Eq. 26 shows no eps: identical at eps -> 1)."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    solids = 1.0 - voidage
    phi = incidence_angle(axis, slip)
    f_l = (sanjeevi_padding_drag_at(re, solids, 1) - sanjeevi_padding_drag_at(re, solids, 0)) * np.sin(phi) * np.cos(phi)
    return (3 * np.pi * mu * d_p * voidage * speed * f_l)[:, None] * lift_direction(axis, slip)


def isolated_torque_magnitude(reynolds):
    """``T_p,isol(Re)``, not given in Mema et al. (2020) (flagged): matching Eq. 30 to Eq. 27 at eps_s -> 0 gives
    ``T_P,phi = C_T Re / 32``; with the sin phi cos phi dependence taken out at 45 degrees:
    ``T_p,isol = C_T,45(Re) Re / (32 sin 45 cos 45) = C_T,45 Re / 16``."""
    return zastawny_coefficient(reynolds, np.pi / 4, ZASTAWNY_TORQUE) * np.asarray(reynolds, float) / 16.0


def multi_particle_torque(slip, voidage, axis, d_p, rho, mu):
    """Torque [N m] of Sanjeevi & Padding 2020 (Eqs. 30-33, Table 4):
    ``T = 2 pi mu d_p^2 eps |u| T_P,phi``, ``T_P,phi = T_P,mag sin phi cos phi``,
    ``T_P,mag = T_p,isol (1 - eps_s)^2 + Re^a eps_s^b [c (1 - eps_s) + d eps_s^3/(1 - eps_s)] + e eps_s (1 - eps_s)^2 Re``."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    es = 1.0 - np.asarray(voidage, float)
    k = SANJEEVI_PADDING_TORQUE
    t_mag = (isolated_torque_magnitude(re) * (1 - es) ** 2
             + re ** k["a"] * es ** k["b"] * (k["c"] * (1 - es) + k["d"] * es ** 3 / (1 - es))
             + k["e"] * es * (1 - es) ** 2 * re)
    phi = incidence_angle(axis, slip)
    magnitude = 2 * np.pi * mu * d_p ** 2 * voidage * speed * t_mag * np.sin(phi) * np.cos(phi)
    return magnitude[:, None] * torque_direction(axis, slip)


# --------------------------------------------------------------------------- registry
# A law is one function ``law(particle, slip, voidage, axis)`` of a ``ParticleShape`` and per-particle
# arrays, returning the drag coefficient c [kg/s] (N,) with F_D = c * slip, or a lift force [N] /
# hydrodynamic torque [N m] (N, 3); plus one registration with its name, the shapes it is for, the
# aspect ratio its coefficients were fitted for (None: any), its validity and its reference. The case
# checks, ``fvdem schema`` and the bridge read ``LAWS``; adding a law touches this module and its test.
from dataclasses import dataclass  # noqa: E402


@dataclass(frozen=True)
class ParticleShape:
    """What a law needs of the particles and the fluid: cylinder ``diameter`` and total ``length`` [m]
    (length = diameter for spheres), fluid ``density`` [kg/m^3] and ``viscosity`` [Pa s]."""

    diameter: float
    length: float
    density: float
    viscosity: float

    @property
    def equivalent_diameter(self) -> float:
        return float(spherocylinder_shape(self.diameter, self.length)[0])

    @property
    def is_sphere(self) -> bool:
        return self.length <= self.diameter

    @property
    def kernel_args(self) -> np.ndarray:
        """``(diameter, length, d_p, rho, mu)``: what the compiled kernels (``kernels.py``) read."""
        return np.array([self.diameter, self.length, self.equivalent_diameter, self.density, self.viscosity])


def kernel_inputs(slip, voidage, axis):
    """Slip (N, 3), voidage (N,) and axes (N, 3) as the contiguous float arrays the kernels take
    (a scalar voidage or a single axis broadcast to every particle)."""
    slip = np.ascontiguousarray(np.atleast_2d(slip), dtype=float)
    n = len(slip)
    voidage = np.ascontiguousarray(np.broadcast_to(np.asarray(voidage, float), (n,)))
    axis = np.ascontiguousarray(np.broadcast_to(np.asarray(axis, float), (n, 3)))
    return slip, voidage, axis


@dataclass(frozen=True)
class Law:
    kind: str  # "drag", "lift" or "torque"
    name: str
    function: object
    shapes: tuple  # particle shapes it applies to
    aspect_ratio: float | None  # the aspect ratio its coefficients were fitted for (None: any)
    validity: str
    reference: str
    summary: str
    re_range: tuple | None = None  # (low, high) superficial Re it was fitted on, where stated
    solids_range: tuple | None = None  # (low, high) solids fraction
    kernel: str | None = None  # its compiled form: a function of ``kernels.py`` (None: numpy only)

    def evaluate(self, particle: "ParticleShape", slip, voidage, axis):
        """The law at the particles: its compiled kernel when it has one (the bridge's path), else
        ``function`` (the numpy reference; tests/test_kernels.py holds them equal to 1e-12)."""
        if self.kernel is None:
            return self.function(particle, slip, voidage, axis)
        from . import kernels
        slip, voidage, axis = kernel_inputs(slip, voidage, axis)
        n = len(slip)
        shape = particle.kernel_args
        out = np.empty(n) if self.kind == "drag" else np.empty((n, 3))
        getattr(kernels, self.kernel)(slip, voidage, axis, shape, out)
        if (self.re_range is not None or self.solids_range is not None) and n:
            reynolds = kernels.slip_reynolds(slip, voidage, shape, np.empty(n))
            warn_outside_range(self.name, reynolds, 1.0 - voidage, self.re_range or (-np.inf, np.inf),
                               self.solids_range or (-np.inf, np.inf))
        return out

    def outside(self, reynolds: float, solids: float) -> list:
        """What of (Re, solids fraction) lies outside the fitted ranges, in words (empty: inside)."""
        out = []
        for quantity, value, bounds in (("Re", reynolds, self.re_range), ("solids fraction", solids, self.solids_range)):
            if bounds is not None and not bounds[0] <= value <= bounds[1]:
                out.append(f"{quantity} {value:.3g} outside {bounds[0]:g}-{bounds[1]:g}")
        return out


LAWS: dict[str, dict[str, Law]] = {"drag": {}, "lift": {}, "torque": {}}


def register(kind, name, *, shapes=("sphere", "spherocylinder"), aspect_ratio=None, validity="", reference="",
             summary="", re_range=None, solids_range=None, kernel=None):
    """Decorator: register ``function`` as the ``kind`` law ``name``; ``kernel`` names its compiled
    form in ``kernels.py`` (optional: without one the numpy function runs)."""
    def decorate(function):
        LAWS[kind][name] = Law(kind, name, function, tuple(shapes), aspect_ratio, validity, reference, summary,
                               re_range, solids_range, kernel)
        return function
    return decorate


# Fused kernels: a (drag, lift, torque) set evaluated in one pass over the particles (``kernels.py``),
# used by the bridge instead of the three kernels one by one when the case chooses that set.
FUSED: dict[tuple, str] = {}


def register_fused(drag: str, lift: str, torque: str, kernel: str) -> None:
    """Register ``kernel(slip, voidage, axis, shape, c, lift, torque)`` of ``kernels.py`` for the set."""
    FUSED[(drag, lift, torque)] = kernel


def evaluate_set(particle: "ParticleShape", drag: str, lift: str, torque: str, slip, voidage, axis):
    """Drag coefficient, lift and torque (None where the law is 'none') of a set of laws: one fused
    kernel when the set has one, else each law's ``Law.evaluate``."""
    fused = FUSED.get((drag, lift, torque))
    if fused is None:
        return (law("drag", drag).evaluate(particle, slip, voidage, axis),
                law("lift", lift).evaluate(particle, slip, voidage, axis),
                law("torque", torque).evaluate(particle, slip, voidage, axis))
    from . import kernels
    slip, voidage, axis = kernel_inputs(slip, voidage, axis)
    n = len(slip)
    return getattr(kernels, fused)(slip, voidage, axis, particle.kernel_args, np.empty(n), np.empty((n, 3)),
                                   np.empty((n, 3)))


def law(kind: str, name: str) -> Law:
    try:
        return LAWS[kind][name]
    except KeyError:
        raise ValueError(f"no {kind} law {name!r}; registered: {', '.join(LAWS[kind])}") from None


def law_names(kind: str) -> tuple:
    return tuple(LAWS[kind])


def describe_laws(kind: str) -> str:
    """One line per registered law, for the case reference and ``fvdem schema``."""
    return "; ".join(f"'{n}': {l.summary}" for n, l in LAWS[kind].items())


@register("drag", "hoelzer-sommerfeld", validity="any Re; the voidage function is Di Felice's (eps 0.4-1)",
          reference="Hoelzer & Sommerfeld (2008), Powder Technol. 184; Di Felice (1994), Int. J. Multiph. Flow 20",
          summary="Hoelzer-Sommerfeld with Di Felice's voidage function (single-particle, any shape)",
          kernel="hoelzer_sommerfeld_drag")
def _hoelzer_sommerfeld(particle, slip, voidage, axis):
    args = (slip, voidage, particle.equivalent_diameter, particle.density, particle.viscosity)
    if particle.is_sphere:
        return single_particle_drag_coefficient(*args)
    phi, crosswise, lengthwise = sphericities(particle.diameter, particle.length, incidence_angle(axis, slip))
    return single_particle_drag_coefficient(*args, phi, crosswise, lengthwise)


@register("drag", "sanjeevi-padding", shapes=("spherocylinder",), aspect_ratio=4.0,
          validity="Re 0.1-1000, solids fraction 0-0.35 (fitted), aspect ratio 4",
          reference="Sanjeevi & Padding (2020), AIChE J. 66; Mema et al. (2020) Table 2",
          summary="Sanjeevi-Padding 2020 (multi-particle, AR-4 spherocylinders)", kernel="sanjeevi_padding_drag")
def _sanjeevi_padding_drag(particle, slip, voidage, axis):
    return multi_particle_drag_coefficient(slip, voidage, axis, particle.equivalent_diameter, particle.density,
                                           particle.viscosity)


@register("drag", "gidaspow", validity="Ergun below voidage 0.8, Wen-Yu above (Re < 1000 in the Schiller-Naumann term)",
          reference="Gidaspow (1994), Multiphase Flow and Fluidization; Ergun (1952); Wen & Yu (1966)",
          summary="Gidaspow (Ergun below voidage 0.8 with the sphericity, Wen-Yu above; not a Mema et al. (2020) closure: "
                  "it reproduces Ergun's packed-bed pressure drop, docs/validation.md)", kernel="gidaspow_drag")
def _gidaspow(particle, slip, voidage, axis):
    sphericity = 1.0 if particle.is_sphere else float(sphericities(particle.diameter, particle.length, 0.0)[0])
    return gidaspow_drag_coefficient(slip, voidage, particle.equivalent_diameter, particle.density,
                                     particle.viscosity, sphericity)


def tenneti_normalised(solids, reynolds):
    """Tenneti, Garg & Subramaniam (2011), Int. J. Multiph. Flow 37, 1072, Eqs. 9-12 (immersed-boundary
    DNS, random fixed arrays of spheres). Their force includes the pressure share (``F_tot``)::

        F_tot = F_isol / eps^3 + 5.81 phi / eps^3 + 0.48 phi^(1/3) / eps^4 + phi^3 Re (0.95 + 0.61 phi^3 / eps^2)

    with Schiller-Naumann's ``F_isol = 1 + 0.15 Re^0.687``; returned as the drag ``F = eps F_tot``.
    Fitted for 0.1 <= phi <= 0.5 and 0.01 <= Re <= 300; at phi -> 0 it is Schiller-Naumann's isolated sphere."""
    phi, re = np.asarray(solids, float), np.asarray(reynolds, float)
    eps = 1.0 - phi
    total = ((1.0 + 0.15 * re ** 0.687) / eps ** 3 + 5.81 * phi / eps ** 3 + 0.48 * phi ** (1.0 / 3.0) / eps ** 4
             + phi ** 3 * re * (0.95 + 0.61 * phi ** 3 / eps ** 2))
    return eps * total


def tang_normalised(solids, reynolds):
    """Tang, Peters, Kuipers, Kriebitzsch & van der Hoef (2015), AIChE J. 61, 688, Eq. 20 (immersed-
    boundary DNS, random fixed arrays of spheres; Beetstra's creeping-flow terms kept)::

        F = 10 phi / eps^2 + eps^2 (1 + 1.5 sqrt(phi))
            + Re [0.11 phi (1 + phi) - 0.00456 / eps^4 + (0.169 eps + 0.0644 / eps^4) Re^-0.343]

    Fitted for 0.1 <= phi <= 0.6 and 50 <= Re <= 1000. At phi -> 0: 1 + Re (0.2334 Re^-0.343 - 0.00456),
    on Schiller-Naumann's isolated sphere at Re = 1000 but 18-19 % above it at Re = 50-100 (tests)."""
    phi, re = np.asarray(solids, float), np.asarray(reynolds, float)
    eps = 1.0 - phi
    low = 10.0 * phi / eps ** 2 + eps ** 2 * (1.0 + 1.5 * np.sqrt(phi))
    return low + re * (0.11 * phi * (1.0 + phi) - 0.00456 / eps ** 4 + (0.169 * eps + 0.0644 / eps ** 4) * re ** -0.343)


def _dense(name, normalised):
    """The registered form of a dense-suspension law: the sphere law on the volume-equivalent
    diameter, times ``non_spherical_factor`` for spherocylinders, warning once outside its range."""
    def evaluate(particle, slip, voidage, axis):
        d_p = particle.equivalent_diameter
        c = dense_drag_coefficient(normalised, slip, voidage, d_p, particle.density, particle.viscosity)
        speed = np.linalg.norm(np.atleast_2d(slip), axis=1)
        registered = LAWS["drag"][name]
        warn_outside_range(name, slip_reynolds(speed, voidage, d_p, particle.density, particle.viscosity),
                           1.0 - np.broadcast_to(np.asarray(voidage, float), speed.shape), registered.re_range,
                           registered.solids_range)
        return c if particle.is_sphere else c * non_spherical_factor(particle, slip, voidage, axis)
    return evaluate


register("drag", "beetstra", validity="solids fraction 0.1-0.6, Re 0-1000 (superficial); spherocylinders: "
         "times the isolated Hoelzer-Sommerfeld shape ratio",
         reference="Beetstra, van der Hoef & Kuipers (2007), AIChE J. 53, 489-501, Eq. 15",
         summary="Beetstra-van der Hoef-Kuipers 2007 (lattice-Boltzmann random sphere arrays; rods by the "
                 "isolated shape ratio)", re_range=(0.0, 1000.0), solids_range=(0.1, 0.6), kernel="beetstra_drag")(
             _dense("beetstra", beetstra_normalised))


register("drag", "tenneti", validity="solids fraction 0.1-0.5, Re 0.01-300 (superficial); spherocylinders: "
         "times the isolated Hoelzer-Sommerfeld shape ratio",
         reference="Tenneti, Garg & Subramaniam (2011), Int. J. Multiph. Flow 37, 1072-1092, Eqs. 9-12",
         summary="Tenneti-Garg-Subramaniam 2011 (immersed-boundary DNS of random sphere arrays; Schiller-Naumann "
                 "when dilute; rods by the isolated shape ratio)", re_range=(0.0, 300.0), solids_range=(0.0, 0.5),
         kernel="tenneti_drag")(
             _dense("tenneti", tenneti_normalised))


register("drag", "tang", validity="solids fraction 0.1-0.6, Re 50-1000 (superficial); below Re 50 Beetstra's "
         "creeping-flow terms; spherocylinders: times the isolated Hoelzer-Sommerfeld shape ratio",
         reference="Tang, Peters, Kuipers, Kriebitzsch & van der Hoef (2015), AIChE J. 61, 688-698, Eq. 20",
         summary="Tang et al. 2015 (immersed-boundary DNS of random sphere arrays, Re 50-1000; rods by the "
                 "isolated shape ratio)", re_range=(0.0, 1000.0), solids_range=(0.1, 0.6), kernel="tang_drag")(
             _dense("tang", tang_normalised))


@register("drag", "none", summary="no drag")
def _no_drag(particle, slip, voidage, axis):
    return np.zeros(len(slip))


def _oriented(function):
    def evaluate(particle, slip, voidage, axis):
        return function(slip, voidage, axis, particle.equivalent_diameter, particle.density, particle.viscosity)
    return evaluate


for _kind, _single, _multi in (("lift", single_particle_lift, multi_particle_lift),
                               ("torque", single_particle_torque, multi_particle_torque)):
    register(_kind, "none", summary=f"no {_kind}")(lambda particle, slip, voidage, axis: None)
    register(_kind, "zastawny", shapes=("spherocylinder",), aspect_ratio=4.0,
             validity="isolated particle, Re 0.1-1000 (Mema et al. (2020) Table 3, aspect ratio 4)",
             reference="Zastawny et al. (2012), Int. J. Multiph. Flow 39; Mema et al. (2020) Table 3",
             summary="Zastawny form with Mema et al.'s Table 3 (single-particle, AR-4)",
             kernel=f"zastawny_{_kind}")(_oriented(_single))
    register(_kind, "sanjeevi-padding", shapes=("spherocylinder",), aspect_ratio=4.0,
             validity="Re 0.1-1000, solids fraction 0-0.35 (fitted), aspect ratio 4",
             reference="Sanjeevi & Padding (2020), AIChE J. 66",
             summary="Sanjeevi-Padding 2020 (multi-particle, AR-4)", kernel=f"sanjeevi_padding_{_kind}")(_oriented(_multi))

register_fused("sanjeevi-padding", "sanjeevi-padding", "sanjeevi-padding", "sanjeevi_padding_all")
