"""Stochastic hydrodynamic force: the drag fluctuation each particle feels from its neighbours, which a
grid of cells a few diameters wide cannot resolve, as a per-particle Ornstein-Uhlenbeck process
(``coupling.stochastic_force``; registered by name in ``MODELS``, ``fvdem laws stochastic_force``).

**Why.** A drag closure gives the *mean* force on a particle at its (filtered) voidage and slip. In a
particle-resolved simulation each particle's force departs from that mean by tens of per cent, along and
across the mean slip, because its neighbours sit differently around it; this neighbour-to-neighbour
variation drives the particles' horizontal velocity fluctuations in a fluidized suspension. An unresolved
CFD-DEM, whose cells are three diameters wide, sees none of it (docs/validation-suspension.md, "Hindered settling of
a periodic suspension": horizontal fluctuations 0.02-0.2 of the settling velocity against 1/3-2/3 in
resolved simulations and experiments). Lattanzi, Tavanashad, Subramaniam & Capecelatro (2022) close the
gap with a stochastic force; ``force-langevin`` is that model's structure.

**The model** (``force-langevin``). Symbols: ``phi = 1 - eps`` the local solids fraction (the drag law's
voidage at the particle); ``W`` the particle's slip (interstitial gas velocity minus particle velocity)
[m/s], ``s = W / |W|``; ``Re = rho d_e eps |W| / mu`` the superficial slip Reynolds number (``laws.reynolds``;
``Re_m`` of Mehrabadi et al.); ``c`` the drag coefficient of the case's drag law [kg/s], ``c |W|`` the
magnitude of the particle's mean drag [N]; ``d_e`` the volume-equivalent diameter [m]; ``Theta`` the
granular temperature [m^2/s^2].

1. Per particle, a dimensionless isotropic Ornstein-Uhlenbeck vector ``xi`` of unit variance per component
   and integral time ``T_F`` (Lattanzi et al. 2022, their "force Langevin" model):
   ``d xi = -xi dt / T_F + sqrt(2 / T_F) dW``.
2. The force, along and across the slip (the anisotropy of the fluctuations about the mean slip):
   ``F'' = k c |W| [ sigma_par (xi . s) s + sigma_perp (xi - (xi . s) s) ]``
   with ``k = coupling.stochastic_scale`` (1: the model as published; any other value is a calibration and
   is reported as one); ``sigma_par`` is further multiplied by ``k_par = coupling.stochastic_along_scale``
   (1 as published): the share of the along-slip fluctuation the grid does not resolve, a calibration (the
   drag law at the particles' interpolated voidage and slip already varies along the slip from particle to
   particle, never across it). Its standard deviation is ``k k_par sigma_par c |W|`` along the slip and
   ``k sigma_perp c |W|`` across it.
3. The normalised standard deviations are the drag law's linear response to the pseudo-turbulent gas
   velocity fluctuations that fixed random sphere assemblies produce in particle-resolved DNS,
   ``sigma_i^2 = <u'_i u'_i> / |W|^2`` (the drag ``c W`` of a velocity ``W + u'``, at fixed ``c``):

   - ``k_f / (|W|^2 / 2) = 2 phi + 2.5 phi (1 - phi)^3 exp(-phi Re^(1/2))`` (``pseudo_turbulent_energy``)
   - ``b_par = a exp(-b phi)``, ``a = 0.523 / (1 + 0.305 exp(-0.114 Re))``, ``b = 3.511 / (1 + 1.801
     exp(-0.005 Re))`` (``streamwise_anisotropy``: ``<u'_par u'_par> = 2 k_f (1/3 + b_par)``, each
     transverse component ``2 k_f (1/3 - b_par / 2)``)
   - hence ``sigma_par^2 = (k_f / (|W|^2/2)) (1/3 + b_par)``, ``sigma_perp^2 = (k_f / (|W|^2/2)) (1/3 -
     b_par / 2)`` (``force_langevin_amplitude``).

   Mehrabadi, Tenneti, Garg & Subramaniam (2015), J. Fluid Mech. 770, 210-246 (PR-DNS of fixed random
   sphere assemblies, fitted for 0.1 <= phi <= 0.5 and 0.01 <= Re_m <= 300). The project holds no copy of
   the paper; the coefficients (2, 2.5, 0.523, 0.305, 0.114, 3.511, 1.801, 0.005) and the split ``2 k_f
   (1/3 + b_par)`` / ``2 k_f (1/3 - b_par/2)`` agree term by term with two independent public
   implementations of the same fit (an OpenFOAM pseudo-turbulent momentum model, "Subramaniam", and a
   Fortran compressible-flow code's "Mehrabadi's terms"), checked 2026-12-07. Lattanzi et al. (2022) fit
   sigma_F directly to the drag variance of such assemblies; that fit could not be consulted, so this
   closure is built from the published pseudo-turbulence instead. Not included: the
   along-slip response's extra factor ``1 + d ln c / d ln |W|`` (1.1-1.4 at Re 3-30) of a drag growing
   faster than linearly with the slip (``c`` is held fixed).
4. The integral time is the mean free time between collisions of the kinetic theory of dense gases
   (Chapman & Cowling; Lattanzi et al. 2022 close ``T_F`` with it):
   ``1 / T_F = 24 phi g_0 sqrt(Theta / pi) / d_e`` (``collision_frequency``), ``g_0 = (1 - phi/2) /
   (1 - phi)^3`` (Carnahan-Starling, ``contact_radial_distribution``), ``Theta`` the granular temperature
   of all particles: a third of the variance of their velocities about the particles' mean velocity (the
   statistically homogeneous suspension's; in a bed with a mean circulation it also counts the
   circulation, overestimating ``Theta`` and shortening ``T_F``). ``Theta = 0`` (particles at rest) gives
   ``T_F = inf``: the fluctuation frozen, as in a fixed bed.
5. Rods: ``d_e``, ``Re`` and the collision time are those of the volume-equivalent sphere, and the
   force is split along and across the slip regardless of the rod's orientation: an assumption (the data
   are for spheres), not a fit to rod suspensions.

**Mean drag kept.** ``F''`` is the particle's departure from the mean drag, so its average over the
particles is zero by definition; each coupling interval the sample mean is removed from the forces (the
particles' sum is zero to round-off), so that a sum of ``N`` random forces cannot push the particle phase
as a whole through the gas and the closure's mean drag stays the mean drag. With ``stochastic_zero_mean =
"cell"`` the mean is removed over the particles whose centres share a grid cell instead (each force then scaled
by ``sqrt(n / (n - 1))`` for the cell's ``n`` particles, so its variance stays the model's; a particle alone in
its cell feels none): the closure already gives each cell its mean drag, and the fluctuation, a sub-grid
effect, then adds no force to a cell's particles as a whole and none (to the deposition's spread) to its gas,
so that it cannot drive the resolved flow. Over the whole box it is the published model's reading; per cell an
assumption of fvdem's (docs/validation-suspension.md, "Velocity fluctuations with a stochastic drag force").

**Time stepping, exact for any step.** The force is held over a coupling interval ``dt`` (one CFD step)
on both sides, like the lift: the particles' DEM kicks add ``F''`` to their external force, and the gas
receives ``-F''`` through the same deposition weights (Eq. 8's ``-sum F / V_cell``), so the mixture's
momentum is conserved exactly. The held value is the process's mean over the interval, ``J = (1/dt)
int xi dt``, drawn jointly with the end value from their exact Gaussian law given the start value ``x``
(``h = dt / T_F``, ``a = exp(-h)``; two standard normals ``n1``, ``n2`` per component):

- ``xi(t + dt) = a x + sqrt(1 - a^2) n1``
- ``J = x (1 - a) / h + C n1 / sqrt(1 - a^2) + sqrt(V - C^2 / (1 - a^2)) n2``
- ``V = Var J = 2 (h - (1 - a) - (1 - a)^2 / 2) / h^2`` (a series below ``h = 1e-3``), ``C = Cov(xi(t +
  dt), J) = (1 - a)^2 / h``

(``interval_moments``), so the impulse a particle receives over an interval is the continuous process's
whatever ``dt / T_F``, and the state keeps variance 1 and autocorrelation ``exp(-t / T_F)``
(tests/verification/test_stochastic.py). The normals come from numpy's PCG64 generator seeded with
``coupling.stochastic_seed``, drawn per particle id (not per row: the DEM re-sorts its rows), and the
generator's state and ``xi`` are saved in checkpoints (``state`` / ``restore``), so a resumed run is
bit-for-bit the uninterrupted one.

**What it does not capture.** The fluctuations' spatial correlation between neighbours (each particle's
process is independent); the dependence of the drag variance on the particles' own motion (the data are
for fixed assemblies; Tavanashad et al. 2021 show freely moving suspensions differ); and anything of the
box-scale concentration waves the grid resolves, which the model leaves to the resolved gas. The
fluctuation level of a periodic suspension also depends on the box size (box-scale waves grow with it);
the model adds the particle-scale part only.
"""
from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numba
import numpy as np
from numba import float64, int64, njit, types, void

