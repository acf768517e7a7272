"""Where a run's wall time goes: seconds accumulated per phase of the step, like LAMMPS's loop-time
breakdown. The model's parts add to one ``Timings``; ``fvdem run`` prints it and ``summary.json``
holds it under ``timings``. A phase costs two clock reads (~0.1 us) per call: nothing beside a step.
"""
from __future__ import annotations

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

    __slots__ = ("seconds",)

    def __init__(self, seconds: dict | None = None):
        self.seconds = {name: 0.0 for name in PHASES}
        if seconds:
            self.seconds.update({k: float(v) for k, v in seconds.items() if k in PHASES})

    def add(self, phase: str, seconds: float) -> None:
        self.seconds[phase] += seconds

    def table(self, total: float) -> dict:
        """Per phase and ``other`` (the rest of ``total``), and ``total`` [s]."""
        out = dict(self.seconds)
        out["other"] = max(0.0, total - sum(self.seconds.values()))
        out["total"] = total
        return out


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
