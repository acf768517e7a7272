"""Where a run's wall time goes: seconds accumulated per phase of the step, like LAMMPS's loop-time
breakdown. The model's parts add to one ``Timings``; ``fvdem run`` prints it and ``summary.json``
holds it under ``timings``. A phase costs two clock reads (~0.1 us) per call: nothing beside a step.

A part times a phase with ``with timings.phase("closures"): ...`` or adds measured seconds with
``timings.add``. Phases nest: a phase's seconds are its own, less whatever was recorded in other phases
while it was open (the gas step's ``gas_other`` is the step less its momentum and pressure phases).
"""
from __future__ import annotations

from time import perf_counter

PHASES = {
    "neighbour_list": "DEM: neighbour-list rebuilds (cell sort, half list, history transfer)",
    "contact_forces": "DEM: pair and wall contact forces",
    "integration": "DEM: velocity-Verlet kicks and drift, rotation, implicit drag",
    "voidage_mapping": "coupling: particle-grid map and voidage",
    "closures": "coupling: interpolation to the particles, drag, lift, torque, particle response",
    "deposition": "coupling: exchange terms scattered to the cells, momentum return",
    "gas_momentum": "gas: momentum predictor (three component solves)",
    "gas_pressure": "gas: pressure corrections (Rhie-Chow fluxes, pressure solve, face pressures)",
    "gas_other": "gas: sources, porous zone, face averages, diagnostics of the step",
    "output": "samples, time series, snapshots, checkpoints",
}


class Timings:
    """Seconds per phase (``PHASES``)."""

    __slots__ = ("seconds", "_open")

    def __init__(self, seconds: dict | None = None):
        self.seconds = {name: 0.0 for name in PHASES}
        if seconds:
            self.seconds.update({k: float(v) for k, v in seconds.items() if k in PHASES})
        self._open: list = []  # the phases open now, innermost last: [name, start, seconds recorded inside]

    def add(self, phase: str, seconds: float) -> None:
        """``seconds`` more of ``phase`` (measured by the caller); not counted in a phase open around it."""
        self.seconds[phase] += seconds
        if self._open:
            self._open[-1][2] += seconds

    def phase(self, name: str) -> "Phase":
        """A context manager timing its block as phase ``name`` (less the phases recorded inside it)."""
        return Phase(self, name)

    def table(self, total: float) -> dict:
        """Per phase and ``other`` (the rest of ``total``), and ``total`` [s]."""
        out = dict(self.seconds)
        out["other"] = max(0.0, total - sum(self.seconds.values()))
        out["total"] = total
        return out


class Phase:
    """``with timings.phase(name):`` (``Timings.phase``)."""

    __slots__ = ("timings", "name")

    def __init__(self, timings: Timings, name: str):
        if name not in timings.seconds:
            raise KeyError(f"no timing phase {name!r}; the phases: {', '.join(PHASES)}")
        self.timings, self.name = timings, name

    def __enter__(self) -> None:
        self.timings._open.append([self.name, perf_counter(), 0.0])

    def __exit__(self, *exc) -> None:
        open_phases = self.timings._open
        name, start, inside = open_phases.pop()
        elapsed = perf_counter() - start
        self.timings.seconds[name] += elapsed - inside
        if open_phases:  # all of it, its own and its inner phases', is not the enclosing phase's
            open_phases[-1][2] += elapsed


def format_table(timings: dict, threads: int, steps: int, simulated: float) -> str:
    """The table ``fvdem run`` prints: seconds, share of the total and what each phase is."""
    total = timings["total"]
    lines = [f"Loop time of {total:.4g} s on {threads} thread(s) for {steps} steps ({simulated:.4g} simulated s)",
             f"{'phase':16s} {'seconds':>10s} {'%total':>7s}"]
    for name, seconds in timings.items():
        if name == "total" or (seconds == 0.0 and name != "other"):
            continue
        share = 100.0 * seconds / total if total > 0 else 0.0
        lines.append(f"{name:16s} {seconds:10.4g} {share:7.1f}  {PHASES.get(name, 'not in a timed phase')}")
    return "\n".join(lines)
