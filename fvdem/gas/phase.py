"""The gas phase of a case: grid, solver, fixed porous zone, diagnostics and checkpoint state."""
from __future__ import annotations

import warnings

import numpy as np

from ..correlations import ergun_beta_per_solids
from ..errors import SimulationError
from .inlet import InletSchedule
from .mesh import GasMesh
from .solver import GasProperties, GasSolver

# above this largest cell Courant number |u| dt / dx a run is warned (once): steady flow diverges from
# about 2 (tools/stability_map.py, cfd map) and a bed's velocity spikes grow with it
WARN_COURANT = 1.0


class GasPhase:
    """Gas grid over the case domain and its solver; a fixed porous zone (a fixed bed) when configured.

    In the porous zone the voidage is fixed and the interphase coefficient is Ergun's, written on the
    interstitial velocity (Gidaspow's dense branch, evaluated each step with the local gas speed):
    ``beta = 150 eps_s^2 mu / (eps d^2) + 1.75 eps_s rho |u| / d``.
    """

    def __init__(self, case):
        g = case.gas
        self.config = g
        self.mesh = GasMesh.box(g.cells, case.domain.lower, case.domain.upper, case.domain.periodic)
        self.solver = GasSolver(self.mesh, GasProperties(g.density, g.viscosity), case.domain.gravity,
                                inlet_velocity=g.inlet_velocity, walls=g.walls, scheme=g.scheme,
                                correctors=g.correctors, linear_solver=g.linear_solver,
                                linear_tolerance=g.linear_tolerance, tolerance=g.simple_tolerance,
                                pressure_preconditioner=g.pressure_preconditioner,
                                corrector_tolerance=g.corrector_tolerance)
        self.dt = g.cfd_step
        self.step_count = 0
        zone = g.porous_zone
        centres = self.mesh.cell_centers
        if zone.enabled:
            self.zone = np.all((centres >= np.asarray(zone.lower)) & (centres <= np.asarray(zone.upper)), axis=1)
        else:
            self.zone = np.zeros(self.mesh.cell_count, bool)
        self.solver.voidage[self.zone] = zone.voidage
        self.solver.voidage_old[:] = self.solver.voidage
        n = self.mesh.cell_count
        self.exchange_beta = np.zeros(n)  # set by the coupling bridge [kg/(m^3 s)]
        self.exchange_source = np.zeros((n, 3))  # [N/m^3]
        # momentum the coupling returns to the gas [N s] per cell (C, 3), applied as a source over the
        # next step (so that it passes through the pressure correction, not into the cell velocity
        # unprojected); part of the gas's momentum until then
        self.returned_momentum = np.zeros((n, 3))
        self._body_force = np.asarray(g.body_force, float)
        self.inlet_ramp = float(g.inlet_ramp)
        # the inlet velocity of each step: the start-up ramp, the full velocity, the steps (gas.inlet_*)
        self.inlet = InletSchedule(g.inlet_velocity, g.inlet_ramp, g.inlet_steps, g.cfd_step)
        if self.inlet_ramp > 0.0:
            self.solver.set_inlet_velocity(0.0)
        self.mean_pressure_gradient = np.asarray(g.mean_pressure_gradient, float)
        self._courant_warned = False

    def set_voidage(self, voidage, previous=None) -> None:
        """New particle voidage for the next step; the current one becomes the old level of the
        ``d(eps)/dt`` term (or ``previous`` when given, e.g. at start-up)."""
        s = self.solver
        s.voidage_old[:] = s.voidage if previous is None else previous
        s.voidage[:] = voidage

    # ------------------------------------------------------------------ the coupling bridge's interface
    # set_voidage and set_exchange in; step; flux_velocity, pressure_gradient and exchange_lost out;
    # return_momentum for what the particles did not receive (docs/coupling.md)
    def flux_velocity(self) -> np.ndarray:
        """Cell velocities consistent with the face fluxes [m/s] (N, 3): what the particles see."""
        return self.solver.flux_velocity()

    def pressure_gradient(self) -> np.ndarray:
        """Cell pressure gradient [Pa/m] (N, 3) of the last step."""
        return self.solver.pressure_gradient()

    def exchange_lost(self, dt: float) -> np.ndarray:
        """Momentum the gas gave the particles through the exchange over ``dt`` [kg m/s] per cell (N, 3):
        ``V (beta u - S) dt`` with the exchange set for the step and the gas's momentum velocity ``u``."""
        return (self.exchange_beta[:, None] * self.solver.velocity - self.exchange_source) * \
            self.mesh.cell_volumes[:, None] * dt

    def return_momentum(self, momentum) -> None:
        """Momentum [kg m/s] per cell (N, 3) the gas lost that the particles did not receive: a source of the
        next step (so that the exchange conserves momentum)."""
        self.returned_momentum += momentum

    def set_exchange(self, beta, source) -> None:
        """Interphase momentum exchange of the next step: ``-beta u + source`` per unit volume (Eq. 8)."""
        self.exchange_beta[:] = beta
        self.exchange_source[:] = source

    def _update_porous_zone(self) -> None:
        if not self.zone.any():
            return
        z = self.config.porous_zone
        speed = np.linalg.norm(self.solver.velocity[self.zone], axis=1)
        self.solver.beta[self.zone] += (1.0 - z.voidage) * ergun_beta_per_solids(
            z.voidage, speed, z.particle_diameter, self.config.density, self.config.viscosity)

    def step(self) -> dict:
        """One CFD step; timed as ``gas_other`` less the solver's ``gas_momentum`` and ``gas_pressure``."""
        with self.timings.phase("gas_other"):
            return self._step()

    def _step(self) -> dict:
        s = self.solver
        inlet = self.inlet.change_before(self.step_count)  # the ramp (implicit: its value at the step's end), a step
        if inlet is not None:
            s.set_inlet_velocity(inlet)
        s.beta[:] = self.exchange_beta
        self._update_porous_zone()
        s.source[:] = (self._body_force + s.voidage[:, None] * self.mean_pressure_gradient + self.exchange_source
                       + self.returned_momentum / (self.mesh.cell_volumes[:, None] * self.dt))
        self.returned_momentum[:] = 0.0
        try:
            info = s.step(self.dt)
        except (RuntimeError, ValueError, FloatingPointError) as exc:  # e.g. a singular factorization
            if isinstance(exc, SimulationError):
                raise
            raise SimulationError(f"the gas step diverged ({exc}) at step {self.step_count}; CFD step {self.dt:.3g} s, "
                                  f"largest Courant number {self.courant_number():.3g} "
                                  "(docs/speed-accuracy.md: keep it below 1)") from None
        s.voidage_old[:] = s.voidage
        self.step_count += 1
        courant = self.courant_number()
        if courant > WARN_COURANT and self.config.scheme == "piso" and not self._courant_warned:
            self._courant_warned = True
            warnings.warn(f"gas step {self.step_count}: largest cell Courant number {courant:.3g} exceeds "
                          f"{WARN_COURANT:g} (CFD step {self.dt:.3g} s): steady flow diverges from about 2 and "
                          "a bed's pressure drop and voidage lose accuracy (docs/speed-accuracy.md); reduce "
                          "gas.cfd_step", RuntimeWarning, stacklevel=2)
        return info

    # ------------------------------------------------------------------ what the rest of fvdem reads
    # (the scenes, monitors and writers; nothing outside fvdem/gas/ touches the solver)
    @property
    def timings(self):
        """The ``fvdem.timing.Timings`` the steps add to (``gas_momentum``, ``gas_pressure``, ``gas_other``);
        a ``Model`` sets the run's."""
        return self.solver.timings

    @timings.setter
    def timings(self, timings) -> None:
        self.solver.timings = timings

    @property
    def velocity(self) -> np.ndarray:
        """Interstitial cell velocities [m/s] (C, 3), the momentum equation's (read-only outside the gas)."""
        return self.solver.velocity

    @property
    def pressure(self) -> np.ndarray:
        """Cell pressures [Pa] (C,) (read-only outside the gas)."""
        return self.solver.pressure

    @property
    def voidage(self) -> np.ndarray:
        """Cell voidage (gas volume fraction) of the last step (C,) (read-only outside the gas)."""
        return self.solver.voidage

    @property
    def periodic(self) -> bool:
        """Whether the box is periodic along every axis (no inlet, no outlet)."""
        return bool(self.solver.periodic)

    def max_speed(self) -> float:
        """The largest cell speed [m/s]."""
        return float(np.linalg.norm(self.solver.velocity, axis=1).max())

    @property
    def inlet_velocity(self) -> float:
        """The superficial inlet velocity [m/s] the inlet holds now (``inlet``: the ramp and steps of the case)."""
        return float(self.solver.inlet_velocity)

    # ------------------------------------------------------------------ observables
    def layer_height(self, height: float) -> float:
        """Height [m] of the cell-centre layer nearest to ``height``."""
        z = self.mesh.cell_centers[:, 2]
        return float(z[np.argmin(np.abs(z - height))])

    def plane_pressure(self, height: float) -> float:
        """Mean pressure [Pa] of the cell layer nearest to ``height`` [m]."""
        z = self.mesh.cell_centers[:, 2]
        layer = np.abs(z - self.layer_height(height)) < 1e-9
        return float(self.solver.pressure[layer].mean())

    def diagnostics(self) -> dict:
        s = self.solver
        z = self.mesh.cell_centers[:, 2]
        first = self.plane_pressure(z.min())
        diag = {"gas_max_speed": self.max_speed(), "gas_inlet_pressure": first}
        if not s.periodic:
            # pressure drop from the inlet face (the face pressure the solver's gradient takes) to
            # the last cell layer, less the gas head: what the particles (and wall friction) hold up [Pa]
            inlet = s.inlet_pressure()
            inlet_height = z.min() - 0.5 * self.mesh.spacing[2]
            diag["bed_pressure_drop"] = (inlet - self.plane_pressure(z.max())
                                         + self.config.density * s.gravity[2] * (z.max() - inlet_height))
        if self.zone.any():
            zone = self.config.porous_zone
            lo, hi = zone.lower[2], zone.upper[2]
            inset = 0.25 * (hi - lo)
            a, b = lo + inset, hi - inset
            diag["porous_zone_pressure_gradient"] = ((self.plane_pressure(a) - self.plane_pressure(b))
                                                     / (self.layer_height(b) - self.layer_height(a)))
            slip = self.config.inlet_velocity / zone.voidage  # interstitial speed in the zone
            diag["ergun_pressure_gradient"] = ((1.0 - zone.voidage) * slip / zone.voidage * ergun_beta_per_solids(
                zone.voidage, slip, zone.particle_diameter, self.config.density, self.config.viscosity))
            # the measured gradient also carries the gas's own weight: -dp/dz = beta u / eps - rho g_z
            diag["expected_pressure_gradient"] = (diag["ergun_pressure_gradient"]
                                                  - self.config.density * self.solver.gravity[2])
        return diag

    def check_health(self, time: float) -> None:
        s = self.solver
        if not (np.all(np.isfinite(s.velocity)) and np.all(np.isfinite(s.pressure))):
            raise SimulationError(f"non-finite gas velocity or pressure at t = {time:.6g} s; CFD step {self.dt:.3g} s, "
                                  f"largest Courant number {self.courant_number():.3g}")

    def courant_number(self) -> float:
        speed = np.abs(self.solver.velocity).max(axis=0)
        return float(np.max(speed * self.dt / np.asarray(self.mesh.spacing)))

    # ------------------------------------------------------------------ checkpoint state
    def state(self) -> dict:
        """The solver's state (``GasSolver.state``) under ``gas.``, with the phase's returned momentum and
        its step count first in ``gas.counters`` (the checkpoint format of 0.2.0)."""
        solver = self.solver.state()
        counters = solver.pop("counters")
        state = {f"gas.{k}": v for k, v in solver.items()}
        state.update({"gas.returned_momentum": self.returned_momentum,
                      "gas.counters": np.array([self.step_count, *counters])})
        return state

    def restore(self, data) -> None:
        counters = [int(v) for v in data["gas.counters"]] + [0, 0]  # older checkpoints: 3 counters
        self.step_count = counters[0]
        solver = {k[4:]: data[k] for k in data if k.startswith("gas.") and k != "gas.counters"}
        solver["counters"] = counters[1:5]
        self.solver.restore(solver)
        if "gas.returned_momentum" in data:
            self.returned_momentum = np.array(data["gas.returned_momentum"], copy=True)
        if self.inlet.varies:
            # the inlet as the uninterrupted run left it: __init__ set it to 0 for the ramp's start, and
            # the ramp and steps only update it where they change it (a run resumed after the ramp's end
            # kept no inflow at all)
            self.solver.set_inlet_velocity(self.inlet.after(self.step_count))