from .kernels import column_sums
from .laws import reynolds, slip_speed

# a model's two functions, compiled for these signatures so that one compiled loop runs any model:
AMPLITUDE = types.UniTuple(float64, 2)(float64, float64)  # (phi, Re) -> (sigma_par, sigma_perp) [-]
DECORRELATION = float64(float64, float64, float64)  # (phi, d_e [m], Theta [m^2/s^2]) -> 1 / T_F [1/s]
_ROWS, _VALUES = float64[:, ::1], float64[::1]


# --------------------------------------------------------------------------- the formulas
@njit(cache=True, inline="always")
def pseudo_turbulent_energy(solids, re):
    """Pseudo-turbulent kinetic energy of the gas over the mean slip's, ``k_f / (|W|^2 / 2) = 2 phi + 2.5 phi
    (1 - phi)^3 exp(-phi Re^(1/2))`` (Mehrabadi et al. 2015; fixed random sphere assemblies, 0.1 <= phi <=
    0.5, 0.01 <= Re <= 300; 0 at phi = 0)."""
    return 2.0 * solids + 2.5 * solids * (1.0 - solids) ** 3 * math.exp(-solids * math.sqrt(re))


@njit(cache=True, inline="always")
def streamwise_anisotropy(solids, re):
    """Anisotropy of the pseudo-turbulent Reynolds stress along the mean slip, ``b_par = <u'_par u'_par> /
    (2 k_f) - 1/3 = a exp(-b phi)`` with ``a = 0.523 / (1 + 0.305 exp(-0.114 Re))``, ``b = 3.511 / (1 + 1.801
    exp(-0.005 Re))`` (Mehrabadi et al. 2015; within (0, 0.523], so both stresses stay positive)."""
    a = 0.523 / (1.0 + 0.305 * math.exp(-0.114 * re))
    b = 3.511 / (1.0 + 1.801 * math.exp(-0.005 * re))
    return a * math.exp(-b * solids)


