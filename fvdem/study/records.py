"""What a run folder holds and where a run stands, read by every part of the study engine and by the reports: a
run's summary, time series, case and simulated seconds, its folder from a ``study.json`` entry, the words a study
records of a run (``Outcome``) and the one decision of where a run stands (``RunState``, ``classify_run``, on the
rules ``at_end`` and ``series_ahead``). A leaf of the study package (it imports no other module of it)."""
from __future__ import annotations

import json
from enum import StrEnum
from pathlib import Path

from ..case import CaseError, load_case


class RunState(StrEnum):
    """Where a run of a study stands, read from its folder (``classify_run``): what ``fvdem study --status``
    lists, what decides which runs a folder's tidying leaves alone, and what each word on record puts a run at
    (``Outcome.state``: the table's rows, the findings)."""

    ENDED = "ended"  # its summary shows its end (its duration, or an end the case stops at) and nothing after it
    RUNNING = "running"  # a process holds its folder's lock
    IN_PROGRESS = "in progress"  # simulated time and a checkpoint to resume from
    PARTIAL = "partial"  # simulated time but no checkpoint: it starts again
    NOT_STARTED = "not started"
    FAILED = "failed"  # its last task failed
    NOT_PLANNED = "not planned"  # out of the study file before its end: listed, not counted

    @property
    def on_the_way(self) -> bool:
        """Whether the run may yet bring a result: neither ended, failed nor out of the study file."""
        return self not in (RunState.ENDED, RunState.FAILED, RunState.NOT_PLANNED)


class Outcome(StrEnum):
    """What a study records of a run (``study.json``'s and the table's ``status``): its last task's word, or
    "pending" without a result; the report corrects the word by what the run's folder holds (``fvdem.study.
    reports.report``). Not where the run stands: ``state`` puts each word at a ``RunState``."""

    FINISHED = "finished"  # it reached its end in that task
    RESUMED = "resumed"  # the same, from a checkpoint
    SKIPPED = "skipped"  # it was at its end before
    STOPPED = "stopped"  # checkpointed before its end: the study's stop file
    PAUSED = "paused"  # checkpointed before its end: its batch job's walltime (resubmitted)
    FAILED = "failed"  # with the cause
    PENDING = "pending"  # no result yet, or (the report) it ended before its duration was raised: more to run
    RUNNING = "running"  # the report: its time series has passed its summary (on its way again)
    NOT_PLANNED = "not planned"  # the report: the study file no longer lists it and it has not ended

    @property
    def state(self) -> RunState:
        """Where a run this word is on record for stands."""
        return _STATE_OF[self]


_STATE_OF = {Outcome.FINISHED: RunState.ENDED, Outcome.RESUMED: RunState.ENDED, Outcome.SKIPPED: RunState.ENDED,
             Outcome.STOPPED: RunState.IN_PROGRESS, Outcome.PAUSED: RunState.IN_PROGRESS,
             Outcome.RUNNING: RunState.IN_PROGRESS, Outcome.PENDING: RunState.NOT_STARTED,
             Outcome.FAILED: RunState.FAILED, Outcome.NOT_PLANNED: RunState.NOT_PLANNED}


def state_of(status: str) -> RunState:
    """Where a run stands whose ``status`` (a table row's, a ``study.json`` entry's) is on record (``Outcome``)."""
    return Outcome(status).state


def early_end(summary: dict) -> str | None:
    """The stop condition (``fvdem.scenes.stops``) a run's summary says it ended by before its end time (its
    ``ended``; a summary written before fvdem recorded that says ``settled``), None where it did not."""
    return summary.get("ended") or ("settled" if summary.get("settled") else None)


def at_end(summary: dict | None, duration: float | None = None, case=None) -> bool:
    """Whether ``summary`` (a run's ``summary.json``) shows the run at its end: not stopped early, and its
    duration reached (``duration`` [s], else ``case``'s ``time.end``; without either, any summary of a whole run)
    or ended early by a stop condition (``early_end``): under ``case`` one the case still sets
    (``StopCondition.still_ends``: a margin raised since sends the run on), without a case whichever it recorded."""
    if not summary or summary.get("stopped_early"):
        return False
    end = case.time.end if case is not None else duration
    if end is None or float(summary.get("simulated_time") or 0.0) >= end * (1 - 1e-9):
        return True
    why = early_end(summary)
    if case is None or why is None:
        return why is not None
    from ..scenes.stops import STOP_CONDITIONS
    condition = STOP_CONDITIONS.get(why)
    return condition is not None and condition.still_ends(summary, case)


