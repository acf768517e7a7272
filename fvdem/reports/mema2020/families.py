"""The study's families and how the findings and figures count their runs: a row's state (``row_ended``, ...,
on ``fvdem.study.records.state_of``), the runs that have told something (``told_rows``), the families named by
suffix that count as another's ("<name>_t95", "<name>_expansion", "<name>_tall": ``t95_runs``, ``expansion_runs``,
``tall_columns``) and each family's values per velocity (``by_velocity``, ``t95_by_velocity``, ``mean_t95``)."""
from __future__ import annotations

from ...study.records import RunState, state_of


def row_ended(row: dict) -> bool:
    """Whether a table row's run has ended (its status on record, ``state_of``)."""
    return state_of(row["status"]) is RunState.ENDED


def row_on_the_way(row: dict) -> bool:
    """Whether a table row's run may yet bring a result (neither ended, failed nor out of the study file)."""
    return state_of(row["status"]).on_the_way


def row_failed(row: dict) -> bool:
    """Whether a table row's run failed."""
    return state_of(row["status"]) is RunState.FAILED


ROOFED = 0.5  # a run whose bed top stood at the outlet for this share of the window or more: its bed was roofed


def is_roofed(row: dict) -> bool:
    """Whether a table row's bed stood at the outlet for most of the window (``bed_at_roof``, ``_at_roof``)."""
    return (row.get("bed_at_roof") or 0.0) >= ROOFED


def point_of(run: dict) -> tuple:
    """A study index entry's axes values (its ``point``), in the study's axes order."""
    return tuple(run.get("point", {}).values())


def pairs_of(runs, first, second) -> dict:
    """``{axes values: (runs of family first, then of family second)}`` where both ran at those values, every
    replica of each (the figures draw the spread, not one replica)."""
    by = {}
    for r in runs:
        by.setdefault(point_of(r), {}).setdefault(r["family"], []).append(r)
    return {point: (*fam[first], *fam[second]) for point, fam in by.items() if first in fam and second in fam}


def by_velocity(rows, family, key):
    """``{U/Umf: [row[key], ...]}`` of the runs of a family that did not fail (replicas together)."""
    out = {}
    for r in rows:
        if r["family"] == family and not row_failed(r) and "gas.u_over_umf" in r:
            out.setdefault(r["gas.u_over_umf"], []).append(r.get(key))
    return out


def t95_by_velocity(rows, family):
    """``{U/Umf: [t95 or None, ...]}`` of the runs of a family (replicas listed together)."""
    return by_velocity(rows, family, "t95")


def counted_t95(rows, family) -> dict:
    """``{U/Umf: [t95, ...]}`` of a family's replicas, a run not mixed by its end counted at its end (None where
    that end is unknown): the values ``mean_t95`` averages and ``within_spread`` spreads."""
    t, ends = t95_by_velocity(rows, family), by_velocity(rows, family, "simulated_seconds")
    return {v: [x if x is not None else e for x, e in zip(values, ends[v])] for v, values in t.items()}


def mean_t95(rows, family) -> dict:
    """``{U/Umf: (mean t95 over the replicas, whether it is a lower bound)}`` of a family: a replica not mixed by
    its end counts as its end time, which makes the mean a lower bound (``check_findings`` has left out the
    runs still on their way), and a velocity with an unmixed replica of unknown end is left out."""
    t = t95_by_velocity(rows, family)
    return {v: (sum(known) / len(known), None in t[v]) for v, known in counted_t95(rows, family).items()
            if known and None not in known}


EXPANSION = "_expansion"  # a family "<name>_expansion": <name>'s runs cut short after the bed-expansion window


def expansion_runs(rows) -> list:
    """``rows`` with the runs of each family "<name>_expansion" (``EXPANSION``) counted as <name>'s (each keeps
    its own family's name as ``column``). Such a family runs <name>'s case from beds of its own (other insertion
    seeds) only as long as the window its bed expansion is measured over (``_bed_expansion``: 5 s with a 1 s
    ramp): more replicas of the one finding that needs many (AR-4 MP's beds at 1.6-1.7 Umf expand 1.6-2.6 times
    by chance of a spout, AR-1's 1.7-1.9) at a quarter of a 20 s run's cost. They count for the expansion
    alone: a run cut short says nothing of t95, and its void fractions are of other times than a whole run's."""
    return [_counted_as_base(r, EXPANSION) if r["family"].endswith(EXPANSION) else r for r in rows]


T95_ONLY = "_t95"  # a family "<name>_t95": <name>'s runs that end when they mix, for the t95 findings alone


