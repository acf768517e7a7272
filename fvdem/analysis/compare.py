"""Several run folders on one chart (``fvdem compare``): the comparisons, registered by name.

A comparison draws PNGs of the run folders ``runs`` into a folder ``out``: ``draw(runs, out, options) ->
[paths]``, with ``available(runs)``, whether the folders' files support it. ``timeseries`` (the diagnostics
the runs recorded in common, one line a run) is generic; a scene's observables name the others they
support (``Observable.comparisons``: the mixing observable's ``mixing``), registered where they are
defined (``register_comparison``), so that a scene of one's own adds a comparison without editing this
module or the command line. ``fvdem compare`` draws those that the runs' scenes name
(``fvdem.scenes.comparisons_of``).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from .plots import NOT_PLOTTED, read_timeseries, run_labels, timeseries_panels


@dataclass(frozen=True)
class Comparison:
    name: str
    draw: Callable  # (runs, out, options: dict) -> list of written paths
    available: Callable  # runs -> bool
    summary: str


COMPARISONS: dict[str, Comparison] = {}


def register_comparison(name: str, available: Callable, summary: str = ""):
    """Decorator on ``draw(runs, out, options) -> [paths]``: registers the comparison ``name``, drawn where
    ``available(runs)`` holds."""
    def decorate(draw):
        COMPARISONS[name] = Comparison(name, draw, available,
                                       summary or (draw.__doc__ or "").strip().split("\n")[0])
        return draw
    return decorate


def common_columns(runs) -> list[str]:
    """The ``timeseries.csv`` columns every run recorded, in the first run's order (time and the bookkeeping
    columns left out)."""
    series = [read_timeseries(r) for r in runs]
    return [k for k in series[0] if k != "time" and k not in NOT_PLOTTED and all(k in s for s in series[1:])]


def plot_timeseries_compare(runs, path, columns=None) -> Path:
    """``columns`` of the runs' time series (default: the first eight they recorded in common), a panel each,
    a line a run, labelled by folder (``run_labels``)."""
    series = [read_timeseries(r) for r in runs]
    if columns:
        missing = [(c, str(r)) for c in columns for r, s in zip(runs, series) if c not in s]
        if missing:
            raise ValueError("columns not recorded: " + ", ".join(f"{c} in {r}" for c, r in missing))
        keys = list(columns)
    else:
        keys = common_columns(runs)[:8]
    if not keys:
        raise ValueError("the runs recorded no column in common besides time")
    return timeseries_panels(series, run_labels(runs), keys, Path(path))


@register_comparison("timeseries", lambda runs: all((Path(r) / "timeseries.csv").exists() for r in runs))
def compare_timeseries(runs, out, options) -> list:
    """The diagnostics the runs recorded in common (or ``--columns``), one line a run: timeseries_compare.png."""
    return [plot_timeseries_compare(runs, Path(out) / "timeseries_compare.png", options.get("columns"))]


def compare(runs, out, names, options=None) -> list:
    """Draw the comparisons ``names`` (keys of ``COMPARISONS``) that the runs support into ``out``; the
    written paths."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for name in names:
        comparison = COMPARISONS[name]
        if comparison.available(runs):
            paths += comparison.draw(runs, out, options or {})
    return paths


__all__ = ["COMPARISONS", "Comparison", "register_comparison", "compare", "common_columns",
           "plot_timeseries_compare", "compare_timeseries"]
