"""The time loop of a case: builds the model and the scene, advances, runs the writers on schedules.

``Simulation.run`` advances in chunks of loop steps up to the next scheduled event; at an event it
(in this order) checks the state's health, measures what the scene declares and appends a
``timeseries.csv`` row, writes a VTU snapshot, writes a checkpoint, and tests the stop criterion.
Writers only read the state, so a run resumed from a checkpoint continues bit-for-bit.
"""
from __future__ import annotations

import time as _time
from dataclasses import asdict
from pathlib import Path

from .case import Case, to_toml
from .errors import SimulationError
from .io.checkpoint import load_checkpoint
from .io.locks import folder_lock
from .io.run_folder import (CHECKPOINT, OutputError, RunState, Schedule, guarded_write, open_output, prepare_output,
                            write_checkpoint, write_final, write_snapshot)
from .io.progress import advance_bar, progress_bar
from .io.run_log import RunLog
from .io.timeseries import TimeseriesWriter
from .model import Model, build_dem, build_particles, load_initial_state, set_threads
from .monitors import RunawayWatch
from .provenance import describe, peak_memory_mb, provenance
from .scenes import scene_for
from .signals import stop_on_signals
from .timing import Timings


class Simulation:
    """A case, its model state and (optionally) its output folder.

    Library use::

        case = fvdem.load_case("cases/bed_ar1.toml", {"particles.count": 2000, "time.end": 0.2})
        sim = fvdem.Simulation(case)            # no output folder: nothing is written
        sim.run(0.05)                           # advance 0.05 s of simulated time
        sim.particles.position, sim.diagnostics()
    """

    def __init__(self, case: Case, out_dir=None, *, overwrite: bool = False, resume: bool = False,
                 progress: bool | None = None, threads: int | None = None, stop_file=None):
        self.case = case
        # a file whose appearance stops the run like SIGTERM (checkpoint written), or a callable saying when
        # (once per chunk): how a study stops runs in Dask workers (no signals there) and before a walltime
        self._stop_when = stop_file if callable(stop_file) else (Path(stop_file).exists if stop_file else None)
        self.threads = set_threads(case.run.threads if threads is None else threads)
        self.progress = case.output.progress if progress is None else progress
        self._lock = folder_lock(out_dir, {"case": case.name})  # one writer per folder (``fvdem.io.locks``)
        with self._lock:  # here and in each run(): another process writing the folder is refused (FolderInUse)
            self.out = open_output(out_dir, case, overwrite, resume) if out_dir is not None else None
            self.log = RunLog(self.out)  # run.log: provenance, progress, warnings (nothing without a folder)
            with self.log.warnings_captured():
                self._build(case, resume)

    def _build(self, case: Case, resume: bool) -> None:
        """The scene, the model (from the checkpoint when resuming), the schedules and the writers."""
        made_by = describe(provenance(self.threads))
        arrays, meta = load_checkpoint(self.out / CHECKPOINT) if resume else (None, None)
        self.log.start(case.name, made_by, meta["time"] if resume else None)
        self.scene = scene_for(case)
        self.run_state = (RunState(histories=self.scene.new_histories()) if meta is None
                          else RunState.from_checkpoint(meta["writers"], self.scene.new_histories()))
        self.model = Model(case, arrays, Timings(self.run_state.timings))
        self.watch = RunawayWatch(self.model)
        o, dt = case.output, self.model.time_step
        self.schedules = {name: Schedule(max(1, round(interval / dt))) for name, interval in
                          (("timeseries", o.timeseries_interval), ("snapshot", o.snapshot_interval),
                           ("checkpoint", o.checkpoint_interval))}
        self._stop_requested = False
        self._segment = None  # (wall, cpu) clocks at the start of the current run() call
        if self.out is not None:
            self._timeseries = TimeseriesWriter(self.out / "timeseries.csv", self.scene.columns(self.model))
            if resume:
                self._timeseries.start(resume_time=self.time)
            else:
                (self.out / "case.toml").write_text(to_toml(case, header=f"made by {made_by}"))
                self._timeseries.start()
                self._on_events(self.step_count)

    # ------------------------------------------------------------------ state access
    dem = property(lambda self: self.model.dem)
    gas = property(lambda self: self.model.gas)
    bridge = property(lambda self: self.model.bridge)
    particles = property(lambda self: self.model.particles)
    step_count = property(lambda self: self.model.step_count, doc="CFD steps when coupled or gas only, else DEM steps")
    time = property(lambda self: self.model.time)
    time_step = property(lambda self: self.model.time_step, doc="the loop's step [s]")
    stopped_early = property(lambda self: self._stop_requested)

    def diagnostics(self) -> dict:
        """This instant's values of everything the scene measures."""
        return self.scene.measure(self.model)

    # ------------------------------------------------------------------ running
    def request_stop(self, *_):
        """Ask the loop to stop at the next chunk boundary (checkpoint written)."""
        self._stop_requested = True

    def run(self, duration: float | None = None) -> dict:
        """Advance ``duration`` [s] (default: to ``time.end``), or until the scene ends the run (settled, mixed)
        or it is stopped. Returns the summary dictionary (also written as summary.json with an output folder)."""
        with self._lock:
            return self._run(duration)

    def _run(self, duration: float | None) -> dict:
        end_time = self.case.time.end if duration is None else self.time + duration
        if self.run_state.ended:  # ended before (e.g. resumed): still, under this case's criteria?
            self.run_state.ended = self.scene.ends(self.model, self.diagnostics(), self.run_state.histories)
        end_step = int(round(end_time / self.time_step))
        start_step = self.step_count
        bar = progress_bar(end_time, self.time, f"{self.case.name} (simulated s)") if self.progress else None
        wall0, cpu0 = self._segment = _time.perf_counter(), _time.process_time()
        self.log.start_progress(self.time, end_time)
        try:
            with stop_on_signals(self.request_stop, self.out is not None), self.log.warnings_captured():
                self._advance_to(end_step, bar, wall0, start_step)
        except Exception as exc:
            self.log.line(f"error at t = {self.time:.6g} s: {type(exc).__name__}: {exc}")
            raise
        finally:
            if bar is not None:
                bar.close()
            self.run_state.wall_seconds += _time.perf_counter() - wall0
            self.run_state.cpu_seconds += _time.process_time() - cpu0
            self.run_state.timings = dict(self.model.timings.seconds)
            self._segment = None
        summary = self.summary(self.step_count - start_step, _time.perf_counter() - wall0)
        if self.out is not None:
            self._write_guarded(self._write_checkpoint)
            self._write_guarded(write_final, self.out, self.particles, summary)
            self.log.end(summary, self._stop_requested, self.run_state.ended)
        return summary

    def _advance_to(self, end_step: int, bar, wall0: float, start_step: int) -> None:
        """The loop: chunks of steps up to the next event, the events, the progress bar and log."""
        while self.step_count < end_step and not self._stop_requested and not self.run_state.ended:
            step = self.step_count
            target = min(end_step, self._next_event(step), step + 500)
            chunk_start = _time.process_time()
            self.model.advance(target - step)
            # CPU time, not wall: a suspended run (SIGSTOP, sleep) or one sharing its cores is no runaway
            self.watch.cost(target - step, _time.process_time() - chunk_start)
            if self._stop_when is not None and self._stop_when():
                self._stop_requested = True
            events_start = _time.perf_counter()
            self._write_guarded(self._on_events, self.step_count)
            self.model.timings.add("output", _time.perf_counter() - events_start)
            elapsed = _time.perf_counter() - wall0
            rate = (self.step_count - start_step) / elapsed if elapsed > 0 else None
            self.log.progress(self.time, rate)
            advance_bar(bar, self.time, rate)

    def summary(self, steps: int = 0, wall: float = 0.0) -> dict:
        """The run's summary: time, steps, cost, and what the scene's observables derive."""
        summary = {"case": self.case.name, "simulated_time": self.time, "steps": self.step_count,
                   "settled": self.run_state.ended == "settled", "ended": self.run_state.ended or None,
                   "stopped_early": self._stop_requested, "threads": self.threads,
                   "wall_seconds": self.run_state.wall_seconds, "cpu_seconds": self.run_state.cpu_seconds,
                   "timings": self.model.timings.table(self.run_state.wall_seconds),
                   "provenance": provenance(self.threads), "peak_memory_mb": peak_memory_mb()}
        summary.update(self.scene.summary(self.model, self.diagnostics(), self.run_state.histories,
                                          {"steps": steps, "wall": wall}))
        return summary

    # ------------------------------------------------------------------ events
    def _next_event(self, step: int) -> int:
        if self.out is None:  # the samples still feed the end tests and the histories the summary reads
            samples = self.case.time.stop_when_settled or self.scene.keeps_history
            return self.schedules["timeseries"].next_after(step) if samples else step + 10**9
        return min(s.next_after(step) for s in self.schedules.values())

    def _on_events(self, step: int) -> None:
        if self.schedules["timeseries"].due(step):
            self.model.check_health()
            values = self.diagnostics()
            if "gas_max_speed" in values:
                self.watch.gas(values)
            self.watch.particles(values)
            self.scene.record(self.model, values, self.run_state.histories)
            if self.out is not None:
                self._timeseries.append(values)
            self.run_state.ended = self.scene.ends(self.model, values, self.run_state.histories)
        if self.out is None:
            return
        if self.case.output.vtk and self.schedules["snapshot"].due(step):
            write_snapshot(self.out, self.model, self.run_state.snapshots)
        if self.schedules["checkpoint"].due(step) and step > 0:
            self._write_checkpoint()

    def _write_checkpoint(self) -> None:
        """The model's arrays and the run state as of now (cost so far included: a killed run keeps it)."""
        state = asdict(self.run_state)
        state["timings"] = dict(self.model.timings.seconds)
        if self._segment is not None:
            state["wall_seconds"] += _time.perf_counter() - self._segment[0]
            state["cpu_seconds"] += _time.process_time() - self._segment[1]
        write_checkpoint(self.out, self.model, {"writers": state, "time": self.time})

    def _write_guarded(self, write, *args) -> None:
        """Run a writer; a full disk or an unwritable folder stops the run (``run_folder.guarded_write``)."""
        guarded_write(write, args, self.time, self.out)

__all__ = ["Simulation", "SimulationError", "OutputError", "build_particles", "build_dem", "load_initial_state",
           "prepare_output"]
