"""The physical model of a case: particles (``DEMSystem``), gas (``GasPhase``) and the bridge between
them (``CouplingBridge``), and how they step together.

``Model(case)`` builds what the case has and picks its **stepping** once, as a value:

- ``"coupled"``: one loop step is one CFD step of ``CouplingBridge.advance`` (map, closures, gas step,
  ``cfd_step / dem_step`` DEM steps, exact exchange);
- ``"gas"``: gas steps only (no particles, or fixed particles without coupling);
- ``"dem"``: DEM steps only (no gas);
- ``"side-by-side"``: DEM steps, and a gas step every ``cfd_step / dem_step`` of them, without
  exchange (``coupling.enabled = false``).

The loop's step is the CFD step in the first two, the DEM step in the others. The model knows nothing
of what a run measures (``fvdem.scenes``) or writes (``fvdem.simulation``).
"""
from __future__ import annotations

import numba
import numpy as np

from .case import Case, CaseError
from .coupling.bridge import CouplingBridge
from .dem.backends import build_backend
from .dem.insertion import insert_particles
from .dem.packing import compress_periodic
from .dem.particles import ParticleArrays
from .dem.system import Box, ContactModel, DEMSystem
from .gas.phase import GasPhase
from .timing import Timings

STEPPINGS = ("coupled", "gas", "dem", "side-by-side")


def set_threads(threads: int) -> int:
    """Use ``threads`` numba threads (0: all available). Returns the number in use."""
    available = numba.config.NUMBA_NUM_THREADS
    wanted = available if threads == 0 else min(threads, available)
    numba.set_num_threads(wanted)
    return wanted


def stepping_of(case: Case) -> str:
    """The stepping a case runs with (see the module docstring)."""
    has_particles = case.particles.count > 0
    if not case.gas.enabled:
        return "dem"
    if has_particles and case.coupling.enabled:
        return "coupled"
    if not has_particles or case.particles.fixed:  # fixed particles never move (refused without gas)
        return "gas"
    return "side-by-side"


def load_initial_state(case: Case) -> ParticleArrays:
    """The particles of ``particles.initial_state``, checked against the case (count, diameter and
    length); ``CaseError`` naming the key otherwise. ``fvdem check`` calls it too, so that it refuses
    what ``fvdem run`` would."""
    cfg = case.particles
    path = case.resolve_path(cfg.initial_state)
    if not path.is_file():
        raise CaseError([f"particles.initial_state = {cfg.initial_state!r}: file {path} does not exist "
                         "(run the case that writes it first: cases/bed_ar1.toml and cases/bed_ar4.toml write the paper cases' settled beds)"])
    try:
        with np.load(path) as data:
            particles = ParticleArrays.from_dict({k: data[k] for k in data.files})
    except (OSError, ValueError, KeyError, EOFError) as exc:
        raise CaseError([f"particles.initial_state = {cfg.initial_state!r}: {path} is not a particle state "
                         f"written by fvdem ({type(exc).__name__}: {exc})"]) from None
    if particles.count != cfg.count:
        raise CaseError([f"particles.count = {cfg.count}: the initial state {path} holds {particles.count}"])
    if not (np.allclose(particles.radius, cfg.radius) and np.allclose(particles.half_length, cfg.half_length)):
        raise CaseError([f"particles: the shape in {path} differs from the case's diameter/length"])
    return particles