@njit(cache=True, inline="always")
def contact_radial_distribution(solids):
    """Carnahan-Starling radial distribution at contact, ``g_0 = (1 - phi/2) / (1 - phi)^3`` (1 at phi = 0)."""
    return (1.0 - 0.5 * solids) / (1.0 - solids) ** 3


@njit(AMPLITUDE, cache=True)
def force_langevin_amplitude(solids, re):
    """``(sigma_par, sigma_perp)``: the standard deviations of the drag fluctuation along and across the slip
    over the mean drag, ``sigma_par^2 = K (1/3 + b_par)``, ``sigma_perp^2 = K (1/3 - b_par / 2)`` with ``K =
    pseudo_turbulent_energy``, ``b_par = streamwise_anisotropy`` (the module docstring, item 3)."""
    energy = pseudo_turbulent_energy(solids, re)
    anisotropy = streamwise_anisotropy(solids, re)
    return math.sqrt(energy * (1.0 / 3.0 + anisotropy)), math.sqrt(energy * (1.0 / 3.0 - 0.5 * anisotropy))


@njit(DECORRELATION, cache=True)
def collision_frequency(solids, diameter, theta):
    """``1 / T_F`` [1/s]: the collision frequency of a dense gas of hard spheres of diameter ``diameter`` [m] at
    solids fraction ``phi`` and granular temperature ``theta`` [m^2/s^2], ``24 phi g_0 sqrt(theta / pi) /
    d`` (Chapman & Cowling; g_0 Carnahan-Starling); its inverse is the mean free time."""
    return 24.0 * solids * contact_radial_distribution(solids) * math.sqrt(theta / math.pi) / diameter


