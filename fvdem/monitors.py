"""Watches over a running model: a step whose cost runs away, a gas that runs away.

Neither changes the state: the cost watch warns once (with the numbers that tell a violent bed from a
struggling gas step), the gas watch stops the run with ``SimulationError`` naming the setting to change.
"""
from __future__ import annotations

import statistics
import warnings
from collections import deque

import numpy as np

from .analysis.bed import particle_top
from .errors import SimulationError

# a chunk costing this many times the median step of the recent chunks is warned about (once)
RUNAWAY_COST = 20.0
# overlaps beyond this fraction of the diameter leave the range the soft defaults were chosen in: the
# reduced beds of tools/speed_accuracy.py --quick reached 5.0-5.4 % (AR-1) and 7.2 % (AR-4) at the
# defaults (bed height within the 5 % budget); a plug start of the full AR-1 bed reached 8.8 % (issue
# 17). Warned once
OVERLAP_WARNING = 0.08
# a share of the particles above this touching the outlet (the roof) is warned once: a plug start
OUTLET_PILE_SHARE = 0.01
# a walled column's gas faster than this many times the speed its inlet (in the densest packing) or
# its particles drive is stopped: the 10x-continuity defect of issue 14 reached 20-50x
RUNAWAY_GAS_SPEED = 10.0


def particle_speeds(model) -> tuple[float, float]:
    """Largest particle speed [m/s] and largest overlap over diameter of the model's particles."""
    d = model.dem.diagnostics()
    return d["max_speed"], d["max_overlap_over_diameter"]


