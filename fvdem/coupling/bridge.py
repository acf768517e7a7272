"""The source-term bridge: one coupling interval (one CFD step = n DEM steps) of gas and particles.

Per interval ``[t, t + dt]`` (``dt`` the CFD step, ``h = dt / n`` the DEM step):

1. **Map** the particles to the grid (``ParticleGridMap``: satellite points along rods, trilinear
   weights) and compute the voidage (``divided``, ``centroid`` or ``trilinear``); the previous
   voidage becomes the old level of the gas's ``d(eps)/dt``.
2. **Closures** at the particles: gas velocity (reconstructed from the face fluxes:
   ``GasSolver.flux_velocity``, exact across voidage jumps) and voidage interpolated, slip
   ``u - v``, drag coefficient ``c`` [kg/s] (drag ``F_D = c (u - v)``), lift and torque, each law's
   compiled kernel (``kernels.py``; the numpy closures are the reference they are tested against);
   with ``coupling.stochastic_force``, each particle's drag fluctuation ``F''`` for the interval
   (``stochastic.py``: an Ornstein-Uhlenbeck process per particle, held over the interval like the lift).
3. **Gas step** with Eq. 8, ``R = -sum (F_D + F_L + F'') / V_cell``, deposited with the transposed
   interpolation weights. *Semi-implicit* (default): the drag enters the gas momentum as
   ``-beta u + S``. The coefficient accounts for the particle's own response over the interval:
   a particle kicked implicitly towards ``u`` with its other forces ``m a`` held gains the drag
   impulse ``J = m (1 - R) (u - v) + m a [(1 - R) m / c - dt]`` with ``R = (1 + h c / 2m)^(-2n)``,
   so ``beta = sum w m (1 - R) / (dt V)`` and ``S = sum w [m (1 - R) v - m a ((1 - R) m / c - dt)] /
   (dt V)``. For ``h c / m -> 0`` this is the usual ``beta = sum c / V``, ``S = beta v``; for
   particles much faster than the step it is ``m / dt`` (the particle follows the gas) instead of a
   stiff ``c`` that would stall the exchange. *Explicit*: the force at the coupling time is held
   over the interval on both sides (CFDEMcoupling's default; unstable for ``dt > 2 m / c``).
4. **Particles**: the new gas velocity and pressure gradient are interpolated into the bridge's own
   buffers (``CouplingInputs``), which the DEM's ``coupled_step`` copies in: its kicks integrate
   ``c (u - v)`` implicitly and hold ``-V_p grad p`` + lift and the torque, and it returns the drag
   impulse they applied, in the particles' order of the call.
5. **Exact exchange**: the gas lost ``V (beta u - S) dt`` per cell, the particles gained the
   recorded impulse; the difference — from contact forces changing within the interval — is
   returned to the gas as a source of its next step (``GasPhase.returned_momentum``; added to the
   cell velocities directly it bypassed the pressure correction and broke continuity by several
   per cent), so that gas plus particle momentum, the pending return included, changes by the
   external forces only, to round-off.

The scheme is chosen once, from ``coupling.drag_treatment`` and ``particles.fixed``: ``SemiImplicitDrag``,
``ExplicitDrag`` (moving or fixed particles) or ``FixedBed`` (semi-implicit, nothing moves: the particles receive
``c u dt``), each an object with the three steps that differ (``closures``, ``exchange``, ``move``).
``CouplingBridge.advance`` runs the phases in order, each timed under its name (``voidage_mapping``,
``closures``, ``deposition``; the gas and the DEM time their own steps).

Torque is not fed back to the gas (docs/equations.md §2). A sphere case evaluates no lift or torque.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..dem.backends import CouplingInputs
from ..errors import SimulationError
from . import closures
from .interpolation import ParticleGridMap
from .kernels import column_sums, exchange_terms, particle_forces, slip_at_particles
from .stochastic import StochasticForce, host_cells
from .voidage import METHODS as VOIDAGE_METHODS
from .voidage import voidage as map_voidage


@dataclass(frozen=True)
class HydrodynamicModel:
    """Closures chosen by name (``coupling`` case section) for particles of one shape, looked up in
    the registry ``closures.LAWS``.

    ``diameter`` the sphere or cylinder diameter [m]; ``length`` the total length [m] (= diameter for
    spheres); ``density``/``viscosity`` of the gas [kg/m^3], [Pa s].
    """

    drag: str
    lift: str
    torque: str
    diameter: float
    length: float
    density: float
    viscosity: float

    @cached_property
    def particle(self) -> closures.ParticleShape:
        return closures.ParticleShape(self.diameter, self.length, self.density, self.viscosity)

    def drag_coefficient(self, slip, voidage, axis):
        """``c`` [kg/s] (N,) with ``F_D = c * slip``."""
        return closures.law("drag", self.drag).evaluate(self.particle, slip, voidage, axis)

    def lift_force(self, slip, voidage, axis):
        """Lift [N] (N, 3), or None when the model has none."""
        return closures.law("lift", self.lift).evaluate(self.particle, slip, voidage, axis)

    def evaluate(self, slip, voidage, axis):
        """``(c, lift, torque)`` of the model's laws (lift/torque None when 'none'), in one pass over the
        particles (``closures.evaluate_set``)."""
        return closures.evaluate_set(self.particle, self.drag, self.lift, self.torque, slip, voidage, axis)

    def hydrodynamic_torque(self, slip, voidage, axis):
        """Hydrodynamic torque [N m] (N, 3), or None when the model has none."""
        return closures.law("torque", self.torque).evaluate(self.particle, slip, voidage, axis)


_NO_LIFT = np.zeros((0, 3))  # the kernels' "none" for lift and explicit drag


def rotational_drag_torque(angular_velocity, inertia, coefficient, dt):
    """Rotational (viscous) drag [N m] (N, 3) held over a coupling interval ``dt`` [s]: the torque that
    takes ``omega`` to ``omega exp(-dt / tau)`` over the interval, ``tau = I / coefficient`` (``I``
    the transverse moment [kg m^2], ``coefficient`` [N m s], e.g. Stokes' ``pi mu d^3``), i.e. the exact
    decay of ``I d(omega)/dt = -coefficient omega``; stable for any ``dt`` (a torque ``-coefficient
    omega`` held explicitly reverses the spin once ``dt > 2 tau``)."""
    decay = -np.expm1(-dt * coefficient / inertia)
    return -(inertia * decay / dt)[:, None] * angular_velocity


def particle_response(mass, drag_coefficient, substep, substeps):
    """``(1 - R, k)`` of the implicit kicks over one coupling interval: ``R = (1 + q)^(-2n)``,
    ``q = (h / 2) c / m``, and ``k = (1 - R) m / (c dt) - 1`` (0 where ``c = 0``), ``dt = n h``. The numpy
    reference of ``kernels.exchange_terms``, which the bridge runs."""
    q = 0.5 * substep * drag_coefficient / mass
    one_minus_r = -np.expm1(-2.0 * substeps * np.log1p(q))
    x = drag_coefficient * substep * substeps / mass
    k = np.divide(one_minus_r, x, out=np.ones_like(x), where=x > 0) - 1.0
    return one_minus_r, k


@dataclass
class AtParticles:
    """What the closures give each particle for one interval (rows in the particles' order at its start):
    the slip ``u - v`` [m/s] (N, 3), the drag coefficient ``c`` [kg/s] (N,), the hydrodynamic torque [N m]
    (N, 3) or None, the forces held over the interval on both sides ``held`` [N] (N, 3) (lift and the
    stochastic fluctuation) or None, and, with the explicit scheme, the drag force held likewise [N] (N, 3)."""

    slip: np.ndarray
    drag_coefficient: np.ndarray
    torque: np.ndarray | None
    held: np.ndarray | None
    explicit_drag: np.ndarray | None = None


class SemiImplicitDrag:
    """The drag implicit on both sides (``coupling.drag_treatment = "semi-implicit"``, moving particles): the
    gas takes ``-beta u + S`` from the particles' response over the interval (``kernels.exchange_terms``), the
    DEM's kicks integrate ``c (u - v)`` by backward Euler, and what they applied is balanced exactly."""

    name = "semi-implicit"

    def closures(self, bridge, at: AtParticles) -> None:
        pass

    def exchange(self, bridge, grid_map, at: AtParticles):
        """``(beta, S)`` per cell [kg/s], [N] (summed, not yet per volume): response, coefficient, source
        and their deposition in one kernel pass."""
        p, cells = bridge.dem.particles, bridge.mesh.cell_count
        return exchange_terms(p.mass, at.drag_coefficient, p.velocity, p.contact_force + p.external_force,
                              np.asarray(bridge.dem.gravity, float), _NO_LIFT if at.held is None else at.held,
                              bridge.dem.dt, bridge.substeps, bridge.cfd_step, grid_map.cells, grid_map.weights,
                              grid_map.counts, np.zeros(cells), np.zeros((cells, 3)))

    def move(self, bridge, inputs: CouplingInputs, at: AtParticles):
        """The particles' steps of the interval; the drag impulse they received [N s] (N, 3)."""
        return bridge.step_particles(inputs, at, at.drag_coefficient)


class ExplicitDrag:
    """The drag at the coupling time held over the interval on both sides (``coupling.drag_treatment =
    "explicit"``; CFDEMcoupling's default, unstable for ``dt > 2 m / c``): what one side loses the other gains,
    so nothing is returned. ``moving = False``: fixed particles (``particles.fixed``) take no steps."""

    name = "explicit"

    def __init__(self, moving: bool = True):
        self.moving = moving

    def closures(self, bridge, at: AtParticles) -> None:
        at.explicit_drag = at.drag_coefficient[:, None] * at.slip
        bridge.check_explicit_stability(at.drag_coefficient, bridge.dem.particles.mass)

    def exchange(self, bridge, grid_map, at: AtParticles):
        exchanged = -at.explicit_drag
        return np.zeros(bridge.mesh.cell_count), grid_map.scatter(exchanged if at.held is None else exchanged - at.held)

    def move(self, bridge, inputs: CouplingInputs, at: AtParticles):
        """The particles' steps with the drag among the held forces; None: no impulse to balance."""
        if self.moving:
            bridge.step_particles(inputs, at, None)
        return None


class FixedBed:
    """Fixed particles (``particles.fixed``) with the semi-implicit drag: the gas takes ``-beta u + S`` with
    ``beta = sum c`` and the particles at rest; nothing moves, and the particles receive the drag at the new
    gas velocity, ``c u dt``, which the exact exchange balances."""

    name = "fixed bed"

    def closures(self, bridge, at: AtParticles) -> None:
        pass

    def exchange(self, bridge, grid_map, at: AtParticles):
        exchanged = np.zeros_like(at.slip)
        return grid_map.scatter(at.drag_coefficient), grid_map.scatter(
            exchanged if at.held is None else exchanged - at.held)

    def move(self, bridge, inputs: CouplingInputs, at: AtParticles):
        return at.drag_coefficient[:, None] * inputs.fluid_velocity * bridge.cfd_step


def coupling_scheme(drag_treatment: str, fixed: bool):
    """The scheme of ``coupling.drag_treatment`` for moving or fixed (``particles.fixed``) particles."""
    if drag_treatment == "explicit":
        return ExplicitDrag(moving=not fixed)
    return FixedBed() if fixed else SemiImplicitDrag()


class CouplingBridge:
    """Couples a DEM (``dem.backends.DEMBackend``) and a ``GasPhase`` for one case (``case.coupling``); the
    coupling scheme (``SemiImplicitDrag``, ``ExplicitDrag``, ``FixedBed``) is chosen once, here. ``timings``:
    the run's (default: the DEM's)."""

    def __init__(self, case, dem, gas, timings=None):
        self.config = cfg = case.coupling
        self.dem, self.gas = dem, gas
        self.timings = dem.timings if timings is None else timings
        p = case.particles
        self.fixed = p.fixed
        self.scheme = coupling_scheme(cfg.drag_treatment, p.fixed)
        self.model = HydrodynamicModel(cfg.drag, cfg.lift if p.shape != "sphere" else "none",
                                       cfg.torque if p.shape != "sphere" else "none", p.diameter,
                                       p.length if p.shape != "sphere" else p.diameter,
                                       case.gas.density, case.gas.viscosity)
        self.cfd_step = case.gas.cfd_step
        self.rotational_drag = cfg.rotational_drag == "stokes" and not p.fixed
        # Stokes' rotational drag of the volume-equivalent sphere, 8 pi mu r^3 = pi mu d_e^3 [N m s]
        self._rotational_coefficient = np.pi * case.gas.viscosity * p.equivalent_diameter ** 3
        self.substeps = max(1, round(case.gas.cfd_step / case.time.dem_step))
        # the drag fluctuation felt from the neighbours (``coupling.stochastic_force``; ``stochastic.py``)
        self.stochastic = None if cfg.stochastic_force == "none" or p.fixed else StochasticForce(
            cfg.stochastic_force, dem.particles.count, cfg.stochastic_seed, cfg.stochastic_scale,
            p.equivalent_diameter, case.gas.density, case.gas.viscosity, cfg.stochastic_along_scale)
        self._inputs = CouplingInputs.zeros(dem.particles.count)  # the DEM's coupling inputs: the bridge's buffers
        self.mesh = gas.mesh
        self.last: dict = {"drag_force": np.zeros(3), "pressure_force": np.zeros(3), "momentum_returned": 0.0}
        self._map: ParticleGridMap | None = None  # refreshed in place each interval
        self._voidage_map: ParticleGridMap | None = None  # the voidage method's, where its weights differ
        eps = self._voidage(self._grid_map())  # one-way too: the over-packed cells are measured from the start
        if cfg.two_way:
            gas.set_voidage(eps, previous=eps)

    # ------------------------------------------------------------------ one interval
    def advance(self) -> None:
        """One CFD step of the gas and ``substeps`` DEM steps of the particles, coupled (the module
        docstring's five phases). The gas and the DEM time their own steps."""
        timings, two_way = self.timings, self.config.two_way
        with timings.phase("voidage_mapping"):
            grid_map, voidage = self._map_particles()
        with timings.phase("closures"):
            at = self._closures(grid_map, voidage)
        if two_way:
            with timings.phase("deposition"):
                beta, source = self.scheme.exchange(self, grid_map, at)
                self.gas.set_exchange(beta / self.mesh.cell_volumes, source / self.mesh.cell_volumes[:, None])
        self.gas.step()
        with timings.phase("closures"):
            inputs, pressure_force = self._particle_inputs(grid_map, at)
        impulse = self.scheme.move(self, inputs, at)  # in the particles' order of this interval
        with timings.phase("deposition"):
            returned = self._return_momentum(grid_map, impulse, at) if impulse is not None and two_way else 0.0
        drag_force = (column_sums(at.explicit_drag) if impulse is None
                      else column_sums(impulse) / self.cfd_step)
        self.last.update(drag_force=drag_force, pressure_force=pressure_force, momentum_returned=returned)

    # ------------------------------------------------------------------ its phases
    def _map_particles(self):
        """1. The particle-grid map of the interval and the cells' voidage, handed to the gas (two-way)."""
        grid_map = self._grid_map()
        voidage = self._voidage(grid_map)
        if self.config.two_way:  # one-way coupling: the gas does not see the particles at all
            self.gas.set_voidage(voidage)
        return grid_map, voidage

    def _closures(self, grid_map, voidage) -> AtParticles:
        """2. Voidage and gas velocity at the particles (one pass over the weights), the slip, and the laws:
        drag coefficient, lift, torque and the stochastic fluctuation."""
        p = self.dem.particles
        at_particles = grid_map.gather(np.column_stack([voidage, self.gas.flux_velocity()]))
        n = p.count
        eps_p, slip = slip_at_particles(at_particles, p.velocity, self.config.minimum_voidage, self.fixed,
                                        np.empty(n), np.empty((n, 3)))
        c, lift, torque = self.model.evaluate(slip, eps_p, p.axis)
        held = lift  # the forces held over the interval on both sides: lift and the stochastic force
        if self.stochastic is not None:
            groups = host_cells(p.position, self.mesh) if self.config.stochastic_zero_mean == "cell" else None
            fluctuation = self.stochastic.force(p, slip, eps_p, c, self.cfd_step, groups)
            held = fluctuation if lift is None else lift + fluctuation
            self.last["stochastic_force"] = fluctuation
        at = AtParticles(slip, c, torque, held)
        self.scheme.closures(self, at)
        return at

    def _particle_inputs(self, grid_map, at: AtParticles):
        """4. The new gas velocity at the particles, and ``-V_p grad p`` (+ ``V_p G``, an imposed mean gradient
        acting on both phases) + the held forces (+ the explicit drag), written into the bridge's buffers for
        the DEM (one gather for both fields). Returns the inputs and the total pressure force [N] (3,)."""
        cfg, gas, p = self.config, self.gas, self.dem.particles
        fields = [gas.flux_velocity()] + ([gas.pressure_gradient()] if cfg.pressure_gradient_force else [])
        at_particles = grid_map.gather(np.column_stack(fields))
        inputs = self._inputs
        if len(inputs.fluid_velocity) != p.count:
            inputs = self._inputs = CouplingInputs.zeros(p.count)
        pressure_force = particle_forces(at_particles, bool(cfg.pressure_gradient_force), p.radius, p.half_length,
                                         np.asarray(gas.mean_pressure_gradient, float),
                                         _NO_LIFT if at.held is None else at.held,
                                         _NO_LIFT if at.explicit_drag is None else at.explicit_drag,
                                         inputs.fluid_velocity, inputs.external_force)
        return inputs, pressure_force

    def step_particles(self, inputs: CouplingInputs, at: AtParticles, drag_coefficient):
        """The DEM's ``substeps`` steps with the inputs, the torque (hydrodynamic, and Stokes' rotational drag
        held exactly) and the drag coefficient of the kicks (None: no drag in the kicks). Returns the drag
        impulse the kicks applied (N, 3), in the particles' order of the call."""
        p = self.dem.particles
        inputs.external_torque[:] = 0.0 if at.torque is None else at.torque
        if self.rotational_drag:
            inputs.external_torque += rotational_drag_torque(p.angular_velocity, p.inertia[:, 0],
                                                             self._rotational_coefficient, self.cfd_step)
        inputs.drag_coefficient = drag_coefficient
        return self.dem.coupled_step(self.substeps, inputs)

    def _return_momentum(self, grid_map, impulse, at: AtParticles) -> float:
        """5. The exact exchange: the gas lost ``V (beta u - S) dt`` per cell (``u`` its momentum velocity), the
        particles gained the drag ``impulse`` (with the flux velocity); the difference becomes a source of the
        gas's next step. The held forces are explicit on both sides: not in the balance (one deposition of
        both). Returns the largest component of the returned total [kg m/s]."""
        lost = self.gas.exchange_lost(self.cfd_step)
        difference = lost - grid_map.scatter(impulse if at.held is None else impulse + at.held * self.cfd_step)
        self.gas.return_momentum(difference)  # a source of the next gas step
        return float(np.abs(difference.sum(axis=0)).max())

    def _grid_map(self) -> ParticleGridMap:
        if self._map is None:
            self._map = ParticleGridMap(self.mesh, self.dem.particles, "trilinear", self.config.satellites)
            return self._map
        return self._map.refresh(self.dem.particles)

    def _voidage(self, grid_map):
        """The cells' voidage by the case's method, through ``grid_map`` where the method's weights are the
        bridge's (trilinear, satellites), else through a map of its own, refreshed in place like it."""
        cfg = self.config
        method = VOIDAGE_METHODS[cfg.voidage]
        points = method.points(cfg.satellites)
        if not grid_map.fits(method.weights, points, self.dem.particles):
            if self._voidage_map is None or not self._voidage_map.fits(method.weights, points, self.dem.particles):
                self._voidage_map = ParticleGridMap(self.mesh, self.dem.particles, method.weights, points)
            else:
                self._voidage_map.refresh(self.dem.particles)
            grid_map = self._voidage_map
        eps, over_packed = map_voidage(self.dem.particles, self.mesh, cfg.voidage, cfg.satellites,
                                       cfg.minimum_voidage, grid_map=grid_map)
        self.last["over_packed_cells"] = over_packed
        return eps

    def check_explicit_stability(self, c, mass) -> None:
        """Explicit drag held over the CFD step diverges once ``dt > 2 m / c`` (forward Euler)."""
        if not len(c):
            return
        response = mass / np.maximum(c, 1e-300)
        i = int(np.argmin(response))
        if self.cfd_step > 2.0 * response[i]:
            raise SimulationError(
                f"explicit drag is unstable: CFD step {self.cfd_step:.3g} s exceeds 2 x the particle response time "
                f"{response[i]:.3g} s (m / c of particle id {int(self.dem.particles.ids[i])}); use "
                "coupling.drag_treatment = 'semi-implicit' or a CFD step below "
                f"{2.0 * response[i]:.3g} s")

    # ------------------------------------------------------------------ checkpoint state
    def state(self) -> dict:
        """The bridge's own state: the stochastic force's process and random generator (empty without one)."""
        return {} if self.stochastic is None else self.stochastic.state()

    def restore(self, data) -> None:
        """Load a ``state()``; a checkpoint without the stochastic force's state (written without one) starts
        its process afresh from the case's seed."""
        if self.stochastic is not None and "stochastic.xi" in data:
            self.stochastic.restore(data)

    # ------------------------------------------------------------------ observables
    def diagnostics(self) -> dict:
        return {"over_packed_cells": self.last["over_packed_cells"],
                "total_drag_z": float(self.last["drag_force"][2]),
                "total_pressure_force_z": float(self.last["pressure_force"][2])}