@njit(cache=True, inline="always")
def interval_moments(h):
    """The exact one-interval law of a unit-variance Ornstein-Uhlenbeck process over ``h = dt / T`` (``h = 0``:
    frozen): ``(a, m, sx, cy, sy)`` with end value ``a x + sx n1`` and interval mean ``m x + cy n1 + sy n2``
    for the start value ``x`` and independent standard normals ``n1``, ``n2``: ``a = exp(-h)``, ``m = (1 -
    a) / h``, ``sx = sqrt(1 - a^2)``, ``cy = C / sx``, ``sy = sqrt(V - cy^2)`` with ``V = 2 (h - (1 - a) - (1 -
    a)^2 / 2) / h^2`` (``2h/3 - h^2/2 + 7h^3/30 - h^4/12`` below ``h = 1e-3``, where the difference loses
    digits) and ``C = (1 - a)^2 / h``."""
    if h <= 0.0:
        return 1.0, 1.0, 0.0, 0.0, 0.0
    b = -math.expm1(-h)
    if h < 1e-3:
        var_mean = h * (2.0 / 3.0 - h * (0.5 - h * (7.0 / 30.0 - h / 12.0)))
    else:
        var_mean = 2.0 * (h - b - 0.5 * b * b) / (h * h)
    sx = math.sqrt(b * (2.0 - b))
    cy = b * b / h / sx
    return math.exp(-h), b / h, sx, cy, math.sqrt(max(var_mean - cy * cy, 0.0))


# --------------------------------------------------------------------------- the loop
@njit(void(types.FunctionType(AMPLITUDE), types.FunctionType(DECORRELATION), int64[::1], _ROWS, _VALUES, _VALUES,
           float64, float64, float64, float64, float64, float64, float64, _ROWS, _ROWS, _ROWS),
      cache=True, parallel=True)
def stochastic_force_loop(amplitude, decorrelation, ids, slip, voidage, drag, diameter, rho, mu, theta, dt, scale,
                          along_scale, state, normals, out):
    """One coupling interval of the stochastic force, per particle (row ``i``, id ``k = ids[i]``): advance
    ``state[k]`` (the unit-variance process ``xi``, rows by particle id) over ``dt`` [s] with the normals
    ``normals[k]`` (6: n1 of the three components, then n2) and write the held force [N] ``out[i] = scale c
    |W| (along_scale sigma_par (J . s) s + sigma_perp (J - (J . s) s))`` (``J`` the interval mean; ``c = drag[i]``
    [kg/s]; ``W = slip[i]`` [m/s]; ``sigma`` of ``amplitude(phi, Re)`` and ``1 / T_F`` of
    ``decorrelation(phi, diameter, theta)``; zero where the slip is zero). Independent rows: race-free."""
    for i in numba.prange(slip.shape[0]):
        k = ids[i]
        eps = voidage[i]
        solids = 1.0 - eps
        speed = slip_speed(slip[i, 0], slip[i, 1], slip[i, 2])
        re = reynolds(speed, eps, diameter, rho, mu)
        sigma_par, sigma_perp = amplitude(solids, re)
        sigma_par *= along_scale
        a, m, sx, cy, sy = interval_moments(dt * decorrelation(solids, diameter, theta))
        j0 = m * state[k, 0] + cy * normals[k, 0] + sy * normals[k, 3]
        j1 = m * state[k, 1] + cy * normals[k, 1] + sy * normals[k, 4]
        j2 = m * state[k, 2] + cy * normals[k, 2] + sy * normals[k, 5]
        for d in range(3):
            state[k, d] = a * state[k, d] + sx * normals[k, d]
        if speed > 0.0:
            n0, n1, n2 = slip[i, 0] / speed, slip[i, 1] / speed, slip[i, 2] / speed
            along = (sigma_par - sigma_perp) * (j0 * n0 + j1 * n1 + j2 * n2)
            magnitude = scale * drag[i] * speed
            out[i, 0] = magnitude * (sigma_perp * j0 + along * n0)
            out[i, 1] = magnitude * (sigma_perp * j1 + along * n1)
            out[i, 2] = magnitude * (sigma_perp * j2 + along * n2)
        else:
            out[i, 0] = out[i, 1] = out[i, 2] = 0.0


