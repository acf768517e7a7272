"""Why a run ends before its end time, as a reader of its folder tells it: each early end an observable reports
(``Observable.ends``, recorded as the summary's ``ended``) registered by name (``STOP_CONDITIONS``) with the case
key that sets it. The study engine knows no end of its own: it asks the condition a summary names whether that
end still holds under the case as the study now sets it (a margin raised since: the run goes on; a criterion
taken out: it runs to its end time) and, for ``fvdem study --status``, when a run that has reached the condition's
mark will end. Adding one: docs/ARCHITECTURE.md, "How to add a stop condition"."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from .observables import past_mixing


@dataclass(frozen=True)
class StopCondition:
    """An early end of a run: its name (the summary's ``ended``), the case key that sets it, and the rules the
    readers of a run folder apply (each a pure function of summary values and the key's value)."""

    name: str  # the word ``Observable.ends`` returns and ``summary.json`` keeps as ``ended``
    setting: str  # the case key that sets it, dotted ("time.stop_after_mixed"); its value None or False: not set
    holds: Callable[[dict, object], bool]  # (summary, the setting's value) -> whether the recorded end stands
    mark: str | None = None  # the summary value the end counts from (e.g. a time reached), None where none does
    ends_at: Callable[[float, object], float] | None = None  # (mark, setting) -> the simulated time it ends at [s]
    index_key: str | None = None  # the key a study index (study.json) lists each run's setting under
    expected: str = ""  # how a status line words that end ("<setting> past its <mark>")
    summary: str = ""  # one line on what it is

    def setting_of(self, case):
        """The value of the case key ``setting`` in ``case``."""
        value = case
        for part in self.setting.split("."):
            value = getattr(value, part)
        return value

    def still_ends(self, summary: dict, case) -> bool:
        """Whether the end ``summary`` records by this condition stands under ``case`` (as the study sets it now)."""
        return self.holds(summary, self.setting_of(case))

    def end_time(self, values: dict, setting) -> float | None:
        """The simulated time [s] a run ends at whose ``values`` (summary or table values) hold this condition's
        ``mark``, under the setting's value ``setting``; None where it cannot tell (no mark yet, not set)."""
        if self.ends_at is None or setting is None or setting is False or values.get(self.mark) is None:
            return None
        return self.ends_at(values[self.mark], setting)


STOP_CONDITIONS: dict[str, StopCondition] = {}


def register_stop_condition(condition: StopCondition) -> StopCondition:
    """Make ``condition`` known to the readers of run folders (the study engine) by its ``name``."""
    STOP_CONDITIONS[condition.name] = condition
    return condition


def stop_settings(case) -> tuple:
    """``(index_key, value)`` of each registered condition a study index lists (``index_key``), from ``case``:
    what ``fvdem study --status`` reads of each run's early end without its case."""
    return tuple((c.index_key, c.setting_of(case)) for c in STOP_CONDITIONS.values() if c.index_key)


# the bed at rest (``Particles.ends``): the recorded end stands while the case still stops when settled
SETTLED = register_stop_condition(StopCondition(
    "settled", "time.stop_when_settled", lambda summary, on: bool(on),
    summary="the bed at rest: rms particle speed below time.settled_speed from time.min_time on"))

# the colours mixed (``Mixing.ends``): the recorded end stands while the run has gone the case's margin past t95
MIXED = register_stop_condition(StopCondition(
    "mixed", "time.stop_after_mixed",
    lambda summary, margin: past_mixing(summary.get("t95"), margin, summary["simulated_time"]),
    mark="t95", ends_at=lambda t95, margin: t95 + margin, index_key="stop_after_mixed",
    expected="time.stop_after_mixed past its t95 where it has mixed",
    summary="the colours mixed: time.stop_after_mixed past the mixing time t95"))