class RunawayWatch:
    """``cost(steps, seconds)`` after each chunk of loop steps; ``particles(values)`` and ``gas(values)``
    at each sample."""

    RECENT = 200  # chunks the typical cost is the median of

    def __init__(self, model):
        self.model = model
        self.recent = deque(maxlen=self.RECENT)  # (seconds per step, neighbour rebuilds, step) per chunk
        self.chunks = 0
        self.warned_about: set = set()  # the warnings given ("cost", "overlap", "outlet"), each once

    def cost(self, steps: int, seconds: float) -> None:
        """Warn once when a chunk's CPU time per step exceeds ``RUNAWAY_COST`` times the median of the
        recent chunks (a jump, not the gradual rise of a bed being poured or fluidized; the first chunk
        holds numba's compilation and is skipped)."""
        if steps <= 0 or seconds <= 0:
            return
        model, rate = self.model, seconds / steps
        rebuilds = model.dem.rebuild_count if model.dem is not None else 0
        self.chunks += 1
        if self.chunks == 1:
            return
        if "cost" not in self.warned_about and len(self.recent) >= 3:
            typical = statistics.median_high(self.recent)  # a recorded chunk: its rebuilds and step too
            if rate >= RUNAWAY_COST * typical[0]:
                self.warned_about.add("cost")
                self._warn(rate, typical, rebuilds)
        self.recent.append((rate, rebuilds, model.step_count))

    def _warn(self, rate, typical, rebuilds) -> None:
        model = self.model
        ref_rate, ref_rebuilds, ref_step = typical
        gas = ""
        if model.gas is not None:
            speed = model.gas.max_speed()
            gas = f"; gas: largest speed {speed:.3g} m/s, Courant number {model.gas.courant_number():.3g}"
        particles = ""
        if model.dem is not None:
            speed, overlap = particle_speeds(model)
            particles = (f"; particles: largest speed {speed:.3g} m/s, largest overlap {overlap:.3g} d, "
                         f"{rebuilds - ref_rebuilds} neighbour-list rebuilds in {model.step_count - ref_step} steps")
        warnings.warn(f"t = {model.time:.4g} s: a step costs {rate / ref_rate:.0f} x the run's recent typical step "
                      f"({rate * 1e3:.3g} ms against {ref_rate * 1e3:.3g} ms){particles}{gas}. If the bed has gone "
                      "violent, reduce time.dem_step and gas.cfd_step (docs/speed-accuracy.md)",
                      RuntimeWarning, stacklevel=4)

    def particles(self, values: dict) -> None:
        """Warn once each when overlaps leave the range the defaults were chosen for, and when particles
        pile against a walled column's outlet (the roof) while gas flows in."""
        model = self.model
        if model.dem is None:
            return
        overlap = values.get("max_overlap_over_diameter", 0.0)
        own_stiffness = model.case.suspension.enabled  # a [suspension] sets k_n from its own overlap target
        if overlap > OVERLAP_WARNING and "overlap" not in self.warned_about and not own_stiffness:
            self.warned_about.add("overlap")
            warnings.warn(f"t = {model.time:.4g} s: the largest overlap is {100 * overlap:.1f} % of a diameter, above "
                          f"{100 * OVERLAP_WARNING:.1f} %, beyond the 5.4 % (AR-1) and 7.2 % (AR-4) the defaults reached in the "
                          "runs they were chosen on (docs/speed-accuracy.md): the bed compresses more than the 5 % "
                          "height budget; raise contact.normal_stiffness (and lower time.dem_step with 1/sqrt(k_n)) "
                          "where the bed's height or pressure matter (the paper's full beds at 2 Umf start at 8-10 % "
                          "and mixed no faster with a 4x stiffer spring: docs/validation.md, stage 1)",
                          RuntimeWarning, stacklevel=4)
        gas, box = model.gas, model.dem.box
        if gas is None or gas.config.inlet_velocity <= 0 or box.periodic[2] or "outlet" in self.warned_about:
            return
        p = model.particles
        top = particle_top(p.position, p.axis, p.radius, p.half_length)
        touching = int(np.count_nonzero(top > box.upper[2] - 0.5 * (p.radius + p.half_length)))
        if touching > OUTLET_PILE_SHARE * p.count:
            self.warned_about.add("outlet")
            ramp = gas.inlet_ramp
            if ramp > 0.0 and model.time > ramp:  # thrown up by the fluidized bed, not lifted as a plug at the start
                cause = (f"the fluidized bed threw them up to the roof after the inlet's {ramp:g} s ramp, and the gas "
                         "leaving through them can hold them there, out of the bed's mixing (Mema et al.'s AR-4 beds at "
                         "2.9 Umf in the 1.05 m column: docs/validation.md, stage 2); a taller domain.upper (its z) or "
                         "a lower gas.u_over_umf keeps them in the bed")
            else:
                cause = ("the bed rose as a plug into the roof and will stay pinned there (a start under a packed bed "
                         + (f"with the inlet at full speed within {ramp:g} s); a longer gas.inlet_ramp" if ramp > 0.0
                            else "at full speed); start with gas.inlet_ramp (e.g. 1 s)") + " or a lower gas.u_over_umf")
            warnings.warn(f"t = {model.time:.4g} s: {touching} particles ({100 * touching / p.count:.1f} %) are "
                          f"against the outlet at z = {box.upper[2]:g} m: {cause}", RuntimeWarning, stacklevel=4)

    def gas(self, values: dict) -> None:
        """Stop a walled column whose gas runs far faster than anything drives it: the inlet's
        interstitial speed in the densest packing (U / 0.3) and the fastest particle (``values``: the
        sample's, ``gas_max_speed`` and, with particles, ``max_speed``)."""
        gas = self.model.gas
        if gas is None or gas.periodic or gas.inlet.maximum <= 0:
            return
        gas_max_speed = values["gas_max_speed"]
        drive = max(gas.inlet.maximum / 0.3, values.get("max_speed", 0.0))
        if gas_max_speed > RUNAWAY_GAS_SPEED * drive:
            raise SimulationError(
                f"the gas runs away at t = {self.model.time:.6g} s: largest cell speed {gas_max_speed:.3g} m/s, "
                f"{gas_max_speed / drive:.0f} x the fastest speed the inlet or the particles drive ({drive:.3g} m/s); "
                f"largest Courant number {gas.courant_number():.3g} at gas.cfd_step = {gas.dt:g} s: reduce "
                "gas.cfd_step (docs/speed-accuracy.md)")
