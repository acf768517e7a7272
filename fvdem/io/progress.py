"""Progress of a long run: a tqdm bar on a terminal, a plain line every few per cent in a log.

A carriage-return bar written to a file is a stream of partial lines (a 4-minute run wrote 200 KB
of them); when standard error is not a terminal, ``LineProgress`` prints one line per
``step_percent`` of simulated time instead: the simulated time, the rate and the estimated time left.
"""
from __future__ import annotations

import sys
import time as _time


class LineProgress:
    """The part of tqdm's interface ``Simulation.run`` uses (``n``, ``update``, ``set_postfix_str``,
    ``close``), printing ``desc: 35% 0.7000/2.0000 s, 92 steps/s, elapsed 0:00:15, left 0:00:28``."""

    def __init__(self, total: float, initial: float = 0.0, desc: str = "", step_percent: float = 5.0,
                 stream=None):
        self.total, self.n, self.desc = float(total), float(initial), desc
        self.step = step_percent
        self.stream = stream if stream is not None else sys.stderr
        self._start_n, self._start = self.n, _time.perf_counter()
        self._next = (int(self._percent() // self.step) + 1) * self.step
        self._postfix = ""
        self._printed, self._printed_postfix = self.n, ""
        # print a last line at close when only the postfix changed since the last (a study's runs done)
        self.final_postfix = False

    def _percent(self) -> float:
        return 100.0 * self.n / self.total if self.total > 0 else 100.0

    @staticmethod
    def _clock(seconds: float) -> str:
        seconds = int(round(seconds))
        return f"{seconds // 3600}:{seconds // 60 % 60:02d}:{seconds % 60:02d}"

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        self._postfix = text

    def update(self, amount: float) -> None:
        self.n += amount
        if self._percent() + 1e-9 >= self._next:
            self._print()
            self._next = (int((self._percent() + 1e-9) // self.step) + 1) * self.step

    def _print(self) -> None:
        elapsed = _time.perf_counter() - self._start
        done = self.n - self._start_n
        left = elapsed * (self.total - self.n) / done if done > 0 else float("nan")
        rate = f", {self._postfix}" if self._postfix else ""
        eta = self._clock(left) if left == left else "?"
        self._printed, self._printed_postfix = self.n, self._postfix
        print(f"{self.desc}: {self._percent():3.0f}% {self.n:.4f}/{self.total:.4f} s{rate}, "
              f"elapsed {self._clock(elapsed)}, left {eta}", file=self.stream, flush=True)

    def close(self) -> None:
        """A last line where the run stopped between two steps of ``step_percent`` (or, with
        ``final_postfix``, where only the postfix changed after the last line)."""
        if self.n > self._printed or (self.final_postfix and self._postfix != self._printed_postfix):
            self._print()


def progress_bar(total: float, initial: float, desc: str, stream=None):
    """tqdm on a terminal, ``LineProgress`` otherwise."""
    stream = stream if stream is not None else sys.stderr
    if getattr(stream, "isatty", lambda: False)():
        from tqdm import tqdm
        return tqdm(total=total, initial=initial, unit="s", unit_scale=False, dynamic_ncols=True, desc=desc,
                    file=stream,
                    bar_format="{desc}: {percentage:3.0f}%|{bar}| {n:.4f}/{total:.4f} s [{elapsed}<{remaining}{postfix}]")
    return LineProgress(total, initial, desc, stream=stream)


def advance_bar(bar, time: float, rate: float | None) -> None:
    """Move a bar (tqdm or ``LineProgress``; None: nothing) to ``time``, showing the steps per second."""
    if bar is None:
        return
    bar.update(time - bar.n)
    if rate:
        bar.set_postfix_str(f"{rate:.0f} steps/s", refresh=False)
