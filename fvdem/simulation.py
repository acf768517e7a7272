"""The time loop of a case: builds the model from a ``Case``, advances it, runs writers on schedules.

``Simulation.run`` advances in chunks of DEM steps up to the next scheduled event; at an event it
(in this order) checks the state's health, appends a ``timeseries.csv`` row, writes a VTU
snapshot, writes a checkpoint, and tests the stop criterion. Writers only read the state, so a
run resumed from a checkpoint continues bit-for-bit as if uninterrupted.
"""
from __future__ import annotations

import json
import os
import shutil
import signal
import warnings
import time as _time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numba
import numpy as np

from .analysis.bed import bed_top, packed_bed_summary
from .analysis.mixing import mixing_indices, mixing_time
from .analysis.suspension import (orientation_histogram, settling_velocity, steady_window,
                                  velocity_fluctuations)
from .case import Case, CaseError, to_toml
from .coupling.bridge import CouplingBridge
from .dem.insertion import insert_particles
from .dem.packing import compress_periodic
from .dem.particles import ParticleArrays
from .dem.system import Box, ContactModel, DEMSystem, SimulationError
from .gas.phase import GasPhase
from .io.checkpoint import load_checkpoint, save_checkpoint
from .io.timeseries import TimeseriesWriter
from .io.vtk import write_gas_vtu, write_particles_vtu, write_pvd

CHECKPOINT = "checkpoint.npz"
FINAL_STATE = "final_state.npz"
TIMESERIES_COLUMNS = ("time", "kinetic_energy", "max_overlap_over_diameter", "contacts_per_particle",
                      "bed_top", "rms_speed", "max_speed")
GAS_TIMESERIES_COLUMNS = ("gas_max_speed", "gas_inlet_pressure")


class OutputError(RuntimeError):
    """The output folder cannot be used as asked (exists, or nothing to resume)."""


def set_threads(threads: int) -> int:
    """Use ``threads`` numba threads (0: all available). Returns the number in use."""
    available = numba.config.NUMBA_NUM_THREADS
    wanted = available if threads == 0 else min(threads, available)
    numba.set_num_threads(wanted)
    return wanted


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
    c = case.contact
    contact = ContactModel(c.normal_stiffness, c.restitution, c.friction, c.rolling_friction,
                           c.tangential_stiffness_ratio, c.tangential_damping_ratio)
    box = Box(case.domain.lower, case.domain.upper, case.domain.periodic)
    return DEMSystem(particles, box, contact, case.time.dem_step, case.domain.gravity, case.neighbour_skin())


def prepare_output(out_dir, overwrite: bool = False, resume: bool = False) -> Path:
    """Create the output folder; never replace results unless ``overwrite``."""
    out = Path(out_dir)
    try:
        return _prepare_output(out, overwrite, resume)
    except OSError as exc:
        raise OutputError(f"output folder {out}: {exc.strerror or exc}"
                          + (f" ({exc.filename})" if exc.filename and str(exc.filename) != str(out) else "")) from None


# a step costing this many times the run's first measured rate is warned about (once)
RUNAWAY_COST = 20.0
# a walled column's gas faster than this many times the speed its inlet (in the densest packing) or
# its particles drive is stopped: the 10x-continuity defect of issue 14 reached 20-50x
RUNAWAY_GAS_SPEED = 10.0

# keys a resumed run may change: when it ends, what it writes and how it runs; all else is its physics
RESUME_SAFE = ("name", "description", "time.end", "time.stop_when_settled", "time.settled_speed", "time.min_time",
               "output.", "run.")


def check_resumable(case: Case, out: Path) -> None:
    """Refuse to resume ``out`` with a case whose physics differs from the one it was started with
    (its ``case.toml``), naming every key that differs; end time, output and run settings may change."""
    import tomllib
    path = out / "case.toml"
    if not path.exists():
        return
    try:
        before = _flatten(tomllib.loads(path.read_text()))
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise OutputError(f"--resume: {path} cannot be read ({exc}); it records the case the run was started with")
    now = _flatten(tomllib.loads(to_toml(case)))
    changed = [key for key in sorted(set(before) | set(now))
               if before.get(key) != now.get(key) and not any(
                   key == safe or (safe.endswith(".") and key.startswith(safe)) for safe in RESUME_SAFE)]
    if changed:
        listed = "; ".join(f"{k}: {before.get(k, '(unset)')!r} -> {now.get(k, '(unset)')!r}" for k in changed)
        raise OutputError(f"--resume: the case differs from the one {out} was started with in {listed}. A resumed run "
                          "continues the same physics; change only time.end, output.* or run.*, or start a new "
                          "run folder")