def t95_runs(rows) -> list:
    """``rows`` with the runs of each family "<name>_t95" (``T95_ONLY``) counted as <name>'s, flagged
    ``cut_at_t95`` (each keeps its own family's name as ``column``; "<name>_tall_t95" becomes "<name>_tall", a
    taller column's run, ``tall_columns``). Such a family runs <name>'s case from beds of its own (other
    insertion seeds) and ends when it mixes (``time.stop_after_mixed = 0``: t95 is the entropy's first crossing
    of 0.95, ``mixing_time``, so it is the same as a whole run's), or unmixed at its duration: the replicas the
    t95 findings need by the dozen at 2 and 2.9 Umf (the differences' sizes), a quarter to two fifths cheaper
    than runs that go on 2 s past t95. They count for the t95 findings and Fig. 4 alone: their void fractions
    (over the second half of a run) and bed expansion (over a window they may not reach) are of other times
    than a whole run's."""
    return [{**_counted_as_base(r, T95_ONLY), "cut_at_t95": True} if r["family"].endswith(T95_ONLY) else r
            for r in rows]


def series_base(name: str) -> str | None:
    """The family a replica series "<family>_t95" (``T95_ONLY``) or "<family>_expansion" (``EXPANSION``) counts as,
    or None for another name."""
    for suffix in (T95_ONLY, EXPANSION):
        if name.endswith(suffix):
            return name[:-len(suffix)]
    return None


def _counted_as_base(row: dict, suffix: str) -> dict:
    """A run of family "<name><suffix>" (``TALL``, ``EXPANSION``, ``T95_ONLY``) as <name>'s, its own family kept
    as ``column``."""
    return {**row, "family": row["family"][:-len(suffix)], "column": row["family"]}


def expansion_sample(rows) -> tuple[list, list]:
    """The runs whose bed expansion counts (ended, with ``bed_expansion``) and, apart, those left out because
    their bed's top stood at the outlet for most of the window (``is_roofed``: no height of its own there)."""
    ended = [r for r in rows if row_ended(r) and r.get("bed_expansion") is not None]
    at_roof = [is_roofed(r) for r in ended]
    return ([r for r, roof in zip(ended, at_roof) if not roof], [r for r, roof in zip(ended, at_roof) if roof])


TALL = "_tall"  # a family "<name>_tall": <name>'s closures and bed in a column taller than the paper's 1.05 m


def tall_columns(rows, at=lambda r: r.get("gas.u_over_umf")) -> tuple[list, dict]:
    """``rows`` with the runs of each family "<name>_tall" (``TALL``) counted as <name>'s at their point (``at``:
    a table row's U/Umf, or an index entry's axes values), in place of <name>'s runs there (each keeps its own
    family's name as ``column``), and ``{(name, point): [the runs set aside]}``. A study runs a point in a taller
    column where the paper's 1.05 m outlet held the start-up surge's particles (AR-4 MP at 2.9 Umf: t95 4.36 s
    with 4.7 % of the rods pinned at the outlet, 2.64 s in a 2.1 m column; docs/validation.md, stage 1): the
    findings are of the bed, and a column whose roof holds a layer of one colour mixes the column's particles,
    not the bed's. A taller run counts once it has mixed or ended (``check_findings``); until then the
    paper's column's runs stand. The set-aside runs stay in the table, and in each finding's note
    (``_column_note``)."""
    tall = {(r["family"][:-len(TALL)], at(r)) for r in rows if r["family"].endswith(TALL)}
    kept, aside = [], {}
    for r in rows:
        if r["family"].endswith(TALL):
            kept.append(_counted_as_base(r, TALL))
        elif (r["family"], at(r)) in tall:
            aside.setdefault((r["family"], at(r)), []).append(r)
        else:
            kept.append(r)
    return kept, aside


def told_rows(rows) -> list:
    """The rows the findings count: a run that has mixed, or is no longer on its way (a run still running and
    not yet mixed, or not started, is left out, not taken as unmixed)."""
    return [r for r in rows if r.get("t95") is not None or not row_on_the_way(r)]


def mixed_or_ended(r: dict) -> bool:
    """Whether the t95 chart shows a run (``report`` derived its status): mixed (its t95 known), or ended
    unmixed (its end a lower bound of t95); a run still on its way and not yet mixed is left out (its current
    time bounds nothing yet)."""
    return r.get("t95") is not None or row_ended(r)


def among(point: tuple, velocities) -> bool:
    """Whether an axes point (``pairs_of``' keys) holds one of ``velocities`` (U/Umf, to rounding)."""
    return any(abs(v - w) < 1e-9 for v in point for w in velocities)


def set_aside_name(family: str) -> str:
    """The t95 chart's name of a family's runs set aside for a taller column's (``tall_columns``)."""
    return f"{family}: the paper's column, set aside (particles pinned at its outlet)"


def column_of(r: dict) -> str:
    """A run's family as a chart names it: a taller column's own (``tall_columns``' ``column``) or its family."""
    return r.get("column", r["family"])
