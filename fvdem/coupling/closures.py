"""Hydrodynamic closures (docs/equations.md §3, Table 1): the registry of drag, lift and torque laws, and
numpy forms of the laws and their pieces.

Every formula is written once, in ``laws.py``: a compiled scalar function of one particle, with its
formula, validity and reference (the flagged choices on the ambiguous points are listed there). Here:

- ``LAWS`` / ``register`` / ``law``: the registry the case checks, ``fvdem schema`` and the bridge read.
  A law is registered with its name, the shapes it is for, the aspect ratio its coefficients were fitted
  for, its validity, reference and fitted (Re, solids fraction) range. ``SETS`` / ``register_set``: a drag,
  lift and torque law evaluated together in one pass where they share work.
- ``Law.evaluate``: a law at N particles through the compiled loop of its kind, which ``law_loops`` writes
  from the registry with every registered law inlined (``fast_loops``), warning once when used outside its
  fitted range; ``Law.reference_values``: the same law's ``py_func`` particle by particle in plain Python,
  what tests/unit/test_kernels.py holds the compiled path to (1e-12). ``evaluate_set``: a drag, lift and torque
  law together (in one pass where a set is registered for them).
- numpy forms (``single_particle_drag_coefficient``, ``multi_particle_lift``, ``sphericities``, ...):
  the scalar functions of ``laws.py`` applied elementwise, for tools, tests and the analysis.

Notation: ``u`` / ``slip`` the slip velocity (gas interstitial velocity minus particle velocity) [m/s],
``eps`` the local voidage, ``d_p`` the volume-equivalent diameter [m], ``rho`` and ``mu`` the gas density
[kg/m^3] and viscosity [Pa s], ``axis`` the unit particle axis, ``theta`` / ``phi`` the angle between axis
and slip [rad].
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..correlations import ergun_beta_per_solids  # noqa: F401  (also fvdem.coupling.closures.ergun_beta_per_solids)
from . import kernels, law_loops, laws
from .coefficients import (GIDASPOW_SWITCH, SANJEEVI_PADDING_DRAG, SANJEEVI_PADDING_TORQUE,  # noqa: F401  (re-exported)
                           Z_LIFT, Z_TORQUE, ZASTAWNY_LIFT, ZASTAWNY_TORQUE)


# --------------------------------------------------------------------------- numpy forms of the pieces
def _elementwise(function, *args, outputs=1):
    """``function`` (a compiled scalar function of ``laws.py``) over broadcast array arguments."""
    return np.vectorize(function, otypes=[float] * outputs)(*args)


def spherocylinder_shape(diameter, length):
    """Volume-equivalent diameter [m], volume [m^3] and surface [m^2] of a spherocylinder of cylinder
    ``diameter`` and total ``length`` (caps included; ``length == diameter`` is a sphere)
    (``laws.shape_constants``)."""
    return _elementwise(lambda d, length: laws.shape_constants(d, length)[5:], diameter, length, outputs=3)


def sphericities(diameter, length, theta):
    """Sphericity, crosswise and lengthwise sphericity at ``theta`` [rad] (``laws.sphericities``)."""
    return _elementwise(lambda d, length, t: laws.sphericities(t, *laws.shape_constants(d, length)[:5]), diameter,
                        length, theta, outputs=3)


def hoelzer_sommerfeld_cd(reynolds, phi, crosswise, lengthwise):
    """C_D of an isolated non-spherical particle (``laws.hs_cd``: Hoelzer & Sommerfeld 2008, Eq. 11)."""
    return _elementwise(laws.hs_cd, reynolds, phi, crosswise, lengthwise)


def di_felice_exponent(reynolds):
    """Di Felice's (1994) voidage exponent chi (``laws.di_felice_exponent``, Eq. 10)."""
    return _elementwise(laws.di_felice_exponent, reynolds)


def slip_reynolds(slip_speed, voidage, d_p, rho, mu):
    """Particle Reynolds number on the superficial slip, ``rho d_p eps |u| / mu``, floored (``laws.reynolds``)."""
    return _elementwise(laws.reynolds, slip_speed, voidage, d_p, rho, mu)


def _slip_state(slip, voidage, d_p, rho, mu):
    """Slip vectors (N, 3), their magnitudes and the (floored) slip Reynolds numbers."""
    slip = np.atleast_2d(slip)
    speed = np.linalg.norm(slip, axis=1)
    return slip, speed, slip_reynolds(speed, voidage, d_p, rho, mu)


