"""A run's log, ``run.log`` in its folder: what made the run (``fvdem.provenance``), a progress line
every ``step_percent`` of simulated time, every warning as one readable line, how the run ended, and
the timing table. Appended to on resume, so one file tells a run's whole history; a study's worker
writes it like ``fvdem run`` (its warnings would otherwise be lost in the worker's standard error).
"""
from __future__ import annotations

import contextlib
import datetime
import time as _time
import warnings
from pathlib import Path

LOG = "run.log"


def warning_line(message, category) -> str:
    """A warning as one line: ``warning (RuntimeWarning): <message>``, whitespace folded."""
    return f"warning ({category.__name__}): {' '.join(str(message).split())}"


class RunLog:
    """Appends timestamped lines to ``folder/run.log``; with ``folder`` None (a run without an output
    folder) every method does nothing."""

    def __init__(self, folder, step_percent: float = 5.0):
        self.path = Path(folder) / LOG if folder is not None else None
        self.step = step_percent
        self._next = None

    def start(self, case_name: str, made_by: str, resumed_at: float | None) -> None:
        self.line(f"{'started' if resumed_at is None else 'resumed at t = %.6g s' % resumed_at}: {case_name}, "
                  f"{made_by}")

    def end(self, summary: dict, stopped: bool, ended: str) -> None:
        """How the run ended (``ended``: a scene's early end, "settled" or "mixed", else "") and its timing table."""
        from ..timing import format_table
        how = ("stopped (checkpoint written; resume with --resume)" if stopped else
               f"ended time.stop_after_mixed past its mixing time (t95 {summary.get('t95', 0.0):.4g} s)"
               if ended == "mixed" else ended or "reached its end")
        self.line(f"{how} at t = {summary['simulated_time']:.6g} s after {summary['wall_seconds']:.0f} s wall in all")
        self.line(format_table(summary["timings"], summary["threads"], summary["steps"], summary["simulated_time"]))

    def line(self, text: str) -> None:
        if self.path is None:
            return
        stamp = datetime.datetime.now().astimezone().isoformat(timespec="seconds")
        with open(self.path, "a", encoding="utf-8") as fh:
            for part in str(text).splitlines() or [""]:
                fh.write(f"{stamp}  {part}\n")

    def start_progress(self, time: float, end: float) -> None:
        self._end, self._wall0, self._time0 = end, _time.perf_counter(), time
        self._next = self._following(time)

    def _following(self, time: float) -> float:
        percent = 100.0 * time / self._end if self._end > 0 else 100.0
        return (int(percent // self.step + 1e-9) + 1) * self.step

    def progress(self, time: float, steps_per_second: float | None = None) -> None:
        """A line when simulated time crosses the next ``step_percent`` of the run's end."""
        if self.path is None or self._next is None or self._end <= 0 or 100.0 * time / self._end + 1e-9 < self._next:
            return
        elapsed = _time.perf_counter() - self._wall0
        done = time - self._time0
        left = elapsed * (self._end - time) / done if done > 0 else float("nan")
        rate = f", {steps_per_second:.0f} steps/s" if steps_per_second else ""
        self.line(f"progress {100.0 * time / self._end:3.0f}%: t = {time:.4f} of {self._end:.4f} s{rate}, "
                  f"{elapsed:.0f} s wall, {left:.0f} s left")
        self._next = self._following(time)

    @contextlib.contextmanager
    def warnings_captured(self):
        """While the block runs, every warning shown is also written here as one line."""
        if self.path is None:
            yield self
            return
        shown = warnings.showwarning

        def show(message, category, filename, lineno, file=None, line=None):
            with contextlib.suppress(OSError):  # a full disk: the run's own writers report it
                self.line(warning_line(message, category))
            shown(message, category, filename, lineno, file, line)

        warnings.showwarning = show
        try:
            yield self
        finally:
            warnings.showwarning = shown


def tail_lines(path, size: int = 16384) -> list[str]:
    """The non-blank lines of a file's last ``size`` bytes (the first may be partial); empty when the
    file cannot be read. For a log or a time series that a run appends to."""
    try:
        with open(path, "rb") as fh:
            fh.seek(0, 2)
            fh.seek(max(0, fh.tell() - size))
            text = fh.read().decode("utf-8", "replace")
    except OSError:
        return []
    return [line for line in text.splitlines() if line.strip()]


def log_tail(folder, lines: int = 8) -> list[str]:
    """The last ``lines`` lines of a run folder's log (empty without one)."""
    return tail_lines(Path(folder) / LOG)[-lines:]
