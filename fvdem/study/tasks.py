"""What runs on a Dask worker: one bed or run of a study, resumed from its checkpoint, stopped through the
study's stop file, paused before its batch job's walltime. Nothing here knows what a run measures: a
run's result carries the values its study's report asks for (``reports``)."""
from __future__ import annotations

import json
import time
from pathlib import Path

from typing import TYPE_CHECKING

from ..case import CaseError, load_case
from .cluster import job_deadline
from .records import Outcome, run_at_end, simulated_so_far

if TYPE_CHECKING:
    from .specs import BedSpec, RunSpec


STOP_FILE = "STOP"  # in a study folder: running runs checkpoint and stop, queued ones do not start

# s: how long a worker past its job's deadline holds a run it cannot start before it gives it back; the study
# retires such a worker (``_retire``), so this only paces the returns when Dask declined to retire it
PAUSED_RETURN_DELAY = 2.0


def run_finished(run: RunSpec) -> bool:
    """Whether a study's run is at its end under its case as the study now sets it (False where the case
    cannot be read: the study's own check names the cause)."""
    try:
        case = load_case(run.case, {**run.overrides, "output.progress": False})
    except CaseError:
        return False
    return run_at_end(Path(run.folder), case)


def _study_stop_file(folder) -> Path:
    """``OUT/STOP`` of the study that ``folder`` (``OUT/runs/<name>`` or ``OUT/beds/<name>``) belongs to."""
    return Path(folder).parent.parent / STOP_FILE


def _simulate(case_path, overrides, folder, threads, deadline: float | None = None) -> dict:
    """Run (or resume, or skip) one case into ``folder``; returns status and summary. A run stopped
    through the study's stop file checkpoints and comes back ``stopped``; one that would run past
    ``deadline`` (epoch seconds: its batch job's walltime less a margin, ``job_deadline``) checkpoints
    before it and comes back ``paused``, for the study to resubmit in another job."""
    from ..simulation import Simulation
    folder = Path(folder)
    case = load_case(case_path, {**overrides, "output.progress": False})
    if run_at_end(folder, case):
        return {"status": Outcome.SKIPPED, "summary": json.loads((folder / "summary.json").read_text())}
    stop_file = _study_stop_file(folder)
    so_far = {"simulated_time": simulated_so_far(folder), "stopped_early": True}
    if stop_file.exists():
        return {"status": Outcome.STOPPED, "summary": so_far}
    if deadline is not None and time.time() >= deadline:
        # a job on its way out took the run: give it back (the study then retires this worker)
        time.sleep(PAUSED_RETURN_DELAY)
        return {"status": Outcome.PAUSED, "started": False, "summary": so_far}
    stop = _StopWhen(stop_file, deadline)
    resume = (folder / "checkpoint.npz").exists()
    summary = Simulation(case, folder, resume=resume, overwrite=not resume, threads=threads, progress=False,
                         stop_file=stop).run()
    if summary.get("stopped_early"):
        return {"status": Outcome.PAUSED if stop.deadline_reached else Outcome.STOPPED, "started": True,
                "summary": summary}
    return {"status": Outcome.RESUMED if resume else Outcome.FINISHED, "summary": summary}


class _StopWhen:
    """A run's stop condition, checked once per chunk: the study's stop file, or a chunk that would end past
    ``deadline`` (the next chunk taken to last as long as the last one did, with half as much again)."""

    def __init__(self, stop_file: Path, deadline: float | None):
        self.stop_file, self.deadline = stop_file, deadline
        self.deadline_reached = False
        self._last = time.time()

    def __call__(self) -> bool:
        if self.stop_file.exists():
            return True
        now = time.time()
        chunk, self._last = now - self._last, now
        if self.deadline is not None and now + 1.5 * chunk >= self.deadline:
            self.deadline_reached = True
        return self.deadline_reached


def prepare_bed(bed: BedSpec, threads: int) -> str:
    """A settled bed's final state (prepared once; the runs starting from it depend on this task)."""
    outcome = _simulate(bed.case, bed.overrides, bed.folder, threads)
    if outcome["status"] == Outcome.STOPPED:
        raise StudyStopped(f"bed {bed.name} stopped before it settled")
    return str(Path(bed.folder) / "final_state.npz")


class StudyStopped(RuntimeError):
    """The study was asked to stop (its stop file) before this task finished."""


def run_task(run: RunSpec, threads: int, bed_state: str | None = None) -> dict:
    """One run of the study; never raises: a failure comes back with its cause. A run that ended carries
    the values of its summary its study's report keeps (``StudyReport.run_values``)."""
    from .registry import report_for
    started = time.perf_counter()
    overrides = dict(run.overrides)
    if bed_state is not None:
        overrides["particles.initial_state"] = bed_state
    try:
        outcome = _simulate(run.case, overrides, run.folder, threads, job_deadline())
    except Exception as exc:  # noqa: BLE001  (any failure of one run is reported, the others go on)
        from ..io.run_log import log_tail
        return {"name": run.name, "family": run.family, "status": Outcome.FAILED,
                "error": f"{type(exc).__name__}: {exc}", "folder": run.folder, "simulated_seconds": 0.0,
                "point": run.point, "wall_seconds": time.perf_counter() - started, "log_tail": log_tail(run.folder)}
    summary = outcome["summary"]
    chosen = report_for(run.report)
    return {"name": run.name, "family": run.family, "status": outcome["status"],
            "folder": run.folder, "simulated_seconds": summary["simulated_time"], "point": run.point,
            **(chosen.run_values(summary) if chosen.run_values else {}),
            **({"ended": summary["ended"]} if summary.get("ended") else {}),  # early, by a stop condition
            "wall_seconds": time.perf_counter() - started,
            **({"started": outcome["started"], "worker": _worker_address()}
               if outcome["status"] == Outcome.PAUSED else {})}


def _worker_address() -> str | None:
    """The Dask worker running this task (None outside one): a paused run names it, so that the study
    retires it (its job is at its end) before the run goes back into the queue."""
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return None