def single_particle_drag_coefficient(slip, voidage, d_p, rho, mu, phi=1.0, crosswise=1.0, lengthwise=1.0):
    """Drag coefficient ``c`` [kg/s] (N,) of Hoelzer-Sommerfeld with Di Felice's voidage function
    (``laws.hs_coefficient``, Eq. 9). Spheres: ``phi = crosswise = lengthwise = 1``."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    return _elementwise(laws.hs_coefficient, re, voidage, d_p, mu, phi, crosswise, lengthwise)


def single_particle_drag(slip, voidage, d_p, rho, mu, phi=1.0, crosswise=1.0, lengthwise=1.0):
    """Drag force [N] (N, 3): ``single_particle_drag_coefficient`` times the slip (Eq. 9)."""
    slip = np.atleast_2d(slip)
    return single_particle_drag_coefficient(slip, voidage, d_p, rho, mu, phi, crosswise, lengthwise)[:, None] * slip


def gidaspow_drag_coefficient(slip, voidage, d_p, rho, mu, sphericity=1.0):
    """Drag coefficient ``c`` [kg/s] (N,) of Gidaspow (1994) (``laws.gidaspow_coefficient``: Ergun below
    voidage 0.8 with the sphericity in Ergun's diameter, Wen-Yu above)."""
    slip, speed, re = _slip_state(slip, voidage, d_p, rho, mu)
    return _elementwise(laws.gidaspow_coefficient, voidage, speed, re, d_p, rho, mu, sphericity)


def beetstra_normalised(solids, reynolds):
    """Beetstra, van der Hoef & Kuipers (2007) F(phi, Re) (``laws.beetstra_normalised``)."""
    return _elementwise(laws.beetstra_normalised, solids, reynolds)


def tenneti_normalised(solids, reynolds):
    """Tenneti, Garg & Subramaniam (2011) F = eps F_tot (``laws.tenneti_normalised``)."""
    return _elementwise(laws.tenneti_normalised, solids, reynolds)


def tang_normalised(solids, reynolds):
    """Tang et al. (2015) F(phi, Re) (``laws.tang_normalised``)."""
    return _elementwise(laws.tang_normalised, solids, reynolds)


def sanjeevi_padding_drag_at(reynolds, solids, column):
    """Sanjeevi & Padding's F(Re, eps_s) at incidence 0 deg (``column = 0``) or 90 deg (1) (``laws.sp_drag_at``)."""
    return _elementwise(lambda re, es: laws.sp_drag_at(re, es, column), reynolds, solids)


def zastawny_coefficient(reynolds, alpha, k):
    """Zastawny et al.'s form (``laws.zastawny``) with coefficients ``k`` (b1..b10 or c1..c10)."""
    k = np.asarray(k, float)
    return _elementwise(lambda re, a: laws.zastawny(re, a, k), reynolds, alpha)


def isolated_torque_magnitude(reynolds):
    """``T_p,isol(Re) = C_T,45 Re / 16`` (``laws.isolated_torque_magnitude``; flagged)."""
    return _elementwise(laws.isolated_torque_magnitude, reynolds)


def _cos2(axis, slip, speed):
    axis, slip = np.atleast_2d(axis), np.atleast_2d(slip)
    return _elementwise(laws.cos2, slip[:, 0], slip[:, 1], slip[:, 2], axis[:, 0], axis[:, 1], axis[:, 2], speed)


def incidence_angle(axis, slip):
    """Angle between the particle axis and the slip, folded into [0, pi/2] [rad]."""
    axis, slip = np.atleast_2d(axis), np.atleast_2d(slip)
    return np.arccos(np.sqrt(_cos2(axis, slip, np.linalg.norm(slip, axis=1))))


def _rows(function, axis, slip):
    axis, slip = np.broadcast_arrays(np.atleast_2d(axis), np.atleast_2d(slip))
    return np.array([function(*u, *a) for u, a in zip(slip, axis)], float).reshape(-1, 3)


def lift_direction(axis, slip):
    """Unit lift direction (``laws.lift_direction``, Eq. 23) (N, 3)."""
    return _rows(laws.lift_direction, axis, slip)


def torque_direction(axis, slip):
    """Unit torque direction (``laws.torque_direction``, Eq. 28) (N, 3)."""
    return _rows(laws.torque_direction, axis, slip)


def _fluid_shape(d_p, rho, mu):
    """The shape vector of a law that reads only ``d_p``, ``rho`` and ``mu`` (the oriented laws): a sphere of
    diameter ``d_p``."""
    return laws.shape_vector(float(d_p), float(d_p), float(rho), float(mu))


def _at_particles(registered, slip, voidage, axis, shape):
    """The registered law ``registered`` (a ``Law``) at every particle, by its index through its kind's loop
    (``fast_loops``)."""
    slip, voidage, axis = kernel_inputs(slip, voidage, axis)
    out = np.empty(len(slip)) if registered.kind == "drag" else np.empty((len(slip), 3))
    loops = fast_loops()
    getattr(loops, f"{registered.kind}_loop")(loops.INDEX[registered.kind][registered.name], slip, voidage, axis,
                                              shape, out)
    return out


def multi_particle_drag_coefficient(slip, voidage, axis, d_p, rho, mu):
    """Drag coefficient ``c`` [kg/s] (N,) of Sanjeevi & Padding 2020 (``laws.sanjeevi_padding_drag``)."""
    return _at_particles(law("drag", "sanjeevi-padding"), slip, voidage, axis, _fluid_shape(d_p, rho, mu))


def multi_particle_drag(slip, voidage, axis, d_p, rho, mu):
    """Drag force [N] (N, 3): ``multi_particle_drag_coefficient`` times the slip."""
    slip = np.atleast_2d(slip)
    return multi_particle_drag_coefficient(slip, voidage, axis, d_p, rho, mu)[:, None] * slip


def single_particle_lift(slip, voidage, axis, d_p, rho, mu):
    """Lift force [N] (N, 3) of Zastawny's form (``laws.zastawny_lift``, Eqs. 22-24)."""
    return _at_particles(law("lift", "zastawny"), slip, voidage, axis, _fluid_shape(d_p, rho, mu))


def single_particle_torque(slip, voidage, axis, d_p, rho, mu):
    """Torque [N m] (N, 3) of Zastawny's form (``laws.zastawny_torque``, Eqs. 27-29)."""
    return _at_particles(law("torque", "zastawny"), slip, voidage, axis, _fluid_shape(d_p, rho, mu))


def multi_particle_lift(slip, voidage, axis, d_p, rho, mu):
    """Lift force [N] (N, 3) of Sanjeevi & Padding 2020 (``laws.sanjeevi_padding_lift``, Eqs. 25-26)."""
    return _at_particles(law("lift", "sanjeevi-padding"), slip, voidage, axis, _fluid_shape(d_p, rho, mu))


def multi_particle_torque(slip, voidage, axis, d_p, rho, mu):
    """Torque [N m] (N, 3) of Sanjeevi & Padding 2020 (``laws.sanjeevi_padding_torque``, Eqs. 30-33)."""
    return _at_particles(law("torque", "sanjeevi-padding"), slip, voidage, axis, _fluid_shape(d_p, rho, mu))


def non_spherical_factor(particle, slip, voidage, axis):
    """Shape correction of a sphere law for spherocylinders (``laws.non_spherical_factor``) (N,)."""
    slip, voidage, axis = kernel_inputs(slip, voidage, axis)
    shape = particle.kernel_args
    speed = np.linalg.norm(slip, axis=1)
    re = slip_reynolds(speed, voidage, shape[laws.D_P], shape[laws.RHO], shape[laws.MU])
    return np.array([laws.non_spherical_factor(*u, *a, s, r, shape) for u, a, s, r in zip(slip, axis, speed, re)])


# --------------------------------------------------------------------------- range warnings
_RANGE_WARNED: set = set()


def reset_range_warnings() -> None:
    """Forget which out-of-range uses were warned about (each is warned once per process)."""
    _RANGE_WARNED.clear()


def warn_outside_range(name: str, reynolds, solids, re_range, solids_range) -> None:
    """Warn once per law and bound when a law is evaluated outside the (Re, phi) range it was fitted on,
    with the range and the extreme value met."""
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


# --------------------------------------------------------------------------- registry
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
        return float(laws.shape_constants(float(self.diameter), float(self.length))[5])

    @property
    def is_sphere(self) -> bool:
        return self.length <= self.diameter

    @property
    def kernel_args(self) -> np.ndarray:
        """The shape vector every law reads (``laws.shape_vector``)."""
        return laws.shape_vector(float(self.diameter), float(self.length), float(self.density), float(self.viscosity))


def kernel_inputs(slip, voidage, axis):
    """Slip (N, 3), voidage (N,) and axes (N, 3) as the contiguous float arrays the loops take (a scalar
    voidage or a single axis broadcast to every particle)."""
    flags = ("C_CONTIGUOUS", "WRITEABLE")  # the loops are compiled for these (a copy only where needed)
    slip = np.require(np.atleast_2d(slip), float, flags)
    n = len(slip)
    voidage = np.require(np.broadcast_to(np.asarray(voidage, float), (n,)), float, flags)
    axis = np.require(np.broadcast_to(np.asarray(axis, float), (n, 3)), float, flags)
    return slip, voidage, axis


SIGNATURES = {"drag": laws.DRAG, "lift": laws.FORCE, "torque": laws.FORCE}


@dataclass(frozen=True)
class Law:
    kind: str  # "drag", "lift" or "torque"
    name: str
    scalar: object  # the compiled law of one particle (laws.py), compiled for SIGNATURES[kind]
    shapes: tuple  # particle shapes it applies to
    aspect_ratio: float | None  # the aspect ratio its coefficients were fitted for (None: any)
    validity: str
    reference: str
    summary: str
    re_range: tuple | None = None  # (low, high) superficial Re it was fitted on, where stated
    solids_range: tuple | None = None  # (low, high) solids fraction
    none: bool = False  # the "none" law: evaluates to None (lift, torque) or zeros (drag)

    def evaluate(self, particle: ParticleShape, slip, voidage, axis):
        """The law at the particles, through its kind's compiled loop (the bridge's path): drag
        coefficients [kg/s] (N,), or lift forces [N] / torques [N m] (N, 3); None for a 'none' lift or
        torque. Warns once when used outside its fitted range."""
        if self.none and self.kind != "drag":
            return None
        slip, voidage, axis = kernel_inputs(slip, voidage, axis)
        shape = particle.kernel_args
        out = _at_particles(self, slip, voidage, axis, shape)
        self.warn_if_outside(slip, voidage, shape)
        return out

    def warn_if_outside(self, slip, voidage, shape) -> None:
        if (self.re_range is not None or self.solids_range is not None) and len(slip):
            reynolds = kernels.reynolds_loop(slip, voidage, shape, np.empty(len(slip)))
            warn_outside_range(self.name, reynolds, 1.0 - voidage, self.re_range or (-np.inf, np.inf),
                               self.solids_range or (-np.inf, np.inf))

    def reference_values(self, particle: ParticleShape, slip, voidage, axis):
        """The same law in plain Python (its ``py_func``), particle by particle: the reference the compiled
        path is tested against (``Law.evaluate``'s values and shapes, no range warnings)."""
        if self.none and self.kind != "drag":
            return None
        slip, voidage, axis = kernel_inputs(slip, voidage, axis)
        shape = particle.kernel_args
        values = [self.scalar.py_func(*u, eps, *a, shape) for u, eps, a in zip(slip, voidage, axis)]
        return np.array(values, float).reshape((len(slip),) if self.kind == "drag" else (len(slip), 3))

    def outside(self, reynolds: float, solids: float) -> list:
        """What of (Re, solids fraction) lies outside the fitted ranges, in words (empty: inside)."""
        out = []
        for quantity, value, bounds in (("Re", reynolds, self.re_range), ("solids fraction", solids, self.solids_range)):
            if bounds is not None and not bounds[0] <= value <= bounds[1]:
                out.append(f"{quantity} {value:.3g} outside {bounds[0]:g}-{bounds[1]:g}")
        return out


LAWS: dict[str, dict[str, Law]] = {"drag": {}, "lift": {}, "torque": {}}


def register(kind, name, *, shapes=("sphere", "spherocylinder"), aspect_ratio=None, validity="", reference="",
             summary="", re_range=None, solids_range=None, none=False):
    """Decorator: register ``scalar`` (a law of one particle compiled for ``SIGNATURES[kind]``, e.g.
    ``@numba.njit(laws.DRAG, cache=True)``; see ``laws.py``) as the ``kind`` law ``name``."""
    def decorate(scalar):
        compiled = getattr(scalar, "nopython_signatures", None)
        if not compiled or len(compiled) != 1 or (compiled[0].args, compiled[0].return_type) != (
                SIGNATURES[kind].args, SIGNATURES[kind].return_type):
            raise TypeError(f"{kind} law {name!r}: register a function compiled for the {kind} signature, "
                            f"@numba.njit(fvdem.coupling.laws.{'DRAG' if kind == 'drag' else 'FORCE'}, cache=True) "
                            f"(it has {compiled!r})")
        LAWS[kind][name] = Law(kind, name, scalar, tuple(shapes), aspect_ratio, validity, reference, summary,
                               re_range, solids_range, none)
        return scalar
    return decorate


@dataclass(frozen=True)
class LawSet:
    """A drag, lift and torque law evaluated together: ``function`` returns one particle's ``(c, lift x, y, z,
    torque x, y, z)`` (``laws.sanjeevi_padding_set``), the same numbers as the three laws one by one."""

    laws: tuple  # (drag, lift, torque), the registered Law objects
    function: object
    shapes: tuple

    @property
    def name(self) -> str:
        return "/".join(registered.name for registered in self.laws)


SETS: dict[tuple, LawSet] = {}  # (drag, lift, torque) Law objects -> their set


def register_set(drag: str, lift: str, torque: str, *, shapes=("sphere", "spherocylinder")):
    """Decorator: register ``function`` (compiled, ``@numba.njit(cache=True, inline="always")``, of a particle's
    ``(sx, sy, sz, eps, ax, ay, az, shape)`` returning ``(c, lift x, y, z, torque x, y, z)``) as the set of the
    registered laws ``drag``, ``lift`` and ``torque``, evaluated in one pass for ``shapes``."""
    def decorate(function):
        members = (law("drag", drag), law("lift", lift), law("torque", torque))
        SETS[members] = LawSet(members, function, tuple(shapes))
        return function
    return decorate


def fast_loops():
    """The loops of every registered law and set (``law_loops``: one module per registry, laws inlined by
    index, ``INDEX[kind][name]``), written and imported the first time a registry is used."""
    snapshot = (tuple(LAWS["drag"].values()), tuple(LAWS["lift"].values()), tuple(LAWS["torque"].values()),
                tuple(SETS.values()))
    if _LATEST and _LATEST[0] == snapshot:  # the same objects: compared by identity, about a microsecond
        return _LATEST[1]
    registry = {kind: tuple((name, registered.scalar) for name, registered in LAWS[kind].items())
                for kind in ("drag", "lift", "torque")}
    registry["set"] = tuple((s.name, s.function) for s in SETS.values())
    key = tuple(registry.items())
    if key not in _FAST_LOOPS:
        _FAST_LOOPS[key] = law_loops.build(registry)
    _LATEST[:] = [snapshot, _FAST_LOOPS[key]]
    return _LATEST[1]


_FAST_LOOPS: dict = {}  # registry -> its loops' module
_LATEST: list = []  # the last registry's snapshot and loops


def evaluate_set(particle: ParticleShape, drag: str, lift: str, torque: str, slip, voidage, axis):
    """Drag coefficients, lift and torque (None where the law is 'none') of a set of laws: in one pass over
    the particles where a set is registered for them and the particle's shape (``SETS``: the same numbers as
    the laws one by one), else law by law (``Law.evaluate``)."""
    members = (law("drag", drag), law("lift", lift), law("torque", torque))
    found = SETS.get(members)
    if found is None or ("sphere" if particle.is_sphere else "spherocylinder") not in found.shapes:
        return tuple(registered.evaluate(particle, slip, voidage, axis) for registered in members)
    slip, voidage, axis = kernel_inputs(slip, voidage, axis)
    n, shape = len(slip), particle.kernel_args
    c, lift_out, torque_out = np.empty(n), np.empty((n, 3)), np.empty((n, 3))
    loops = fast_loops()
    loops.set_loop(loops.INDEX["set"][found.name], slip, voidage, axis, shape, c, lift_out, torque_out)
    members[0].warn_if_outside(slip, voidage, shape)
    return c, lift_out, torque_out


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


# --------------------------------------------------------------------------- the registered laws
register("drag", "hoelzer-sommerfeld", validity="any Re; the voidage function is Di Felice's (eps 0.4-1)",
         reference="Hoelzer & Sommerfeld (2008), Powder Technol. 184; Di Felice (1994), Int. J. Multiph. Flow 20",
         summary="Hoelzer-Sommerfeld with Di Felice's voidage function (single-particle, any shape)")(
             laws.hoelzer_sommerfeld_drag)
register("drag", "sanjeevi-padding", shapes=("spherocylinder",), aspect_ratio=4.0,
         validity="Re 0.1-1000, solids fraction 0-0.35 (fitted), aspect ratio 4",
         reference="Sanjeevi & Padding (2020), AIChE J. 66; Mema et al. (2020) Table 2",
         summary="Sanjeevi-Padding 2020 (multi-particle, AR-4 spherocylinders)")(laws.sanjeevi_padding_drag)
register("drag", "gidaspow", validity="Ergun below voidage 0.8, Wen-Yu above (Re < 1000 in the Schiller-Naumann term)",
         reference="Gidaspow (1994), Multiphase Flow and Fluidization; Ergun (1952); Wen & Yu (1966)",
         summary="Gidaspow (Ergun below voidage 0.8 with the sphericity, Wen-Yu above; not a Mema et al. (2020) closure: "
                 "it reproduces Ergun's packed-bed pressure drop, docs/validation.md)")(laws.gidaspow_drag)
register("drag", "beetstra", validity="solids fraction 0.1-0.6, Re 0-1000 (superficial); spherocylinders: "
         "times the isolated Hoelzer-Sommerfeld shape ratio",
         reference="Beetstra, van der Hoef & Kuipers (2007), AIChE J. 53, 489-501, Eq. 15",
         summary="Beetstra-van der Hoef-Kuipers 2007 (lattice-Boltzmann random sphere arrays; rods by the "
                 "isolated shape ratio)", re_range=(0.0, 1000.0), solids_range=(0.1, 0.6))(laws.beetstra_drag)
register("drag", "tenneti", validity="solids fraction 0.1-0.5, Re 0.01-300 (superficial); spherocylinders: "
         "times the isolated Hoelzer-Sommerfeld shape ratio",
         reference="Tenneti, Garg & Subramaniam (2011), Int. J. Multiph. Flow 37, 1072-1092, Eqs. 9-12",
         summary="Tenneti-Garg-Subramaniam 2011 (immersed-boundary DNS of random sphere arrays; Schiller-Naumann "
                 "when dilute; rods by the isolated shape ratio)", re_range=(0.0, 300.0),
         solids_range=(0.0, 0.5))(laws.tenneti_drag)
register("drag", "tang", validity="solids fraction 0.1-0.6, Re 50-1000 (superficial); below Re 50 Beetstra's "
         "creeping-flow terms; spherocylinders: times the isolated Hoelzer-Sommerfeld shape ratio",
         reference="Tang, Peters, Kuipers, Kriebitzsch & van der Hoef (2015), AIChE J. 61, 688-698, Eq. 20",
         summary="Tang et al. 2015 (immersed-boundary DNS of random sphere arrays, Re 50-1000; rods by the "
                 "isolated shape ratio)", re_range=(0.0, 1000.0), solids_range=(0.1, 0.6))(laws.tang_drag)
register("drag", "none", summary="no drag", none=True)(laws.no_drag)

for _kind, _single, _multi in (("lift", laws.zastawny_lift, laws.sanjeevi_padding_lift),
                               ("torque", laws.zastawny_torque, laws.sanjeevi_padding_torque)):
    register(_kind, "none", summary=f"no {_kind}", none=True)(laws.no_force)
    register(_kind, "zastawny", shapes=("spherocylinder",), aspect_ratio=4.0,
             validity="isolated particle, Re 0.1-1000 (Mema et al. (2020) Table 3, aspect ratio 4)",
             reference="Zastawny et al. (2012), Int. J. Multiph. Flow 39; Mema et al. (2020) Table 3",
             summary="Zastawny form with Mema et al.'s Table 3 (single-particle, AR-4)")(_single)
    register(_kind, "sanjeevi-padding", shapes=("spherocylinder",), aspect_ratio=4.0,
             validity="Re 0.1-1000, solids fraction 0-0.35 (fitted), aspect ratio 4",
             reference="Sanjeevi & Padding (2020), AIChE J. 66",
             summary="Sanjeevi-Padding 2020 (multi-particle, AR-4)")(_multi)

# sets of laws that share their work, evaluated in one pass (the same numbers as the laws one by one)
register_set("sanjeevi-padding", "sanjeevi-padding", "sanjeevi-padding", shapes=("spherocylinder",))(
    laws.sanjeevi_padding_set)
register_set("hoelzer-sommerfeld", "zastawny", "zastawny", shapes=("spherocylinder",))(laws.single_particle_set)
