"""A study's parts as the engine passes them around: ``RunSpec`` (one run), ``BedSpec`` (one settled bed),
``Study`` (the file read and checked, ``fvdem.study.sweep``). Below everything of the study package but
the report registry (a run carries its report's name)."""
from __future__ import annotations

from dataclasses import dataclass, field

from .registry import DEFAULT_REPORT


# a run's starting state: the study gives it its bed's final state when the bed has settled (not a change of physics)
BED_STATE = ("particles.initial_state",)


@dataclass(frozen=True)
class RunSpec:
    """One run of a study: where its case is, what it changes, and where it writes."""

    name: str
    family: str
    case: str  # path of the base case file
    overrides: dict
    folder: str
    bed: str | None = None  # name of the bed it starts from
    point: dict = field(default_factory=dict)  # the axes' values of this run
    duration: float = 0.0  # simulated seconds (the study's, or its family's own)
    replica: int = 1  # 1, 2, ...: replica k >= 2 starts from its own bed (insertion seed + k - 1)
    report: str = DEFAULT_REPORT  # the study's report: which values of its summary the run's result carries
    physics: str = ""  # its case's physics_fingerprint (its bed's state aside): tells a folder of an older case
    priority: int = 0  # the queue's tier among runs not started, higher first (``priority`` of its family or point)
    stops: tuple = ()  # its case's early-end settings, (index key, value) each: the index lists them for --status


@dataclass(frozen=True)
class BedSpec:
    name: str
    case: str
    overrides: dict
    folder: str
    replica: int = 1  # the replica whose runs start from it (``_bed_priority``)
    physics: str = ""  # its case's physics_fingerprint


@dataclass(frozen=True)
class Study:
    name: str
    path: str
    duration: float
    beds: tuple
    runs: tuple
    cluster: dict
    report: str = DEFAULT_REPORT  # a registered report (``fvdem.study.reports``): the study's table, figures, findings
    left_out: tuple = ()  # the runs (``RunSpec``) a selection (``--only``) left out: the index lists them too
    design: dict | None = None  # a ``[design]``'s record (``designed_runs``): factors, aliases, responses