def _flatten(table, prefix=""):
    flat = {}
    for key, value in table.items():
        if isinstance(value, dict):
            flat.update(_flatten(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def _prepare_output(out: Path, overwrite: bool, resume: bool) -> Path:
    if resume:
        if not (out / CHECKPOINT).exists():
            raise OutputError(f"--resume: {out} holds no {CHECKPOINT} to resume from")
        return out
    if out.exists() and any(out.iterdir()):
        if not overwrite:
            raise OutputError(f"output folder {out} exists and is not empty; pass --overwrite to replace it "
                              "or --resume to continue its run")
        shutil.rmtree(out)
    out.mkdir(parents=True, exist_ok=True)
    return out


@dataclass
class _Schedule:
    every: int  # steps

    def due(self, step: int) -> bool:
        return step % self.every == 0

    def next_after(self, step: int) -> int:
        return (step // self.every + 1) * self.every


@dataclass
class _WriterState:
    pvd_entries: list = field(default_factory=list)
    gas_pvd_entries: list = field(default_factory=list)
    wall_seconds: float = 0.0
    cpu_seconds: float = 0.0
    settled: bool = False
    pressure_history: list = field(default_factory=list)  # (time [s], bed pressure drop [Pa]) rows
    mixing_history: list = field(default_factory=list)  # (time [s], mixing entropy) rows
    # periodic suspension: (time [s], slip Re, settling velocity [m/s], sigma_z, sigma_h [m/s]) rows,
    # and (time [s], orientation-angle density per bin...) rows every tenth sample
    suspension_history: list = field(default_factory=list)
    orientation_history: list = field(default_factory=list)


class Simulation:
    """A case, its model state and (optionally) its output folder.

    Library use::

        case = fvdem.load_case("cases/bed_ar1.toml", {"particles.count": 2000, "time.end": 0.2})
        sim = fvdem.Simulation(case)            # no output folder: nothing is written
        sim.run(0.05)                           # advance 0.05 s of simulated time
        sim.particles.position, sim.diagnostics()
    """

    def __init__(self, case: Case, out_dir=None, *, overwrite: bool = False, resume: bool = False,
                 progress: bool | None = None, threads: int | None = None):
        self.case = case
        self.threads = set_threads(case.run.threads if threads is None else threads)
        self.progress = case.output.progress if progress is None else progress
        self.out = prepare_output(out_dir, overwrite, resume) if out_dir is not None else None
        if resume and self.out is not None:
            check_resumable(case, self.out)
        self.writers = _WriterState()
        # the loop counts DEM steps in a particle-only or uncoupled case, CFD steps (coupling
        # intervals) when the gas is on and coupled, or without particles
        has_particles = case.particles.count > 0
        self.coupled = has_particles and case.gas.enabled and case.coupling.enabled
        # fixed particles never move: only the gas steps (the case refuses them without gas)
        self._gas_steps_only = not has_particles or (case.particles.fixed and not self.coupled)
        # a fully periodic coupled box is a suspension (seed 004): slip Re, fluctuations, orientations
        self.periodic_suspension = self.coupled and all(case.domain.periodic) and not case.particles.fixed
        dt = case.gas.cfd_step if self.coupled or self._gas_steps_only else case.time.dem_step
        self._dt = dt
        self._cfd_every = max(1, round(case.gas.cfd_step / case.time.dem_step)) if has_particles else 1
        self.gas = GasPhase(case) if case.gas.enabled else None
        self.bridge = None
        if case.output.mixing_cells is not None:
            self.mixing_cells = tuple(case.output.mixing_cells)
        elif case.gas.enabled:
            self.mixing_cells = tuple(max(1, n // 2) for n in case.gas.cells)
        else:
            self.mixing_cells = (5, 5, 35)
        self._timeseries_schedule = _Schedule(max(1, round(case.output.timeseries_interval / dt)))
        self._snapshot_schedule = _Schedule(max(1, round(case.output.snapshot_interval / dt)))
        self._checkpoint_schedule = _Schedule(max(1, round(case.output.checkpoint_interval / dt)))
        self._stop_requested = False
        self._cost_reference, self._cost_warned, self._cost_chunks = None, False, 0
        if resume:
            arrays, meta = load_checkpoint(self.out / CHECKPOINT)
            self.dem = None
            if has_particles:
                particles = ParticleArrays.from_dict({k.split(".", 1)[1]: v for k, v in arrays.items()
                                                      if k.startswith("particles.")})
                self.dem = build_dem(case, particles)
                self.dem.restore(arrays)
            if self.coupled:  # before the gas restore: the bridge maps a start-up voidage
                self.bridge = CouplingBridge(case, self.dem, self.gas)
            if self.gas is not None:  # the voidage of the last step, not one mapped from the final positions
                self.gas.restore(arrays)
            self.writers = _WriterState(**meta["writers"])
            self._timeseries().start(resume_time=self.time)
        else:
            self.dem = build_dem(case, build_particles(case)) if has_particles else None
            if self.coupled:
                self.bridge = CouplingBridge(case, self.dem, self.gas)
            if self.out is not None:
                (self.out / "case.toml").write_text(to_toml(case))
                self._timeseries().start()
                self._on_events(self.step_count)

    # ------------------------------------------------------------------ state access
    @property
    def two_colours(self) -> bool:
        """Whether the particles carry two tracer colours (then the mixing is measured)."""
        return self.dem is not None and self.case.particles.colour == "by_height"

    @property
    def particles(self) -> ParticleArrays | None:
        return self.dem.particles if self.dem is not None else None

    @property
    def step_count(self) -> int:
        """Steps of the loop: CFD steps in a coupled or gas-only case, else DEM steps."""
        if self.coupled or self._gas_steps_only:
            return self.gas.step_count
        return self.dem.step_count

    @property
    def time(self) -> float:
        return self.step_count * self._dt

    @property
    def time_step(self) -> float:
        """The loop's step [s]: the CFD step in a coupled or gas-only case, else the DEM step."""
        return self._dt

    def _advance(self, steps: int) -> None:
        """Advance ``steps`` loop steps: coupling intervals (``CouplingBridge.advance``), gas steps (no
        particles, or fixed uncoupled ones), or DEM steps; uncoupled gas and moving particles take a
        gas step every ``cfd_step / dem_step`` DEM steps."""
        if self.coupled:
            for _ in range(steps):
                self.bridge.advance()
            return
        if self._gas_steps_only:
            for _ in range(steps):
                self.gas.step()
            return
        if self.gas is None:
            self.dem.step(steps)
            return
        remaining = steps
        while remaining > 0:
            chunk = min(remaining, self._cfd_every - self.dem.step_count % self._cfd_every)
            self.dem.step(chunk)
            remaining -= chunk
            if self.dem.step_count % self._cfd_every == 0:
                self.gas.step()

    def diagnostics(self) -> dict:
        diag = {"time": self.time}
        if self.gas is not None:
            diag.update(self.gas.diagnostics())
        if self.dem is None:
            return diag
        diag.update(self.dem.diagnostics())
        p = self.particles
        diag["bed_top"] = bed_top(p.position, p.axis, p.radius, p.half_length)
        if self.two_colours:
            lo, hi = self.case.domain.lower, self.case.domain.upper
            diag["mixing_entropy"], diag["lacey_index"] = mixing_indices(p.position, p.colour, lo, hi,
                                                                         self.mixing_cells)
        if self.periodic_suspension:
            diag.update(self._suspension_diagnostics())
        if self.bridge is not None:
            diag.update(self.bridge.diagnostics())
            if "bed_pressure_drop" in diag:
                diag["pressure_drop_over_weight"] = diag["bed_pressure_drop"] / self.bed_weight_per_area()
        return diag

    def _suspension_diagnostics(self) -> dict:
        """Slip Reynolds number ``(1 - phi) (u_f - u_p) d_e / nu`` (seed 004's ``(<u_z> - <u_pz>) d_e / nu``,
        see fvdem.analysis.suspension), the settling velocity [m/s], the particle velocity fluctuations
        [m/s] and the z momentum of particles plus liquid [kg m/s] (zero in a force-balanced box)."""
        p, s, g = self.particles, self.gas.solver, self.case.gas
        fluid = s.flux_velocity()
        settling, phi = settling_velocity(s.voidage, self.gas.mesh.cell_volumes, fluid, p.velocity)
        sigma_z, sigma_h = velocity_fluctuations(p.velocity)
        d_e = self.case.particles.equivalent_diameter
        momentum = float((p.mass * p.velocity[:, 2]).sum()
                         + g.density * (s.voidage * self.gas.mesh.cell_volumes * s.velocity[:, 2]).sum()
                         + self.gas.returned_momentum[:, 2].sum())
        return {"slip_reynolds": settling * d_e * g.density / g.viscosity, "settling_velocity": settling,
                "solids_fraction": phi, "velocity_fluctuation_vertical": sigma_z,
                "velocity_fluctuation_horizontal": sigma_h, "mixture_momentum_z": momentum}

    def bed_weight_per_area(self) -> float:
        """Particle weight over the column's cross-section, W/A [Pa] (the fluidized-bed pressure drop)."""
        lo, hi = np.asarray(self.case.domain.lower), np.asarray(self.case.domain.upper)
        area = (hi[0] - lo[0]) * (hi[1] - lo[1])
        return float(self.particles.mass.sum() * np.linalg.norm(self.case.domain.gravity) / area)

    # ------------------------------------------------------------------ running
    def request_stop(self, *_):
        """Ask the loop to stop at the next chunk boundary (checkpoint written)."""
        self._stop_requested = True

    def run(self, duration: float | None = None) -> dict:
        """Advance ``duration`` [s] of simulated time (default: to ``time.end``), or until settled /
        stopped. Returns the summary dictionary (also written as summary.json with an output folder)."""
        dt = self._dt
        end_time = self.case.time.end if duration is None else self.time + duration
        end_step = int(round(end_time / dt))
        start_step = self.step_count
        bar = self._progress_bar(end_time)
        wall0, cpu0 = _time.perf_counter(), _time.process_time()
        handlers = self._install_signal_handlers()
        try:
            while self.step_count < end_step and not self._stop_requested and not self.writers.settled:
                step = self.step_count
                target = min(end_step, self._next_event(step), step + 500)
                chunk_start = _time.perf_counter()
                self._advance(target - step)
                self._watch_cost(target - step, _time.perf_counter() - chunk_start)
                self._write_guarded(self._on_events, self.step_count)
                if bar is not None:
                    bar.update(self.time - bar.n)
                    elapsed = _time.perf_counter() - wall0
                    if elapsed > 0:
                        bar.set_postfix_str(f"{(self.step_count - start_step) / elapsed:.0f} steps/s",
                                            refresh=False)
        finally:
            self._restore_signal_handlers(handlers)
            if bar is not None:
                bar.close()
            self.writers.wall_seconds += _time.perf_counter() - wall0
            self.writers.cpu_seconds += _time.process_time() - cpu0
        steps = self.step_count - start_step
        summary = self.summary(steps, _time.perf_counter() - wall0)
        if self.out is not None:
            self._write_guarded(self._write_checkpoint)
            self._write_guarded(self._write_final, summary)
        return summary

    def _watch_cost(self, steps: int, seconds: float) -> None:
        """Warn once when the wall time per step grows past ``RUNAWAY_COST`` times the run's first
        measured rate (a bed gone violent: fast particles rebuild the neighbour list every step, large
        overlaps, a gas step struggling), with the numbers that tell which."""
        if steps <= 0 or seconds <= 0:
            return
        rate = seconds / steps
        rebuilds = self.dem.rebuild_count if self.dem is not None else 0
        if self._cost_reference is None:
            self._cost_chunks += 1
            if self._cost_chunks > 1:  # not the first chunk: that one holds numba's compilation
                self._cost_reference = (rate, rebuilds, self.step_count)
            return
        if self._cost_warned or rate < RUNAWAY_COST * self._cost_reference[0]:
            return
        self._cost_warned = True
        ref_rate, ref_rebuilds, ref_step = self._cost_reference
        diag = self.diagnostics()
        gas = (f"; gas: largest speed {diag['gas_max_speed']:.3g} m/s, Courant number {self.gas.courant_number():.3g}"
               if self.gas is not None else "")
        particles = (f"; particles: largest speed {diag['max_speed']:.3g} m/s, largest overlap "
                     f"{diag['max_overlap_over_diameter']:.3g} d, {rebuilds - ref_rebuilds} neighbour-list rebuilds "
                     f"in {self.step_count - ref_step} steps" if self.dem is not None else "")
        warnings.warn(f"t = {self.time:.4g} s: a step costs {rate / ref_rate:.0f} x what it cost at the start "
                      f"({rate * 1e3:.3g} ms against {ref_rate * 1e3:.3g} ms){particles}{gas}. If the bed has gone "
                      "violent, reduce time.dem_step and gas.cfd_step (docs/speed-accuracy.md)",
                      RuntimeWarning, stacklevel=3)

    def _check_gas_runaway(self, diag: dict) -> None:
        """Stop a walled column whose gas runs far faster than anything drives it: the inlet's
        interstitial speed in the densest packing (U / 0.3) and the fastest particle."""
        if self.gas is None or self.gas.solver.periodic or self.gas.config.inlet_velocity <= 0:
            return
        drive = max(self.gas.config.inlet_velocity / 0.3, diag.get("max_speed", 0.0))
        if diag["gas_max_speed"] > RUNAWAY_GAS_SPEED * drive:
            raise SimulationError(
                f"the gas runs away at t = {self.time:.6g} s: largest cell speed {diag['gas_max_speed']:.3g} m/s, "
                f"{diag['gas_max_speed'] / drive:.0f} x the fastest speed the inlet or the particles drive ({drive:.3g} m/s); "
                f"largest Courant number {self.gas.courant_number():.3g} at gas.cfd_step = {self.gas.dt:g} s: reduce "
                "gas.cfd_step (docs/speed-accuracy.md)")

    def _write_guarded(self, write, *args) -> None:
        """Run a writer; a full disk or an unwritable folder stops the run with ``OutputError`` (the
        checkpoint is replaced atomically, so the last complete one stays intact)."""
        try:
            write(*args)
        except OSError as exc:
            where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
            raise OutputError(
                f"writing the output failed at t = {self.time:.6g} s{where}: {exc.strerror or exc}; the last "
                f"complete checkpoint in {self.out} is intact: free space or fix the folder's permissions, then "
                "continue with --resume") from None

    def _next_event(self, step: int) -> int:
        if self.out is None:
            # without an output folder the samples still feed the settled test and the histories the
            # summary reads (t95, pressure drop, suspension statistics)
            records = (self.case.time.stop_when_settled or self.periodic_suspension or self.two_colours
                       or self.bridge is not None)
            return self._timeseries_schedule.next_after(step) if records else step + 10**9
        return min(s.next_after(step) for s in (self._timeseries_schedule, self._snapshot_schedule,
                                                  self._checkpoint_schedule))

    def _on_events(self, step: int) -> None:
        if self._timeseries_schedule.due(step):
            if self.dem is not None:
                self.dem.check_health()
            if self.gas is not None:
                self.gas.check_health(self.time)
            diag = self.diagnostics()
            if "gas_max_speed" in diag:
                self._check_gas_runaway(diag)
            if "pressure_drop_over_weight" in diag and step > 0:
                self.writers.pressure_history.append((self.time, diag["bed_pressure_drop"]))
            if "mixing_entropy" in diag and (not self.writers.mixing_history
                                             or self.writers.mixing_history[-1][0] < self.time):
                self.writers.mixing_history.append((self.time, diag["mixing_entropy"]))
            if self.periodic_suspension and (not self.writers.suspension_history
                                             or self.writers.suspension_history[-1][0] < self.time):
                self.writers.suspension_history.append(
                    (self.time, diag["slip_reynolds"], diag["settling_velocity"],
                     diag["velocity_fluctuation_vertical"], diag["velocity_fluctuation_horizontal"]))
                if len(self.writers.suspension_history) % 10 == 1 and self.particles.half_length.max() > 0:
                    density, _ = orientation_histogram(self.particles.axis)
                    self.writers.orientation_history.append((self.time, *density.tolist()))
            if self.out is not None:
                self._timeseries().append(diag)
            t = self.case.time
            if (self.dem is not None and t.stop_when_settled and self.time >= t.min_time and step > 0
                    and diag["rms_speed"] < t.settled_speed):
                self.writers.settled = True
        if self.out is None:
            return
        if self.case.output.vtk and self._snapshot_schedule.due(step):
            if self.dem is not None:
                name = f"particles_{len(self.writers.pvd_entries):05d}.vtu"
                write_particles_vtu(self.out / name, self.particles)
                self.writers.pvd_entries.append((self.time, name))
                write_pvd(self.out / "particles.pvd", self.writers.pvd_entries)
            if self.gas is not None:
                name = f"gas_{len(self.writers.gas_pvd_entries):05d}.vtu"
                write_gas_vtu(self.out / name, self.gas.mesh, self.gas.solver)
                self.writers.gas_pvd_entries.append((self.time, name))
                write_pvd(self.out / "gas.pvd", self.writers.gas_pvd_entries)
        if self._checkpoint_schedule.due(step) and step > 0:
            self._write_checkpoint()

    def _timeseries(self) -> TimeseriesWriter:
        columns = ("time",) + (TIMESERIES_COLUMNS[1:] if self.dem is not None else ())
        if self.gas is not None:
            columns += GAS_TIMESERIES_COLUMNS
            if self.gas.zone.any():
                columns += ("porous_zone_pressure_gradient",)
            if not self.gas.solver.periodic:
                columns += ("bed_pressure_drop",)
        if self.two_colours:
            columns += ("mixing_entropy", "lacey_index")
        if self.periodic_suspension:
            columns += ("slip_reynolds", "settling_velocity", "velocity_fluctuation_vertical",
                        "velocity_fluctuation_horizontal", "mixture_momentum_z")
        if self.bridge is not None:
            columns += ("over_packed_cells", "total_drag_z", "total_pressure_force_z")
            if not self.gas.solver.periodic:
                columns += ("pressure_drop_over_weight",)
        return TimeseriesWriter(self.out / "timeseries.csv", columns)

    # ------------------------------------------------------------------ outputs
    def summary(self, steps: int = 0, wall: float = 0.0) -> dict:
        diag = self.diagnostics()
        summary = {
            "case": self.case.name,
            "simulated_time": self.time,
            "steps": self.step_count,
            "settled": self.writers.settled,
            "stopped_early": self._stop_requested,
            "threads": self.threads,
            "wall_seconds": self.writers.wall_seconds,
            "cpu_seconds": self.writers.cpu_seconds,
        }
        if self.gas is not None:
            summary.update({k: v for k, v in diag.items() if k.startswith(("gas_", "porous_", "ergun_", "expected_"))})
            summary["gas_cells"] = self.gas.mesh.cell_count
            summary["gas_courant_number"] = self.gas.courant_number()
        if self.dem is None:
            return summary
        n = self.particles.count
        summary.update({
            "particles": n,
            "shape": self.case.particles.shape,
            "ns_per_particle_step_last_run": 1e9 * wall / (steps * n) if steps else None,
            "collision_time": self.case.collision_time(),
            "neighbour_rebuilds": self.dem.rebuild_count,
            **{k: diag[k] for k in ("kinetic_energy", "max_overlap_over_diameter", "contacts_per_particle",
                                    "wall_contacts", "rms_speed", "max_speed")},
        })
        summary.update(packed_bed_summary(self.particles, self.dem.box))
        if self.two_colours:
            history = np.asarray(self.writers.mixing_history, float).reshape(-1, 2)
            summary["mixing_entropy"] = diag["mixing_entropy"]
            summary["lacey_index"] = diag["lacey_index"]
            summary["mixing_cells"] = list(self.mixing_cells)
            summary["t95"] = mixing_time(history[:, 0], history[:, 1]) if len(history) else None
        if self.bridge is not None:
            summary["coupling"] = {"drag": self.bridge.model.drag, "lift": self.bridge.model.lift,
                                   "torque": self.bridge.model.torque,
                                   "drag_treatment": self.case.coupling.drag_treatment,
                                   "voidage": self.case.coupling.voidage}
            summary["bed_weight_per_area"] = self.bed_weight_per_area()
            history = np.asarray(self.writers.pressure_history, float).reshape(-1, 2)
            late = history[history[:, 0] >= 0.5 * self.time] if len(history) else history
            if len(late):
                mean = float(late[:, 1].mean())
                summary.update({"bed_pressure_drop_mean_second_half": mean,
                                "bed_pressure_drop_std_second_half": float(late[:, 1].std()),
                                "pressure_drop_over_weight": mean / self.bed_weight_per_area(),
                                "pressure_samples_second_half": int(len(late))})
        if self.periodic_suspension:
            summary["suspension"] = self.suspension_summary()
        return summary

    def suspension_summary(self) -> dict | None:
        """Steady-window statistics of a periodic suspension: the window (MSER, see
        ``steady_window``), the mean slip Reynolds number with its batch-means standard error, the
        velocity fluctuations over the mean settling velocity, and the orientation-angle density over
        the window against the random ``sin`` (spherocylinders)."""
        rows = np.asarray(self.writers.suspension_history, float).reshape(-1, 5)
        if len(rows) < 20:
            return None
        window = steady_window(rows[:, 0], rows[:, 1])
        steady = rows[rows[:, 0] >= window["start"]]
        settling = float(steady[:, 2].mean())
        p = self.case.particles
        out = {"window_start": window["start"], "window_end": float(rows[-1, 0]), "samples": window["samples"],
               "slip_reynolds": window["mean"], "slip_reynolds_standard_error": window["standard_error"],
               "slip_reynolds_std": window["std"], "settling_velocity": settling,
               "solids_fraction": float(p.count * p.volume / np.prod(np.subtract(self.case.domain.upper,
                                                                                  self.case.domain.lower))),
               "velocity_fluctuation_vertical_over_settling": float(np.sqrt((steady[:, 3] ** 2).mean())) / settling,
               "velocity_fluctuation_horizontal_over_settling": float(np.sqrt((steady[:, 4] ** 2).mean())) / settling,
               "equivalent_diameter": p.equivalent_diameter,
               "kinematic_viscosity": self.case.gas.viscosity / self.case.gas.density}
        orientation = np.asarray(self.writers.orientation_history, float)
        if len(orientation):
            late = orientation[orientation[:, 0] >= window["start"]]
            late = late if len(late) else orientation[-1:]
            edges = np.linspace(0.0, 0.5 * np.pi, orientation.shape[1])
            centres = 0.5 * (edges[1:] + edges[:-1])
            density = late[:, 1:].mean(axis=0)
            out.update({"orientation_angle_centres": centres.tolist(), "orientation_density": density.tolist(),
                        "orientation_random_density": np.sin(centres).tolist(),
                        "mean_abs_cos_vertical": float((np.cos(centres) * density).sum() * (edges[1] - edges[0])),
                        "orientation_samples": int(len(late))})
        return out

    def _write_checkpoint(self) -> None:
        meta = {"writers": asdict(self.writers), "time": self.time}
        state = {}
        if self.dem is not None:
            state.update(self.dem.state())
        if self.gas is not None:
            state.update(self.gas.state())
        save_checkpoint(self.out / CHECKPOINT, state, meta)

    def _write_final(self, summary: dict) -> None:
        p = self.particles
        if p is not None:
            order = np.argsort(p.ids, kind="stable")
            tmp = self.out / (FINAL_STATE + ".tmp")
            with open(tmp, "wb") as fh:
                np.savez(fh, **{k: v[order] for k, v in p.as_dict().items()})
            os.replace(tmp, self.out / FINAL_STATE)
        (self.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")

    def _progress_bar(self, end_time: float):
        if not self.progress:
            return None
        from .io.progress import progress_bar
        return progress_bar(end_time, self.time, f"{self.case.name} (simulated s)")

    def _install_signal_handlers(self):
        if self.out is None:
            return None
        try:
            return {s: signal.signal(s, self.request_stop) for s in (signal.SIGINT, signal.SIGTERM)}
        except ValueError:  # not in the main thread
            return None

    @staticmethod
    def _restore_signal_handlers(handlers) -> None:
        for sig, handler in (handlers or {}).items():
            signal.signal(sig, handler)

    @property
    def stopped_early(self) -> bool:
        return self._stop_requested


__all__ = ["Simulation", "SimulationError", "OutputError", "build_particles", "build_dem", "prepare_output"]
