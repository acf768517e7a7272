"""What a run folder holds, read by every part of the study engine: the run-status words, a run's summary, time
series, case and simulated seconds, and its folder from a ``study.json`` entry. A leaf of the study package
(it imports no other module of it)."""
from __future__ import annotations

import json
from enum import Enum
from pathlib import Path

from ..case import CaseError, load_case


# A run's status (study.json, the table): a task's result says "finished" or "resumed" (it reached its end in
# this call), "skipped" (it had before), "stopped" or "paused" (checkpointed before its end: the study's stop
# file, its job's walltime) or "failed" (with the cause); the study lists a run without a result "pending";
# the report derives "running" (its time series has passed its summary), "pending" (it ended before its
# duration was raised) and "not planned" (the study file no longer lists it, its folder holds something and it
# has not ended: ``write_index`` flags its entry ``"planned": false``; neither counted nor drawn)
ENDED = ("finished", "resumed", "skipped")
IN_PROGRESS = ("pending", "stopped", "paused", "running")
FAILED = "failed"
NOT_PLANNED = "not planned"


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


class RunState(str, Enum):
    """Where a run of a study stands, read from its folder (``classify_run``): what ``fvdem study --status``
    lists and what decides which runs a folder's tidying leaves alone."""

    RUNNING = "running"  # a process holds its folder's lock
    ENDED = "ended"  # its summary shows its end (its duration, or an end the case stops at) and nothing after it
    FAILED = "failed"  # its last task failed
    IN_PROGRESS = "in progress"  # simulated time and a checkpoint to resume from
    PARTIAL = "partial"  # simulated time but no checkpoint: it starts again
    NOT_STARTED = "not started"
    NOT_PLANNED = "not planned"  # out of the study file before its end: listed, not counted


def classify_run(folder: Path, entry: dict, summary: dict | None = None, series=None) -> RunState:
    """Where one run stands: its folder (``entry_folder``), its ``study.json`` entry (``duration``, ``status``,
    ``planned``), and its summary and time series where the caller has read them (else read here)."""
    from ..io.locks import holder
    from ..io.run_folder import CHECKPOINT
    summary = read_summary(folder) or {} if summary is None else summary
    series = read_series(folder) if series is None else series
    held = float(series["time"][-1]) if series is not None else float(summary.get("simulated_time") or 0.0)
    duration = entry.get("duration")
    at_end = bool(summary) and not summary.get("stopped_early") and (
        bool(summary.get("ended")) or duration is None
        or float(summary.get("simulated_time") or 0.0) >= duration * (1 - 1e-9))
    if holder(folder) is not None:
        state = RunState.RUNNING
    elif at_end and held <= float(summary.get("simulated_time") or 0.0) + 1e-9:
        state = RunState.ENDED
    elif entry.get("status") == FAILED:
        state = RunState.FAILED
    elif held > 0:
        state = RunState.IN_PROGRESS if (folder / CHECKPOINT).exists() else RunState.PARTIAL
    else:
        state = RunState.NOT_STARTED
    if entry.get("planned") is False and state not in (RunState.ENDED, RunState.RUNNING):
        state = RunState.NOT_PLANNED
    return state
