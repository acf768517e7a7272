"""The inlet's velocity over a run (``gas.inlet_velocity``, ``gas.inlet_ramp``, ``gas.inlet_steps``): a start-up
ramp from 0, then the full velocity, then steps to other velocities at given times (a defluidization ramp:
tools/validate_umf.py). Step ``n`` of the gas runs from ``n dt`` to ``(n + 1) dt`` with one superficial inlet
velocity [m/s]:

- inside the ramp (``n dt < ramp``): ``U min(1, (n + 1) dt / ramp)``, the velocity at the step's end (the
  step is implicit);
- after it: ``U``, or the velocity of the last step pair ``(t, u)`` whose CFD step (``step_of(t, dt)``, the
  step starting at ``t`` to half a step) has begun (a pair's step is at least the ramp's first step after it).
"""
from __future__ import annotations


def step_of(time: float, dt: float) -> int:
    """The CFD step starting at ``time`` [s] (to half a step): ``round(time / dt)``, as a run's end step is."""
    return int(round(time / dt))


class InletSchedule:
    """The inlet velocity of each CFD step (the module docstring). ``velocity`` [m/s], ``ramp`` [s], ``steps``
    ``(time [s], velocity [m/s])`` pairs in increasing time, ``dt`` the CFD step [s]."""

    def __init__(self, velocity: float, ramp: float, steps, dt: float):
        self.velocity, self.ramp, self.dt = float(velocity), float(ramp), float(dt)
        first = max(0, step_of(self.ramp, self.dt) - 2)
        while first * self.dt < self.ramp:  # the first step past the ramp
            first += 1
        # (first step, velocity) of each pair, in order; a later pair of the same step replaces an earlier one
        changes = {max(step_of(t, self.dt), first): float(u) for t, u in steps}
        self.changes = sorted(changes.items())
        self._change_at = dict(self.changes)

    @property
    def varies(self) -> bool:
        """Whether the velocity changes during the run (a ramp or steps)."""
        return self.ramp > 0.0 or bool(self.changes)

    @property
    def maximum(self) -> float:
        """The largest velocity of the run [m/s]."""
        return max([self.velocity, *self._change_at.values()])

    def _ramp_at(self, time: float) -> float:
        if self.ramp <= 0.0:
            return self.velocity
        return self.velocity * min(1.0, time / self.ramp)

    def change_before(self, step: int) -> float | None:
        """The velocity to set before step ``step`` runs, or None where it keeps the previous step's."""
        if step * self.dt < self.ramp:
            return self._ramp_at((step + 1) * self.dt)
        return self._change_at.get(step)

    def after(self, steps: int) -> float:
        """The velocity the inlet holds after ``steps`` steps (the last one's: what a resumed run restores)."""
        velocity = None
        for first, u in self.changes:
            if first <= steps - 1:
                velocity = u
        return self._ramp_at(steps * self.dt) if velocity is None else velocity

    def of_step(self, step: int) -> float:
        """The velocity of step ``step`` [m/s]."""
        return self.after(step + 1)