def run_at_end(folder: Path, case) -> bool:
    """Whether a run folder's summary shows the run at its end under ``case`` (``at_end``): its end time reached,
    or ended early by a stop condition the case still sets."""
    return at_end(read_summary(folder), case=case)


def ended_early(summary: dict | None) -> bool:
    """Whether a run's summary shows it ended before its end time by a stop condition its case set."""
    return bool(summary) and not summary.get("stopped_early") and early_end(summary) is not None


def series_ahead(summary: dict | None, series) -> bool:
    """Whether a run's time series (``read_series``) holds simulated time its summary does not: a run on its way
    (no summary yet, the summary of a stop, or of an end before its duration was raised)."""
    return series is not None and (not summary or bool(summary.get("stopped_early"))
                                   or float(series["time"][-1]) > float(summary.get("simulated_time") or 0.0) + 1e-9)


def read_summary(folder: Path) -> dict | None:
    """A run folder's ``summary.json`` (None without one, or while it cannot be read: being written)."""
    try:
        return json.loads((Path(folder) / "summary.json").read_text())
    except (OSError, json.JSONDecodeError):
        return None


def entry_folder(out, entry: dict) -> Path:
    """A run's folder from its ``study.json`` entry: absolute in a study folder's index, relative to the folder
    ``out`` in an archive's."""
    return Path(entry["folder"]) if Path(entry["folder"]).is_absolute() else Path(out) / entry["folder"]


def folder_case(folder: Path):
    """The case a run folder's ``case.toml`` holds (``load_case``: units, defaults); None without a readable one."""
    try:
        return load_case(Path(folder) / "case.toml")
    except (CaseError, OSError):
        return None


def simulated_so_far(folder: Path, live: bool = False) -> float:
    """Simulated seconds a run folder holds: its summary's, else its checkpoint's (0 for a new run);
    ``live``: the last line of its time series instead of the checkpoint (a run in progress)."""
    try:
        summary = read_summary(folder)
        if summary is not None and not summary.get("stopped_early"):
            return float(summary["simulated_time"])
        if live and (folder / "timeseries.csv").exists():
            return last_time(folder / "timeseries.csv")
        if summary is not None:
            return float(summary["simulated_time"])
        if (folder / "checkpoint.npz").exists():
            import numpy as np
            with np.load(folder / "checkpoint.npz") as data:
                return float(json.loads(bytes(data["__meta__"]).decode())["time"]) if "__meta__" in data.files else 0.0
    except (OSError, KeyError, ValueError):
        pass
    return 0.0


def last_time(path: Path) -> float:
    """The time column of a time series' last complete line (read from the end of the file)."""
    from ..io.run_log import tail_lines
    for line in reversed(tail_lines(path, 4096)):
        try:
            return float(line.split(",", 1)[0])
        except ValueError:
            continue
    return 0.0


def read_series(folder: Path):
    """A run's time series (``read_timeseries``), or None while it has none or only its header."""
    from ..analysis.plots import read_timeseries
    if not (folder / "timeseries.csv").exists():
        return None
    try:
        series = read_timeseries(folder)
    except (IndexError, ValueError):  # a run that has written its header only
        return None
    return series if len(series.get("time", ())) else None


def classify_run(folder: Path, entry: dict, summary: dict | None = None, series=None) -> RunState:
    """Where one run stands: its folder (``entry_folder``), its ``study.json`` entry (``duration``, ``status``,
    ``planned``), and its summary and time series where the caller has read them (else read here)."""
    from ..io.locks import holder
    from ..io.run_folder import CHECKPOINT
    summary = read_summary(folder) or {} if summary is None else summary
    series = read_series(folder) if series is None else series
    held = float(series["time"][-1]) if series is not None else float(summary.get("simulated_time") or 0.0)
    if holder(folder) is not None:
        state = RunState.RUNNING
    elif at_end(summary, entry.get("duration")) and not series_ahead(summary, series):
        state = RunState.ENDED
    elif entry.get("status") == Outcome.FAILED:
        state = RunState.FAILED
    elif held > 0:
        state = RunState.IN_PROGRESS if (folder / CHECKPOINT).exists() else RunState.PARTIAL
    else:
        state = RunState.NOT_STARTED
    if entry.get("planned") is False and state not in (RunState.ENDED, RunState.RUNNING):
        state = RunState.NOT_PLANNED
    return state