# --------------------------------------------------------------------------- the registry
@dataclass(frozen=True)
class StochasticModel:
    """A stochastic-force model: its two compiled functions (``AMPLITUDE``, ``DECORRELATION``), where it was
    fitted (``solids_range``, ``re_range``: warned once outside), and what it is."""

    name: str
    amplitude: object
    decorrelation: object
    summary: str
    reference: str = ""
    validity: str = ""
    solids_range: tuple | None = None
    re_range: tuple | None = None


NO_STOCHASTIC_FORCE = "no stochastic force (the drag closure's mean drag only)"
MODELS: dict[str, StochasticModel | None] = {"none": None}  # 'none': no model object (the bridge skips it)
_SUMMARIES = {"none": NO_STOCHASTIC_FORCE}


def register_stochastic_force(name, amplitude, decorrelation, *, summary, reference="", validity="",
                              solids_range=None, re_range=None):
    """Make a model available to ``coupling.stochastic_force``: ``amplitude`` compiled for ``AMPLITUDE``,
    ``decorrelation`` for ``DECORRELATION`` (``@numba.njit(fvdem.coupling.stochastic.AMPLITUDE, cache=True)``)."""
    for function, signature, what in ((amplitude, AMPLITUDE, "amplitude"),
                                      (decorrelation, DECORRELATION, "decorrelation")):
        compiled = getattr(function, "nopython_signatures", None)
        if not compiled or len(compiled) != 1 or (compiled[0].args, compiled[0].return_type) != (
                signature.args, signature.return_type):
            raise TypeError(f"stochastic force {name!r}: its {what} must be compiled for "
                            f"fvdem.coupling.stochastic.{'AMPLITUDE' if what == 'amplitude' else 'DECORRELATION'} "
                            f"(it has {compiled!r})")
    MODELS[name] = StochasticModel(name, amplitude, decorrelation, summary, reference, validity, solids_range,
                                   re_range)
    _SUMMARIES[name] = summary


def stochastic_force_names() -> tuple:
    return tuple(MODELS)


def describe_stochastic_forces() -> str:
    """One line per registered model, for the case reference and ``fvdem schema``."""
    return "; ".join(f"'{name}': {summary}" for name, summary in _SUMMARIES.items())


register_stochastic_force(
    "force-langevin", force_langevin_amplitude, collision_frequency,
    summary="Lattanzi et al. (2022)'s force Langevin model: a per-particle Ornstein-Uhlenbeck drag fluctuation "
            "along and across the slip, its level from Mehrabadi et al. (2015)'s pseudo-turbulence of fixed "
            "sphere assemblies, its time the kinetic theory's mean free time (rods: on the volume-equivalent "
            "sphere)",
    reference="Lattanzi, Tavanashad, Subramaniam & Capecelatro (2022), Phys. Rev. Fluids 7, 014301; Mehrabadi, "
              "Tenneti, Garg & Subramaniam (2015), J. Fluid Mech. 770, 210-246; Chapman & Cowling (1970); "
              "Carnahan & Starling (1969)",
    validity="solids fraction 0.1-0.5, Re 0.01-300 (the pseudo-turbulence fits, spheres); statistically "
             "homogeneous suspensions (one granular temperature)",
    solids_range=(0.1, 0.5), re_range=(0.0, 300.0))  # below Re 0.01: the creeping limit, not warned