def build_particles(case: Case) -> ParticleArrays:
    """Particles of a case: inserted without overlap, or loaded from ``particles.initial_state``."""
    cfg = case.particles
    if cfg.initial_state is not None:
        particles = load_initial_state(case)
    elif cfg.insertion.method == "compress":
        lower, upper = np.asarray(case.domain.lower, float), np.asarray(case.domain.upper, float)
        try:
            particles = compress_periodic(cfg.count, cfg.radius, cfg.half_length, cfg.density, upper - lower,
                                          cfg.insertion.seed, cfg.insertion.orientation
                                          if cfg.shape == "spherocylinder" else "vertical")
        except ValueError as exc:
            raise CaseError([f"particles.insertion: {exc}"]) from None
        particles.position += lower
    else:
        ins = cfg.insertion
        lower = ins.lower or case.domain.lower
        upper = ins.upper or case.domain.upper
        try:
            position, axis = insert_particles(cfg.count, cfg.radius, cfg.half_length, lower, upper,
                                              ins.orientation if cfg.shape == "spherocylinder" else "vertical",
                                              ins.gap, ins.seed)
        except ValueError as exc:
            raise CaseError([f"particles.insertion: {exc}"]) from None
        particles = ParticleArrays.create(position, cfg.radius, cfg.half_length, cfg.density, axis=axis)
    if cfg.colour == "by_height":
        rank = np.empty(particles.count, np.int64)
        rank[np.argsort(particles.position[:, 2], kind="stable")] = np.arange(particles.count)
        particles.colour[:] = (rank >= particles.count // 2).astype(np.int32)
    else:
        particles.colour[:] = 0
    return particles


def build_dem(case: Case, particles: ParticleArrays) -> DEMSystem:
    """The case's DEM on its backend (``run.dem_backend``; ``fvdem.dem.backends``)."""
    c = case.contact
    contact = ContactModel(c.normal_stiffness, c.restitution, c.friction, c.rolling_friction,
                           c.tangential_stiffness_ratio, c.tangential_damping_ratio, c.wall_friction,
                           c.wall_rolling_friction)
    box = Box(case.domain.lower, case.domain.upper, case.domain.periodic)
    return build_backend(case.run.dem_backend, particles, box, contact, case.time.dem_step, case.domain.gravity,
                         case.contact.neighbour_skin)  # None: the adaptive skin


class Model:
    """DEM, gas and bridge of a case, stepped together (``stepping``, see the module docstring).

    ``state`` (``None``: build the particles from the case) is a checkpoint's arrays to continue from;
    ``timings`` the phases' seconds so far (``fvdem.timing``).
    """

    def __init__(self, case: Case, state: dict | None = None, timings: Timings | None = None):
        self.case = case
        self.timings = timings or Timings()  # seconds per phase, shared by DEM, gas and bridge
        self.stepping = stepping_of(case)
        has_particles = case.particles.count > 0
        self.time_step = case.gas.cfd_step if self.stepping in ("coupled", "gas") else case.time.dem_step
        self._cfd_every = max(1, round(case.gas.cfd_step / case.time.dem_step)) if has_particles else 1
        self.gas = GasPhase(case) if case.gas.enabled else None
        self.dem = self.bridge = None
        if has_particles:
            if state is None:
                self.dem = build_dem(case, build_particles(case))
            else:
                particles = ParticleArrays.from_dict({k.split(".", 1)[1]: v for k, v in state.items()
                                                      if k.startswith("particles.")})
                self.dem = build_dem(case, particles)
                self.dem.restore(state)
        if self.dem is not None:
            self.dem.timings = self.timings
        if self.gas is not None:
            self.gas.timings = self.timings
        if self.stepping == "coupled":  # before the gas restore: the bridge maps a start-up voidage
            self.bridge = CouplingBridge(case, self.dem, self.gas, self.timings)
            if state is not None:
                self.bridge.restore(state)
        if state is not None and self.gas is not None:  # the last step's voidage, not a remapped one
            self.gas.restore(state)

    @property
    def particles(self) -> ParticleArrays | None:
        return self.dem.particles if self.dem is not None else None

    @property
    def step_count(self) -> int:
        """Loop steps taken: CFD steps when coupled or gas only, else DEM steps."""
        return self.gas.step_count if self.stepping in ("coupled", "gas") else self.dem.step_count

    @property
    def time(self) -> float:
        return self.step_count * self.time_step

    def advance(self, steps: int) -> None:
        """Advance ``steps`` loop steps."""
        if self.stepping == "coupled":
            for _ in range(steps):
                self.bridge.advance()
        elif self.stepping == "gas":
            for _ in range(steps):
                self.gas.step()
        elif self.stepping == "dem":
            self.dem.step(steps)
        else:
            remaining = steps
            while remaining > 0:
                chunk = min(remaining, self._cfd_every - self.dem.step_count % self._cfd_every)
                self.dem.step(chunk)
                remaining -= chunk
                if self.dem.step_count % self._cfd_every == 0:
                    self.gas.step()

    def check_health(self) -> None:
        """``SimulationError`` with the cause for non-finite values or particles through walls."""
        if self.dem is not None:
            self.dem.check_health()
        if self.gas is not None:
            self.gas.check_health(self.time)

    def state(self) -> dict:
        """Every array needed to continue bit-for-bit."""
        state = {}
        if self.dem is not None:
            state.update(self.dem.state())
        if self.gas is not None:
            state.update(self.gas.state())
        if self.bridge is not None:
            state.update(self.bridge.state())
        return state


__all__ = ["Model", "STEPPINGS", "set_threads", "stepping_of", "build_particles", "build_dem", "load_initial_state"]
