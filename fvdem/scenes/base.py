"""What a run measures: observables, grouped into scenes.

An ``Observable`` is one small measurement with its computation beside it: the ``timeseries.csv``
columns it writes, the values it ``measure``s at each sample (read by later observables, the
stop test and the writers), a ``history`` it keeps over the run (saved in checkpoints, so a resumed
run continues it), the ``summary.json`` entries it derives, whether the run ends early (``ends``: the
bed at rest, the colours mixed) and the names of the report plots that show it
(``fvdem.analysis.plots.PLOTS``) and the comparisons of several runs it supports
(``fvdem.analysis.compare.COMPARISONS``). It only reads the model.

A ``Scene`` is the kind of run (fluidized bed, periodic suspension, fixed bed, settling) as a value: a
name and the observables it measures. ``scene_for(case)`` gives a case's scene: the first registered
scene whose ``applies(case)`` holds (``register_scene``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


class Observable:
    """Base of an observable (see the module docstring); every method has a do-nothing default."""

    name = ""
    plots: tuple = ()
    comparisons: tuple = ()  # ``fvdem compare`` charts of several runs (``fvdem.analysis.compare.COMPARISONS``)
    keeps_history = False  # whether ``record`` keeps samples (then a run without output still samples)

    def columns(self, model) -> tuple:
        """``timeseries.csv`` columns (keys of ``measure``'s values)."""
        return ()

    def measure(self, model, values: dict) -> dict:
        """This sample's values; ``values`` holds those of the observables before it."""
        return {}

    def new_history(self):
        return []

    def record(self, model, values: dict, history) -> None:
        """Keep what the summary needs from this sample (``values``: all observables' values)."""

    def summary(self, model, values: dict, history, run: dict) -> dict:
        """``summary.json`` entries; ``run`` holds ``steps`` and ``wall`` of the last ``run`` call."""
        return {}

    def ends(self, model, values: dict, history) -> str:
        """Why the run ends now, before its end time (a case's stop criterion this observable measures: the
        bed at rest, the colours mixed), else ""; tested at each sample after ``record``."""
        return ""


@dataclass(frozen=True)
class Scene:
    """A kind of run: its name and what it measures, in column order."""

    name: str
    observables: tuple

    def columns(self, model) -> tuple:
        return ("time",) + tuple(c for o in self.observables for c in o.columns(model))

    def measure(self, model) -> dict:
        values = {"time": model.time}
        for observable in self.observables:
            values.update(observable.measure(model, values))
        return values

    def new_histories(self) -> dict:
        return {o.name: o.new_history() for o in self.observables if o.keeps_history}

    def record(self, model, values: dict, histories: dict) -> None:
        for observable in self.observables:
            if observable.keeps_history:
                observable.record(model, values, histories[observable.name])

    def summary(self, model, values: dict, histories: dict, run: dict) -> dict:
        out = {}
        for observable in self.observables:
            out.update(observable.summary(model, values, histories.get(observable.name), run))
        return out

    def ends(self, model, values: dict, histories: dict) -> str:
        """The first early end an observable reports (``Observable.ends``), else ""."""
        return next((why for o in self.observables if (why := o.ends(model, values, histories.get(o.name)))), "")

    @property
    def keeps_history(self) -> bool:
        return any(o.keeps_history for o in self.observables)

    def _declared(self, kind: str) -> tuple:
        """"timeseries" (every run's common diagnostics), then each observable's own names of ``kind``
        (``"plots"`` or ``"comparisons"``), each once, in the observables' order."""
        names = ["timeseries"]
        for observable in self.observables:
            names += [n for n in getattr(observable, kind) if n not in names]
        return tuple(names)

    @property
    def plots(self) -> tuple:
        return self._declared("plots")

    @property
    def comparisons(self) -> tuple:
        return self._declared("comparisons")


@dataclass(frozen=True)
class SceneType:
    name: str
    applies: Callable  # case -> bool
    build: Callable  # case -> Scene
    summary: str


SCENES: dict[str, SceneType] = {}


def register_scene(name: str, applies: Callable, summary: str = ""):
    """Decorator on ``build(case) -> Scene``: registers the scene ``name`` for cases where
    ``applies(case)``; scenes are tried in registration order."""
    def decorate(build):
        SCENES[name] = SceneType(name, applies, build, summary or (build.__doc__ or "").strip().split("\n")[0])
        return build
    return decorate


def scene_for(case) -> Scene:
    """The scene of a case: the first registered one that applies."""
    for kind in SCENES.values():
        if kind.applies(case):
            return kind.build(case)
    raise ValueError(f"no registered scene applies to case {case.name!r}; registered: {', '.join(SCENES)}")


def _declared_by(out, kind: str, every) -> tuple:
    """The names of ``kind`` (``"plots"``, ``"comparisons"``) a run folder's scene declares, from its case.toml;
    without a readable case (none, or one this version no longer reads), ``every`` registered one."""
    from pathlib import Path

    from ..case import CaseError, load_case
    try:
        return getattr(scene_for(load_case(Path(out) / "case.toml")), kind)
    except (CaseError, OSError):
        return tuple(every)


def plots_of(out) -> tuple:
    """The plots (``fvdem.analysis.plots.PLOTS`` names) a run folder's scene declares, from its case.toml;
    without a readable case, every plot."""
    from ..analysis.plots import PLOTS
    return _declared_by(out, "plots", PLOTS)


def comparisons_of(runs) -> tuple:
    """The comparisons (``fvdem.analysis.compare.COMPARISONS`` names) the run folders' scenes declare, from
    their case.toml files, in the first run's order; a folder without a readable case adds every one."""
    from ..analysis.compare import COMPARISONS
    names = []
    for run in runs:
        names += [n for n in _declared_by(run, "comparisons", COMPARISONS) if n not in names]
    return tuple(names)