# --------------------------------------------------------------------------- the component
_WARNED: set = set()


class StochasticForce:
    """The stochastic force of a case's particles (``model`` a name of ``MODELS`` other than 'none'): owns the
    process state ``xi`` (rows by particle id) and its random generator (PCG64 seeded with ``seed``).

    ``count`` particles of volume-equivalent diameter ``diameter`` [m] in a gas of ``density`` [kg/m^3] and
    ``viscosity`` [Pa s]; ``scale`` multiplies the model's standard deviations and ``along_scale`` the one along
    the slip once more (1 and 1: as published)."""

    def __init__(self, model: str, count: int, seed: int, scale: float, diameter: float, density: float,
                 viscosity: float, along_scale: float = 1.0):
        self.model = MODELS[model]
        self.scale, self.along_scale = float(scale), float(along_scale)
        self.diameter, self.density, self.viscosity = float(diameter), float(density), float(viscosity)
        self.generator = np.random.Generator(np.random.PCG64(seed))
        self.xi = self.generator.standard_normal((count, 3))  # the stationary start
        self._normals = np.empty((count, 6))

    def force(self, particles, slip, voidage, drag, dt, groups=None) -> np.ndarray:
        """The held force [N] (N, 3) of the next coupling interval ``dt`` [s], in the rows' order of
        ``particles`` (the DEM's host view: its ``ids`` key each particle's process, its ``velocity`` gives
        the granular temperature), its mean over the particles removed; advances the process. ``slip`` (N, 3)
        [m/s], ``voidage`` (N,) and ``drag`` (N,) [kg/s] are the drag law's inputs and coefficients of the
        interval, in the same rows. ``groups`` (N,) non-negative integers (e.g. each particle's host cell):
        the mean is removed within each group instead (``remove_group_means``)."""
        ids, velocity = particles.ids, particles.velocity
        n = len(ids)
        out = np.empty((n, 3))
        if n == 0:
            return out
        self.generator.standard_normal(out=self._normals)
        stochastic_force_loop(self.model.amplitude, self.model.decorrelation, np.ascontiguousarray(ids, np.int64),
                              np.ascontiguousarray(slip, float), np.ascontiguousarray(voidage, float),
                              np.ascontiguousarray(drag, float), self.diameter, self.density, self.viscosity,
                              granular_temperature(velocity), float(dt), self.scale, self.along_scale, self.xi,
                              self._normals, out)
        if groups is None:
            out -= column_sums(out) / n
        else:
            remove_group_means(out, groups)
        self._warn_outside(slip, voidage)
        return out

    def _warn_outside(self, slip, voidage) -> None:
        m = self.model
        solids = 1.0 - np.asarray(voidage)
        re = self.density * self.diameter * np.asarray(voidage) * np.linalg.norm(slip, axis=1) / self.viscosity
        for quantity, values, bounds in (("solids fraction", solids, m.solids_range), ("Re", re, m.re_range)):
            if bounds is None:
                continue
            for side, extreme, outside in (("below", values.min(), values.min() < bounds[0]),
                                           ("above", values.max(), values.max() > bounds[1])):
                key = (m.name, quantity, side)
                if outside and key not in _WARNED:
                    _WARNED.add(key)
                    warnings.warn(f"stochastic force {m.name!r} used at {quantity} {extreme:.3g}, {side} its fitted "
                                  f"range {bounds[0]:g}-{bounds[1]:g} (further uses outside it are not warned)",
                                  RuntimeWarning, stacklevel=3)

    def state(self) -> dict:
        """The process and its generator (``stochastic.xi``, ``stochastic.generator``), for checkpoints."""
        return {"stochastic.xi": self.xi.copy(), "stochastic.generator": generator_words(self.generator)}

    def restore(self, data) -> None:
        """Load a ``state()``: the next intervals draw what the saved run would have drawn."""
        xi = np.array(data["stochastic.xi"], float, order="C", copy=True)
        if xi.shape != self.xi.shape:
            raise ValueError(f"stochastic.xi holds {xi.shape[0]} particles; the case has {self.xi.shape[0]}")
        self.xi = xi
        set_generator_words(self.generator, data["stochastic.generator"])


def remove_group_means(force, groups) -> None:
    """Remove, in place, the mean of the rows of ``force`` (N, 3) within each group of ``groups`` (N,)
    non-negative integers, and scale each row by ``sqrt(n / (n - 1))`` for its group's ``n`` rows, so that a
    row of independent unit-variance components keeps unit variance; a group of one row is set to zero. The
    rows of a group then sum to zero to round-off."""
    groups = np.asarray(groups, np.int64)
    size = int(groups.max()) + 1 if len(groups) else 0
    n = np.bincount(groups, minlength=size).astype(float)
    for k in range(force.shape[1]):
        means = np.bincount(groups, weights=force[:, k], minlength=size) / np.maximum(n, 1.0)
        force[:, k] -= means[groups]
    members = n[groups]
    force *= np.where(members > 1.0, np.sqrt(members / np.maximum(members - 1.0, 1.0)), 0.0)[:, None]


def host_cells(position, mesh) -> np.ndarray:
    """The index of the cell of ``mesh`` (a ``GasMesh`` box) that holds each point of ``position`` (N, 3)
    [m], in FiPy's order (x fastest); periodic axes wrapped, others clipped to the grid."""
    shape = np.asarray(mesh.shape, np.int64)
    spacing = np.asarray(mesh.spacing, float)
    lower = np.asarray(mesh.cell_centers[0], float) - 0.5 * spacing
    index = np.floor((np.asarray(position, float) - lower) / spacing).astype(np.int64)
    for axis in range(3):
        if mesh.periodic[axis]:
            index[:, axis] %= shape[axis]
        else:
            np.clip(index[:, axis], 0, shape[axis] - 1, out=index[:, axis])
    return index[:, 0] + shape[0] * (index[:, 1] + shape[1] * index[:, 2])


def granular_temperature(velocity) -> float:
    """A third of the mean squared departure of the particles' velocities from their mean [m^2/s^2]."""
    v = np.asarray(velocity, float)
    if not len(v):
        return 0.0
    return float(((v - v.mean(axis=0)) ** 2).sum(axis=1).mean() / 3.0)


_LOW = (1 << 64) - 1


def generator_words(generator) -> np.ndarray:
    """A PCG64 generator's full state as six uint64 words (the 128-bit state and increment, high word first,
    and the buffered 32-bit draw), which ``np.savez`` keeps exactly."""
    s = generator.bit_generator.state
    if s["bit_generator"] != "PCG64":
        raise ValueError(f"a {s['bit_generator']} generator; the stochastic force uses PCG64")
    state, inc = s["state"]["state"], s["state"]["inc"]
    return np.array([state >> 64, state & _LOW, inc >> 64, inc & _LOW, s["has_uint32"], s["uinteger"]], np.uint64)


def set_generator_words(generator, words) -> None:
    """The inverse of ``generator_words``."""
    w = [int(x) for x in np.asarray(words, np.uint64)]
    generator.bit_generator.state = {"bit_generator": "PCG64", "state": {"state": (w[0] << 64) | w[1],
                                                                         "inc": (w[2] << 64) | w[3]},
                                     "has_uint32": w[4], "uinteger": w[5]}


__all__ = ["MODELS", "NO_STOCHASTIC_FORCE", "StochasticForce", "StochasticModel", "register_stochastic_force", "stochastic_force_names",
           "describe_stochastic_forces", "force_langevin_amplitude", "collision_frequency", "interval_moments",
           "pseudo_turbulent_energy", "streamwise_anisotropy", "contact_radial_distribution", "stochastic_force_loop",
           "granular_temperature", "remove_group_means", "host_cells", "AMPLITUDE", "DECORRELATION"]
