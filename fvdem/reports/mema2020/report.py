"""Seed 000's study report (Mema et al. (2020), §5-§6), registered as ``"mema2020"``: mixing entropy
against time per family (Fig. 2), t95 against U/Umf (Fig. 4), AR-1 against AR-4 MP (Fig. 3) with their
void fractions below 0.3 m (Fig. 7), AR-4 MP drag only against drag + lift + torque (Fig. 9); the table's
t95, pressure-drop, bed-height, entropy and binarity columns; and the paper's findings, each with
fvdem's numbers and a verdict (``check_findings``)."""
from __future__ import annotations

import json
import math
import re
from pathlib import Path
from dataclasses import replace

from ...analysis.plots import COLOUR_LAYERS
from ...scenes.observables import colour_layer_record
from ...study.records import RunState, folder_case, state_of
from ...study.registry import StudyReport, register_report


def row_ended(row: dict) -> bool:
    """Whether a table row's run has ended (its status on record, ``state_of``)."""
    return state_of(row["status"]) is RunState.ENDED


def row_on_the_way(row: dict) -> bool:
    """Whether a table row's run may yet bring a result (neither ended, failed nor out of the study file)."""
    return state_of(row["status"]).on_the_way


def row_failed(row: dict) -> bool:
    """Whether a table row's run failed."""
    return state_of(row["status"]) is RunState.FAILED


# s: the window of the bed's height and of its channels, the same in every run whatever its length (8 s,
# 20 s, or ended 2 s past t95: ``time.stop_after_mixed``): from this long after the inlet reached its velocity,
# for ``WINDOW``
WINDOW_START, WINDOW = 1.0, 3.0


def _window_mean(series, column: str, ramp: float | None = None):
    """The mean of a time-series column from ``WINDOW_START`` after the inlet ramp (``ramp`` [s]) for ``WINDOW``
    (to the run's end if sooner); without a ramp known, or before the run reaches that window, over the second
    half of its time series. One window for all runs: AR-1's first replicas' beds stood 1-5 % higher over their
    second halves (4-8 s) than over 2.75-5.5 s, enough to decide AR-1 against AR-4 by run length. None without
    the column. ``series``: ``_series``'s (None, or at least one row)."""
    import numpy as np
    if series is None or column not in series:
        return None
    times = series["time"]
    start = None if ramp is None else ramp + WINDOW_START
    if start is None or times[-1] <= start:
        return float(np.mean(series[column][times >= 0.5 * times[-1]]))
    return float(np.mean(series[column][(times >= start) & (times <= start + WINDOW)]))


def _bed_surface(series, ramp: float | None = None):
    """The bed's height [m] as the table gives it: ``bed_top`` (the height below which 99 % of the particle tops
    lie) over the window (``_window_mean``). The summary's ``bed_height`` is a packed bed's (solid volume over
    area and core solids fraction): in a fluidized bed it exceeds the column (1.37 m in the 1.05 m column for
    AR-1 at 2.9 Umf)."""
    return _window_mean(series, "bed_top", ramp)


def _bed_expansion(series, ramp: float | None = None):
    """The bed's expansion: its height (``_bed_surface``) over ``bed_top`` at the run's start (the settled bed
    it started from); None without it."""
    surface = _bed_surface(series, ramp)
    return None if surface is None or series["bed_top"][0] <= 0 else surface / float(series["bed_top"][0])


DENSE = 0.9  # the dense bed: the height under this share of the particle centres (``_dense_bed_expansion``)


def _centre_quantile(count, z_lower: float, layer_height: float, share: float = DENSE) -> float | None:
    """The height [m] under which ``share`` of the particle centres lie, from their counts in horizontal layers
    from ``z_lower`` up (``colour_layer_record``), the centres spread evenly within the layer it falls in. None
    without particles."""
    cumulative, total = [], 0
    for n in count:
        total += n
        cumulative.append(total)
    if total <= 0:
        return None
    target = share * total
    layer = next(i for i, c in enumerate(cumulative) if c >= target)
    below = cumulative[layer - 1] if layer else 0
    return z_lower + layer_height * (layer + (target - below) / count[layer])


def _dense_bed_expansion(record: dict | None, ramp: float | None = None) -> float | None:
    """The dense bed's expansion: the height under 90 % (``DENSE``) of the particle centres (``_centre_quantile``)
    over the window (``_window_mean``, at the particle snapshots: every 0.5 s) over its value at the first
    snapshot (the settled bed). Beside ``_bed_expansion`` (99 % of the tops), which the few particles thrown above
    the bed set: at 1.6-1.7 Umf AR-4 MP's 99 % height stood 1.6-2.6 times its settled value by the chance of a
    spout (1 % of the rods thrown to 0.6-0.9 m) while its 90 % height stood 1.2-1.4 times, below AR-1's 1.5-1.8
    (2026-12-05). ``record``: ``colour_layer_record``'s (None for a run without snapshots or an archived record:
    those archived before 2026-12-04 have none); None without it or its first snapshot's height."""
    import numpy as np
    if record is None or not record.get("count"):
        return None
    heights = [_centre_quantile(c, record["z_lower"], record["layer_height"]) for c in record["count"]]
    if heights[0] is None or heights[0] <= 0 or None in heights:
        return None
    window = _window_mean({"time": np.asarray(record["times"], float), "dense": np.asarray(heights)}, "dense", ramp)
    return window / heights[0]


ROOF_MARGIN = 0.01  # m: a bed top within this of the column's outlet is the outlet's
ROOFED = 0.5  # a run whose bed top stood at the outlet for this share of the window or more: its bed was roofed


def _roofed(row: dict) -> bool:
    """Whether a table row's bed stood at the outlet for most of the window (``bed_at_roof``, ``_at_roof``)."""
    return (row.get("bed_at_roof") or 0.0) >= ROOFED


def _at_roof(series, roof: float | None, ramp: float | None = None):
    """The share of the window's samples (``_window_mean``) at which ``bed_top`` stands at the column's outlet
    (within ``ROOF_MARGIN`` of ``roof`` [m]): rods or spheres thrown up and pinned against the outlet by the gas
    leaving through them (AR-4 MP at 2.9 Umf: 1,055-1,095 rods, 3.3 %, from 1.5 s), so that the height below
    which 99 % of the tops lie is the outlet's, not the bed's. None without the column or the roof."""
    if roof is None or series is None or "bed_top" not in series:
        return None
    at_roof = {**series, "bed_top": (series["bed_top"] >= roof - ROOF_MARGIN).astype(float)}
    return _window_mean(at_roof, "bed_top", ramp)


def _reaches_roof(series, roof: float | None) -> bool:
    """Whether a run's bed top (``bed_top`` of its series) ever stood at the column's outlet (within
    ``ROOF_MARGIN`` of ``roof`` [m]); False without the column, the series or its bed top."""
    if roof is None or series is None or "bed_top" not in series or not len(series["bed_top"]):
        return False
    return float(series["bed_top"].max()) >= roof - ROOF_MARGIN


def _roof_share(series, roof: float | None, record: dict | None):
    """The share of the particles in the column's top layer of the mixing grid (0.03 m under the outlet on the
    paper's grid) at the run's last particle snapshot, from ``record`` (``colour_layer_record``'s): those pinned
    at the outlet (AR-4 MP at 2.9 Umf: 3.3 % of the rods at 3 s, 4.7 % at 6 s; SP at 2.6: 10 % from 1.5 s on).
    0 where the bed's top never reached the outlet (``_reaches_roof``: the record need not be read then); None
    without the column, the series or the record."""
    if roof is None or series is None or "bed_top" not in series:
        return None
    if not _reaches_roof(series, roof):
        return 0.0
    if record is None or not record["count"]:
        return None
    last = record["count"][-1]
    reaches = record["z_lower"] + record["layer_height"] * len(last)  # the record stops at the highest layer reached
    if not sum(last) or reaches < roof - 1e-9:
        return 0.0
    return last[-1] / sum(last)


def _gas(folder: Path):
    """The gas settings of a run's case.toml; None without a readable one."""
    case = folder_case(folder)
    return None if case is None else case.gas


def _inlet_passes_umf(gas) -> float | None:
    """When [s] a run's inlet velocity reaches the Umf its ``u_over_umf`` refers to: ``inlet_ramp / u_over_umf``
    for a linear ramp from 0 (0 for a full-speed start); None without the case's gas settings or a U/Umf."""
    if gas is None or not gas.u_over_umf:
        return None
    return gas.inlet_ramp / gas.u_over_umf if gas.u_over_umf >= 1.0 else None


def _point(run: dict) -> tuple:
    """A study index entry's axes values (its ``point``), in the study's axes order."""
    return tuple(run.get("point", {}).values())


def _pairs(runs, first, second) -> dict:
    """``{axes values: (runs of family first, then of family second)}`` where both ran at those values, every
    replica of each (the figures draw the spread, not one replica)."""
    by = {}
    for r in runs:
        by.setdefault(_point(r), {}).setdefault(r["family"], []).append(r)
    return {point: (*fam[first], *fam[second]) for point, fam in by.items() if first in fam and second in fam}


def void_fraction_samples(folder, below=0.3):
    """Cell void fractions of the cells whose centres are below ``below`` [m], over the second half of
    a run's gas snapshots (the fluidized state, not the start-up), pooled; empty without snapshots."""
    import meshio
    import numpy as np
    snapshots = sorted(Path(folder).glob("gas_*.vtu"))
    values = []
    for snapshot in snapshots[len(snapshots) // 2:] if len(snapshots) > 1 else []:
        grid = meshio.read(snapshot)
        centres = grid.points[grid.cells[0].data].mean(axis=1)
        values.append(np.asarray(grid.cell_data["voidage"][0])[centres[:, 2] < below])
    return np.concatenate(values) if values else np.zeros(0)


VOID_FRACTION = "void_fraction.json"  # an archived run's void-fraction record (its gas snapshots are not kept)


def void_fraction_record(folder, below=0.3) -> dict | None:
    """A run's cell void fractions below ``below`` [m] over the second half of its gas snapshots, as a
    20-bin density histogram on [0, 1], their binarity (``void_fraction_binarity``) and count; from the
    snapshots, else from an archived run's ``void_fraction.json``; None without either."""
    import numpy as np
    from ...analysis.mixing import void_fraction_binarity
    values = void_fraction_samples(folder, below)
    if values.size:
        counts, edges = np.histogram(values, bins=20, range=(0.0, 1.0), density=True)
        binarity = void_fraction_binarity(values)
        return {"below": below, "edges": edges.tolist(), "density": counts.tolist(), "cells": int(values.size),
                "binarity": None if math.isnan(binarity) else binarity}
    stored = Path(folder) / VOID_FRACTION
    return json.loads(stored.read_text()) if stored.exists() else None


def plot_void_fractions(runs, path, below=0.3):
    """Histograms of the cell void fraction below ``below`` [m] over the second half of each run's gas
    snapshots, on one chart, with each run's binarity (``void_fraction_binarity``; Mema et al. (2020) Fig. 7)."""
    import numpy as np
    from ...analysis.plots import _pyplot, _save
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for r in runs:
        record = void_fraction_record(r["folder"], below)
        if record is not None:
            edges = np.asarray(record["edges"])
            binarity = "-" if record["binarity"] is None else f"{record['binarity']:.2f}"
            ax.step(0.5 * (edges[1:] + edges[:-1]), record["density"], where="mid",
                    label=f"{r['name']} (binarity {binarity})")
    ax.set_xlabel("cell void fraction")
    ax.set_ylabel("probability density")
    ax.set_title(f"cells below z = {below} m, second half of the run")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, Path(path))


FIG7_VELOCITIES = (1.6, 2.0, 2.3, 2.9)  # the paper's Fig. 7 panels (a)-(d), U/Umf


def plot_void_fraction_panels(panels: dict, path, below=0.3):
    """The paper's Fig. 7: one panel per U/Umf (``panels``: U/Umf -> runs), a histogram per family of the cell void
    fraction below ``below`` [m] over the second half of its runs' gas snapshots, the replicas pooled (each run's
    density weighted by its cells), labelled with each replica's binarity (``void_fraction_binarity``)."""
    import numpy as np
    from ...analysis.plots import _pyplot, _save
    plt = _pyplot()
    columns = min(2, len(panels))
    rows = (len(panels) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(5.0 * columns, 3.4 * rows), squeeze=False, sharey=True)
    for ax, (ratio, runs) in zip(axes.flat, sorted(panels.items())):
        by = {}
        for r in runs:
            record = void_fraction_record(r["folder"], below)
            if record is not None:
                by.setdefault(_column(r), []).append(record)
        for family, records in by.items():
            edges = np.asarray(records[0]["edges"])
            cells = np.array([rec["cells"] for rec in records], float)
            density = np.average([rec["density"] for rec in records], axis=0, weights=cells)
            binarity = ", ".join("-" if rec["binarity"] is None else f"{rec['binarity']:.2f}" for rec in records)
            ax.step(0.5 * (edges[1:] + edges[:-1]), density, where="mid",
                    label=f"{family} ({len(records)} run{'s' if len(records) > 1 else ''}, binarity {binarity})")
        ax.set_title(f"{ratio:g} Umf" + ("" if by else ": no gas snapshots"), fontsize=9)
        ax.set_xlabel("cell void fraction")
        ax.grid(alpha=0.3)
        if by:
            ax.legend(fontsize=7)
    for ax in axes[:, 0]:
        ax.set_ylabel("probability density")
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(f"cells below z = {below} m, second half of each run", fontsize=10)
    return _save(fig, Path(path))


# Mema et al.'s findings (§5-§6) that a study's t95 table can check; each rule sees the runs by family
CLOSE = 0.10  # relative differences below this need replicas to be told from chaos


SPREAD = 2.0  # with many replicas, an order is told where the means differ by more than this many standard errors
# with few, by more than Student's t at the same one-sided level (the normal distribution's at 2: 97.7 %) for the
# Welch-Satterthwaite degrees of freedom of the difference (``_critical``): 4.53 with two replicas a side (df 2),
# 2.87 with three (df 4), 2.15 with ten (df 18); a replica's spread is itself a guess
TOLD = 0.977249868051821  # Phi(SPREAD)


def _critical(df: float | None) -> float:
    """How many standard errors tell a difference (``SPREAD`` for ``df`` None or infinite: no spread estimated
    from the replicas, the ``CLOSE`` rule's error; else Student's t at ``TOLD`` for ``df`` degrees of freedom)."""
    if df is None or not math.isfinite(df):
        return SPREAD
    from scipy.stats import t
    return float(t.ppf(TOLD, max(df, 1.0)))


def _satterthwaite(terms: list, dfs: list) -> float | None:
    """The Welch-Satterthwaite degrees of freedom of a sum of variance terms (``terms``: each ``var / n``, with its
    estimate's degrees of freedom in ``dfs``); None where every term is 0."""
    total = sum(terms)
    below = sum(t * t / d for t, d in zip(terms, dfs) if t > 0)
    return total * total / below if below > 0 else None


def _degrees(a: list, b: list) -> float | None:
    """The degrees of freedom of ``_replica_error``'s difference (``_satterthwaite``): each family's variance with
    ``n - 1``, a borrowed one (``_variances``: one run, or replicas all counted at one end) with its lender's; None
    without a spread."""
    var = _variances(a, b)
    if var is None:
        return None
    own = [len(v) - 1 if len(v) > 1 and _sample_variance(v) > 0 else None for v in (a, b)]
    dfs = [d if d else other for d, other in zip(own, reversed(own))]
    return _satterthwaite([v / len(x) for v, x in zip(var, (a, b))], dfs)


def _sample_variance(values: list) -> float:
    mean = sum(values) / len(values)
    return sum((x - mean) ** 2 for x in values) / (len(values) - 1)


def _errors(k: float) -> str:
    """``k`` standard errors as the findings say it: "2 standard errors", "4.53 standard errors"."""
    return f"{k:.3g} standard errors"


def _margin_words() -> str:
    """The rules' words for the margin (``_critical``)."""
    return (f"Student's t at {100 * TOLD:.1f} % one-sided for the Welch-Satterthwaite degrees of freedom "
            f"({_critical(2):.3g} with two replicas a side, {SPREAD:g} with many)")


def _margin(a: list, b: list) -> tuple[float, float] | None:
    """The standard error of the difference of two families' means (``_replica_error``) and how many of it tell a
    difference (``_critical`` for its degrees of freedom, ``_degrees``); None without a spread."""
    error = _replica_error(a, b)
    return None if error is None else (error, _critical(_degrees(a, b)))


def _within_spread(a: list, b: list) -> str | None:
    """Whether two families' replica values at one velocity (a run not mixed by its end counted at its end) lie
    within their spread, where either has replicas: the difference of the means within ``_critical`` standard
    errors of it (Student's t for the difference's degrees of freedom, ``_degrees``; 2 for many replicas),
    ``sqrt(var_a / n_a + var_b / n_b)`` with each family's sample variance (a family of one run
    takes the other's: the same chaos; so does a family whose variance is 0, its replicas all unmixed and
    counted at the same end, where the spread is unknown, not absent). More replicas shrink the error, so an
    order that exists is told in the end. Returns the means and the bound as text, or None where the difference
    is beyond it, or neither family has replicas (the ``CLOSE`` rule then). Within it the two may yet be alike
    (``_alike``), which decides against a claimed order."""
    if max(len(a), len(b)) < 2:
        return None
    means = [sum(v) / len(v) for v in (a, b)]
    told = (f"means {means[0]:.3g} ({', '.join(f'{x:.3g}' for x in a)}) against {means[1]:.3g} "
            f"({', '.join(f'{x:.3g}' for x in b)})")
    margin = _margin(a, b)
    if margin is None:  # no spread known on either side: the CLOSE rule
        return None if _gap(*means) >= CLOSE else f"{told}, within {100 * CLOSE:.0f} % and no spread known"
    error, k = margin
    if abs(means[0] - means[1]) > k * error:
        return None
    return f"{told}, within {_errors(k)} ({k * error:.3g})"


def _alike(a: list, b: list, bounded: bool = False) -> str | None:
    """Whether two families' replica values at one velocity, whose order lies within their spread
    (``_within_spread``), are alike: the difference of the means with ``_critical`` standard errors either side
    (``_replica_error``) within ``CLOSE`` of the larger mean, the difference a single run's chaos leaves
    untold (an equivalence test, two one-sided at about 98 % each). A claimed order then does not hold there:
    a difference of ``CLOSE`` or more is ruled out. Without a spread known, None: one run each tells nothing of
    likeness. More replicas shrink the error, so two values that are alike are told alike in the end, as an order
    that exists is told: with enough replicas every comparison decides. ``bounded``: ``a`` holds runs counted at
    their end (not mixed by then), its mean a lower bound at or above ``b``'s: its true mean may lie anywhere above,
    so only one side is told, that ``b``'s mean lies at most ``CLOSE`` above it (``a`` does not lie below ``b`` by as
    much: against a claim that ``a`` is the lower, as decisive as alike). Returns the numbers as text, or None."""
    spread = _margin(a, b)
    if spread is None:
        return None
    error, k = spread
    means = [sum(v) / len(v) for v in (a, b)]
    margin = CLOSE * max(means)
    reach = (means[1] - means[0] if bounded else abs(means[0] - means[1])) + k * error
    if reach >= margin:
        return None
    within = f"within {100 * CLOSE:.0f} % of the larger ({margin:.3g})"
    if bounded:
        return (f"not below: the mean {means[0]:.3g}, a lower bound (runs not mixed by their end), against "
                f"{means[1]:.3g}, which with {_errors(k)} lies at most {reach:.3g} above it, {within}")
    return (f"alike: the means {means[0]:.3g} and {means[1]:.3g} differ by {abs(means[0] - means[1]):.3g}, with "
            f"{_errors(k)} at most {reach:.3g}, {within}")


def _variances(a: list, b: list) -> list | None:
    """The sample variances of two families' replica values at one velocity, a family of one run, or of replicas
    all counted at one end (variance 0: its spread unknown, not absent), taking the other's (the same chaos);
    None where neither has one."""
    var = [_sample_variance(v) if len(v) > 1 else None for v in (a, b)]
    var = [x if x else y for x, y in zip(var, reversed(var))]
    return var if all(var) else None


def _replica_error(a: list, b: list) -> float | None:
    """The standard error of the difference of two families' means at one velocity (``a``, ``b``: their replica
    values), ``sqrt(var_a / n_a + var_b / n_b)`` from the replicas' spread (``_variances``); None without one."""
    var = _variances(a, b)
    return None if var is None else (var[0] / len(a) + var[1] / len(b)) ** 0.5


def _difference_error(a: list, b: list) -> float:
    """``_replica_error``, or without a spread known the error at which ``SPREAD`` errors are ``CLOSE`` of the
    larger mean (the rule for values without replicas: a difference within 10 % is noise)."""
    error = _replica_error(a, b)
    return CLOSE * max(sum(a) / len(a), sum(b) / len(b)) / SPREAD if error is None else error


MAX_PLANNED = 5000  # replicas: a difference that would take more is "more replicas would tell"


def _replicas_to_tell(series, difference: float, margin: float | None, bounded: bool = False) -> list | None:
    """How many replicas each series of runs would need in all (its runs so far and the ones to add) to tell a
    difference (of two means, or of two differences' sizes) either way if the means and the spread stay as they
    are, at the least cost: the standard error ``sqrt(sum var_i / n_i)`` times ``_critical`` (at the plan's
    degrees of freedom, each series' ``n_i - 1``) below ``|difference|`` (an order told) or, with a ``margin``
    (``_alike``: None where likeness is not told), below ``margin - |difference|`` (alike), whichever is the
    larger. ``bounded``: the first mean is a lower bound at or above the second (runs not mixed by their end,
    ``_alike(bounded=True)``), whose likeness is one-sided (the second does not lie above it by ``margin``):
    below ``margin + difference`` then (the campaign's AR-4 MP at 1.6 Umf, both unmixed at 20 s, against drag
    only's 19.4 and 15.5 s: 6 more runs, not 19).
    ``series``: ``(runs so far, per-run variance, a replica's CPU seconds there or None)`` each; replicas are
    added one at a time where they cut the variance of the difference most per CPU second (per replica where a
    cost is unknown), which for these sums of ``var / n`` is the cheapest allocation: the noisy and the cheap
    series get the most. An estimate for planning ``[[points]]``: the next replicas move the means. None where
    no replica is missing, the difference is 0 and no margin applies, or more than ``MAX_PLANNED`` would be."""
    alike = 0.0 if margin is None else margin + difference if bounded else margin - abs(difference)
    need = max(abs(difference), alike)
    if need <= 0:
        return None
    counts = [max(1, count) for count, _, _ in series]
    known = all(cost for _, _, cost in series)
    costs = [cost if known else 1.0 for _, _, cost in series]
    start = list(counts)

    def short(counts):  # the margin (``_critical`` at the plan's degrees of freedom) times the error above ``need``
        terms = [var / n for (_, var, _), n in zip(series, counts)]
        k = _critical(_satterthwaite(terms, [max(n - 1, 1) for n in counts]))
        return k * k * sum(terms) > need ** 2

    while short(counts):
        if sum(counts) - sum(start) >= MAX_PLANNED:
            return None
        best = max(range(len(series)), key=lambda i: series[i][1] / (counts[i] * (counts[i] + 1)) / costs[i])
        counts[best] += 1
    return None if counts == start else counts


def _to_tell(plan: list | None, series=(), how: str = "[[points]]") -> str:
    """"about 17 of ar4_mp and 4 of ar1 in all would tell (now 3 and 4) ..." (``_replicas_to_tell``'s ``plan``
    for ``series``: ``(name, runs so far, a replica's CPU seconds there or None)`` each), with the core-hours
    the replicas to add would take at those costs (where all are known), or "more replicas would tell"; ``how``:
    the study file's way to add them."""
    if plan is None:
        return f"more replicas would tell: {how}"
    names = [f"{n} of {name}" for n, (name, _, _) in zip(plan, series)]
    now = [str(count) for _, count, _ in series]
    hours = _core_hours(plan, [count for _, count, _ in series], [cost for _, _, cost in series])
    return (f"about {_and(names)} in all would tell (now {_and(now)}), if the means and spread stay: {how}"
            + ("" if hours is None else f"; about {hours:.3g} core-hours at their runs' cost so far"))


def _core_hours(plan: list, counts: list, costs: list) -> float | None:
    """The core-hours of the replicas a plan adds (``plan``: in all; ``counts``: so far; ``costs``: a replica's CPU
    seconds of each), None where a cost is unknown."""
    if any(cost is None for cost in costs):
        return None
    return sum((n - count) * cost for n, count, cost in zip(plan, counts, costs)) / 3600.0


# the runs a finding's plan adds (``_plan_record``'s ``kind``, ``plan_points``): of the t95 findings (whole runs,
# or "<family>_t95"'s, which end when they mix), of the bed expansion (whole runs, or "<family>_expansion"'s, cut
# short after its window), of the void fractions (whole runs alone)
T95, EXPANSION_KIND, WHOLE = "t95", "expansion", "whole"


def _plan_record(plan: list, runs: list, kind: str) -> dict:
    """A finding's plan as data (``findings.json``'s ``plans``, which ``plan_points`` turns into ``[[points]]``):
    ``plan`` (``_replicas_to_tell``'s counts in all) for ``runs``, ``(family, U/Umf, runs so far, a replica's CPU
    seconds there or None)`` each; ``kind``: the runs that count there (``T95``, ``EXPANSION_KIND``, ``WHOLE``)."""
    hours = _core_hours(plan, [count for _, _, count, _ in runs], [cost for *_, cost in runs])
    return {"kind": kind, "core_hours": hours, "runs": [
        {"family": family, "u_over_umf": v, "replicas": n, "now": count, "cpu_seconds": cost}
        for n, (family, v, count, cost) in zip(plan, runs)]}


def _and(items: list) -> str:
    """"a", "a and b", "a, b and c"."""
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def _replica_cost(rows, family: str, v, column: str | None = None) -> float | None:
    """A replica's CPU seconds at a point so far: the mean ``cpu_seconds`` of the runs of ``family`` at U/Umf ``v``
    that reached their end (of those whose own family, ``column``, is ``column`` alone where given: the runs cut
    short of ``_expansion_runs``; without it, of the runs that ended when they mixed alone where the point has some,
    ``_t95_runs``: the replicas a t95 finding's plan adds are of those); None without one."""
    ended = [r for r in rows if r["family"] == family and r.get("gas.u_over_umf") == v and row_ended(r)
             and r.get("cpu_seconds") and (column is None or r.get("column") == column)]
    cut = [r for r in ended if r.get("cut_at_t95")]
    cpu = [r["cpu_seconds"] for r in (cut if column is None and cut else ended)]
    return sum(cpu) / len(cpu) if cpu else None


def _untold(v, a: list, b: list, gap: float, pair: str, names: tuple, alike: bool = True, how: str = "[[points]]",
            costs: tuple = (None, None), bounded: bool = False, plans: list | None = None,
            kind: str = T95) -> str | None:
    """Why the order of two families' values ``a`` and ``b`` at U/Umf ``v`` (their relative difference ``gap``)
    cannot be told: within the replicas' spread (``_within_spread``; ``pair`` names the two families), with how
    many replicas of each (``names``) would tell it at the least cost (``costs``: a replica's CPU seconds of each
    there, ``_replica_cost``; ``how``: the study file's way to add them) or, where ``alike`` (the values' likeness
    is told: ``_alike``), their likeness (``_replicas_to_tell``; ``bounded``: ``a``'s mean a lower bound at or
    above ``b``'s, its likeness one-sided), the plan also appended to ``plans`` as data (``_plan_record``, of runs
    of ``kind``); or within ``CLOSE`` without replicas. None where it can."""
    spread = _within_spread(a, b)
    if spread:
        var, means = _variances(a, b), [sum(x) / len(x) for x in (a, b)]
        series = list(zip(names, (len(a), len(b)), costs))
        plan = var and _replicas_to_tell([(count, s, cost) for (_, count, cost), s in zip(series, var)],
                                         means[0] - means[1], CLOSE * max(means) if alike else None, bounded)
        if plan and plans is not None:
            plans.append(_plan_record(plan, [(name, v, count, cost) for name, count, cost in series], kind))
        return f"{v:g} Umf within the replicas' spread ({pair}: {spread}; {_to_tell(plan, series, how)})"
    if gap < CLOSE and max(len(a), len(b)) < 2:
        return f"{v:g} Umf within {100 * CLOSE:.0f} % without replicas (too noisy to tell)"
    return None


def _gap(a: float, b: float) -> float:
    """The relative difference of two positive means (infinite where both are 0: nothing to tell apart)."""
    return abs(a - b) / max(a, b) if max(a, b) > 0 else float("inf")


TERMINAL = 0.25  # a terminal t95 within this of the paper's "about" value holds
# the paper's terminal mixing times [s] (§5.1, Fig. 4: "about" these from about 2.3 Umf on), the families they are of
PAPER_TERMINAL_T95 = {"ar1": 2.6, "ar4_mp": 2.3}
TERMINAL_FROM = 2.3  # U/Umf


SETTINGS_TOLERANCE = 0.15  # t95 at the defaults within this of t95 at the paper's settings: no change


def _compare_binarity(rows) -> dict:
    """AR-1's void fractions below 0.3 m more binary than AR-4 MP's (Fig. 7), at every velocity both ran."""
    claim = "AR-1 void fractions more binary than AR-4 (Fig. 7)"
    by = {}
    for r in rows:
        if r["family"] in ("ar1", "ar4_mp") and not row_failed(r) and r.get("void_fraction_binarity") is not None:
            by.setdefault(r.get("gas.u_over_umf"), {}).setdefault(r["family"], []).append(r["void_fraction_binarity"])
    common = sorted(v for v, fam in by.items() if v is not None and len(fam) == 2)
    if not common:
        return {"finding": claim, "verdict": "open", "why": "no velocity where AR-1 and AR-4 MP both have gas snapshots"}
    values, close, told, plans = {}, [], {}, []
    for v in common:
        a, b = (sum(by[v][f]) / len(by[v][f]) for f in ("ar1", "ar4_mp"))
        values[f"{v:g}"] = {"ar1": a, "ar4_mp": b}
        untold = _untold(v, by[v]["ar1"], by[v]["ar4_mp"], _gap(a, b), "AR-1 against AR-4 MP", names=("ar1", "ar4_mp"),
                         costs=tuple(_replica_cost(rows, f, v) for f in ("ar1", "ar4_mp")), plans=plans, kind=WHOLE)
        alike = untold and _alike(by[v]["ar1"], by[v]["ar4_mp"])
        if alike:  # alike within the noise: AR-1's not more binary
            told[v], values[f"{v:g}"]["alike"] = False, alike
        elif untold:
            close.append(untold)
        else:
            told[v] = a > b
    rule = ("binarity var / ((mean - packed)(1 - mean)) of the cells below 0.3 m, second half of the run; means of "
            f"the replicas apart by more than t standard errors ({_margin_words()}; within {100 * CLOSE:.0f} % "
            f"without replicas: too noisy); one velocity where AR-1's is told lower, or alike (within "
            f"{100 * CLOSE:.0f} % with t standard errors), decides")
    return _at_every_velocity(claim, told, close, values, rule, plans)


def _at_every_velocity(claim: str, told: dict, untold: list, values: dict, rule: str, plans=()) -> dict:
    """The verdict of a claimed order at every velocity both families ran: ``told`` (velocity -> whether the
    order holds there, where it could be told), ``untold`` (the velocities within the noise, as text). One
    velocity where it is told not to hold decides ``does not hold``, whatever the others leave open; else any
    untold velocity leaves it open (with ``plans``, the replicas that would tell them as data, ``_plan_record``);
    else it holds."""
    if not all(told.values()):
        return {"finding": claim, "verdict": "does not hold", "values": values, "rule": rule}
    if untold:
        return {"finding": claim, "verdict": "open", "why": "; ".join(untold), "values": values, "rule": rule,
                **({"plans": list(plans)} if plans else {})}
    return {"finding": claim, "verdict": "holds", "values": values, "rule": rule}


def _defaults_against_paper_settings(rows) -> dict:
    """The same point at fvdem's defaults (family ``ar1``) and at the paper's settings (``ar1_paper``):
    t95 within ``SETTINGS_TOLERANCE``, and the bed's pressure drop over W/A beside it."""
    claim = "fvdem's defaults do not change the mixing (AR-1 at the paper's own settings)"
    a, b = _t95(rows, "ar1"), _t95(rows, "ar1_paper")
    common = sorted(set(a) & set(b))
    if not common:
        return {"finding": claim, "verdict": "open", "why": "no velocity run both at the defaults and the paper's settings"}
    drop = {r["family"]: r.get("pressure_drop_over_weight") for r in rows
            if r["family"] in ("ar1", "ar1_paper") and r.get("gas.u_over_umf") in common}
    values = {f"{v:g}": {"defaults": a[v], "paper": b[v]} for v in common}
    values["pressure_drop_over_weight"] = drop
    if any(None in a[v] or None in b[v] for v in common):
        return {"finding": claim, "verdict": "open", "why": "not mixed by the run's end (too short)", "values": values}
    gaps = {f"{v:g}": abs(sum(a[v]) / len(a[v]) - sum(b[v]) / len(b[v])) / (sum(b[v]) / len(b[v])) for v in common}
    return {"finding": claim, "verdict": "holds" if max(gaps.values()) < SETTINGS_TOLERANCE else "does not hold",
            "values": values, "gaps": gaps, "rule": f"t95 within {100 * SETTINGS_TOLERANCE:.0f} %"}


def _by_velocity(rows, family, key):
    """``{U/Umf: [row[key], ...]}`` of the runs of a family that did not fail (replicas together)."""
    out = {}
    for r in rows:
        if r["family"] == family and not row_failed(r) and "gas.u_over_umf" in r:
            out.setdefault(r["gas.u_over_umf"], []).append(r.get(key))
    return out


def _t95(rows, family):
    """``{U/Umf: [t95 or None, ...]}`` of the runs of a family (replicas listed together)."""
    return _by_velocity(rows, family, "t95")


def _compare(rows, faster, slower, velocities, claim):
    """``faster`` mixes sooner than ``slower`` at every velocity of ``velocities`` both ran: the mean t95 of
    each family's replicas, a run not mixed by its end counted at its end (its t95 lies beyond: the mean is
    then a lower bound, with no upper one). At a velocity, ``faster`` is faster where its mean (known) lies
    below ``slower``'s lower bound, not faster where its lower bound reaches ``slower``'s mean; where either
    family has replicas, only beyond their spread (``_within_spread``: within it the order is open), and
    without replicas a difference within ``CLOSE`` is too noisy to tell. Where neither mixed by the same end,
    the higher mixing entropy there is the faster (``_entropy_order``), told by the same rules. One velocity
    where it is not faster decides."""
    a, b = _mean_t95(rows, faster), _mean_t95(rows, slower)
    common = sorted(v for v in set(a) & set(b) if velocities(v))
    if not common:
        return {"finding": claim, "verdict": "open", "why": f"no velocity where both {faster} and {slower} ran"}
    values, why, faster_at, plans = {}, [], {}, []
    counted = {f: _counted(rows, f) for f in (faster, slower)}  # read once, not per velocity
    for v in common:
        (low_a, unmixed_a), (low_b, unmixed_b) = a[v], b[v]
        mean_a, mean_b = (None if unmixed_a else low_a), (None if unmixed_b else low_b)
        values[f"{v:g}"] = {f: (mean if mean is not None else f"> {low:.3g} ({_unmixed(rows, f, v)})")
                            for f, low, mean in ((faster, low_a, mean_a), (slower, low_b, mean_b))}
        if mean_a is not None and mean_a < low_b:
            faster_at[v], gap = True, (low_b - mean_a) / low_b
        elif mean_b is not None and low_a >= mean_b:
            faster_at[v], gap = False, (low_a - mean_b) / low_a if low_a > 0 else 0.0
        elif mean_a is None and mean_b is None:
            pair = (faster, slower)
            entropy = {f: _by_velocity(rows, f, "final_mixing_entropy")[v] for f in pair}
            ends = {f: _by_velocity(rows, f, "simulated_seconds")[v] for f in pair}
            values[f"{v:g}"] = {"mixing_entropy_at_end": entropy, "end_time": ends}
            order = _entropy_order(entropy, ends)
            if order is None:
                why.append(f"neither mixed by its end at {v:g} Umf, and their ends differ (too short)")
                continue
            faster_at[v], gap = order
            untold = _untold(v, entropy[faster], entropy[slower], gap, f"neither mixed: {faster} against {slower}, "
                             f"mixing entropy at their end, {ends[faster][0]:g} s", alike=False, names=pair,
                             costs=tuple(_replica_cost(rows, f, v) for f in pair), plans=plans)
            if untold:  # never alike (``_alike``): near its ceiling 10 % of the entropy spans nearly to fully mixed
                why.append(untold)
                del faster_at[v]
            continue
        else:  # one side's lower bound passes the other's mean only once its unmixed runs go on
            unmixed, low, other = (faster, low_a, mean_b) if mean_a is None else (slower, low_b, mean_a)
            why.append(f"{unmixed} not mixed by its end at {v:g} Umf: its mean t95 is only known to exceed "
                       f"{low:.3g} s, against {other:.3g} s (run it longer: [[durations]])")
            continue
        bounded = mean_a is None and mean_b is not None  # faster's mean a bound at or above slower's (``_alike``)
        untold = _untold(v, counted[faster][v], counted[slower][v], gap, f"{faster} against {slower}, t95 [s]",
                         names=(faster, slower), costs=tuple(_replica_cost(rows, f, v) for f in (faster, slower)),
                         bounded=bounded, plans=plans)
        # alike within the noise: not faster; where only ``faster``'s mean is a bound (at or above the other's, as
        # here), not below by 10 % is told as well; ``slower``'s bound would bound the wrong side
        alike = untold and mean_b is not None and _alike(counted[faster][v], counted[slower][v], bounded)
        if alike:
            faster_at[v], values[f"{v:g}"]["alike"] = False, alike
        elif untold:
            why.append(untold)
            del faster_at[v]
    rule = ("mean t95 of the replicas, a run not mixed by its end counted at its end (a lower bound), apart by "
            f"more than t standard errors ({_margin_words()}); differences within {100 * CLOSE:.0f} % need replicas; "
            f"alike (the difference with t standard errors within {100 * CLOSE:.0f} % of the larger mean t95) is not "
            "faster; where neither mixed by the same end, the higher mean mixing entropy there mixes faster (Figs. 3, "
            "9 a)")
    return _at_every_velocity(claim, faster_at, why, values, rule, plans)


def _entropy_order(entropy: dict, ends: dict) -> tuple | None:
    """Where neither of two families (``{family: [per replica]}``, the faster-to-be first) mixed by its end:
    whether the first stands higher in mixing entropy at that end, and the relative difference of the means,
    as Mema et al. read their Figs. 3 and 9 (a): higher entropy at one time, more intensive mixing. Told only
    where every run of both ended at the same time with a known entropy (else None: a run that went on
    longer would stand higher for that alone)."""
    times = [e for f in ends for e in ends[f]]
    values = [x for f in entropy for x in entropy[f]] + times
    if any(x is None for x in values) or max(times) - min(times) > 1e-6 * max(times):
        return None
    first, second = (sum(v) / len(v) for v in entropy.values())
    return first > second, _gap(first, second)


def _counted(rows, family) -> dict:
    """``{U/Umf: [t95, ...]}`` of a family's replicas, a run not mixed by its end counted at its end (None where
    that end is unknown): the values ``_mean_t95`` averages and ``_within_spread`` spreads."""
    t, ends = _t95(rows, family), _by_velocity(rows, family, "simulated_seconds")
    return {v: [x if x is not None else e for x, e in zip(values, ends[v])] for v, values in t.items()}


def _unmixed(rows, family, v) -> str:
    """"k of n not mixed by their end (at 20 s, ...)" of a family's replicas at ``v``."""
    t95 = _t95(rows, family)[v]
    ends = [e for t, e in zip(t95, _by_velocity(rows, family, "simulated_seconds")[v]) if t is None]
    return (f"{len(ends)} of {len(t95)} not mixed by {'their' if len(ends) > 1 else 'its'} end, at "
            + ", ".join(f"{e:g}" for e in ends) + " s")


SHARP = 1.3  # t95 just below 2 Umf over t95 at 2 Umf: a fall to 1 / 1.3 (by 23 %) or more is sharp


def _mean_t95(rows, family) -> dict:
    """``{U/Umf: (mean t95 over the replicas, whether it is a lower bound)}`` of a family: a replica not mixed by
    its end counts as its end time, which makes the mean a lower bound (``check_findings`` has left out the
    runs still on their way), and a velocity with an unmixed replica of unknown end is left out."""
    t = _t95(rows, family)
    return {v: (sum(known) / len(known), None in t[v]) for v, known in _counted(rows, family).items()
            if known and None not in known}


SLIGHT = 0.2  # "only a slight effect": mean t95s within this fraction of MP's


def _slight(rows) -> dict:
    """SP against MP closures only a slight effect on AR-4 mixing (§5.3): at every velocity both ran, the mean
    t95s (``_mean_t95``) within ``SLIGHT`` of MP's. Where one family has not mixed by its end, its mean is a
    lower bound: the gap is then at least ``1 - SP / MP_low`` (MP unmixed) or ``SP_low / MP - 1`` (SP unmixed),
    enough to decide where that reaches ``SLIGHT``."""
    claim = "single- against multi-particle closures: only a slight effect on AR-4 mixing"
    sp, mp = _mean_t95(rows, "ar4_sp"), _mean_t95(rows, "ar4_mp")
    common = sorted(set(sp) & set(mp))
    rule = (f"mean t95 of SP within {100 * SLIGHT:.0f} % of MP's at every velocity both ran; an unmixed run "
            "counted at its end (a lower bound)")
    gaps, low, unknown = {}, {}, []  # low: the gap, or its lower bound where one family has not mixed
    for v in common:
        (s, s_unmixed), (m, m_unmixed), key = sp[v], mp[v], f"{v:g}"
        if not s_unmixed and not m_unmixed:
            low[key] = gaps[key] = abs(s - m) / m
            continue
        if m_unmixed and not s_unmixed and s < m:
            low[key] = 1 - s / m
            gaps[key] = f"> {low[key]:.3g} (MP not mixed by its end)"
        elif s_unmixed and not m_unmixed and s > m:
            low[key] = s / m - 1
            gaps[key] = f"> {low[key]:.3g} (SP not mixed by its end)"
        else:
            gaps[key] = "unknown: not mixed by its end, or both"
        if low.get(key, 0.0) < SLIGHT:
            unknown.append(key)
    apart = any(g >= SLIGHT for g in low.values())
    if not common:
        return {"finding": claim, "verdict": "open", "why": "no velocity where SP and MP both ran"}
    if apart:
        return {"finding": claim, "verdict": "does not hold", "values": gaps, "rule": rule}
    if unknown:
        return {"finding": claim, "verdict": "open", "values": gaps, "rule": rule,
                "why": f"not mixed by the runs' end at {', '.join(unknown)} Umf (too short to tell the gap)"}
    return {"finding": claim, "verdict": "holds", "values": gaps, "rule": rule}


def _sharp_drop(rows) -> dict:
    """AR-1's t95 drops sharply into 2 Umf (§5.1, Fig. 4): t95 at the velocity below 2 Umf over t95 at 2 Umf at
    least ``SHARP``, and larger than every drop between neighbouring velocities above 2 Umf."""
    claim = "AR-1's mixing time drops sharply at 2 Umf (Fig. 4)"
    t = _mean_t95(rows, "ar1")
    below = [v for v in t if v < 2.0]
    if 2.0 not in t or not below:
        return {"finding": claim, "verdict": "open", "why": "needs AR-1 at 2 Umf and at a velocity below it"}
    at, unmixed = t[2.0]
    if unmixed:
        return {"finding": claim, "verdict": "open", "why": "AR-1 at 2 Umf not mixed by the run's end (too short)"}
    before, bound = t[max(below)]
    drop = before / at
    higher = sorted(v for v in t if v >= 2.0)
    # a drop above 2 Umf whose lower velocity is unmixed is unknown: left out
    later = {f"{b:g}": t[a][0] / t[b][0] for a, b in zip(higher, higher[1:]) if not t[a][1]}
    values = {"t95": {f"{v:g}": (f"> {m:.3g} (not mixed by its end)" if lb else m) for v, (m, lb) in sorted(t.items())},
              f"drop {max(below):g} -> 2 Umf": f"> {drop:.3g}" if bound else drop, "drops above 2 Umf": later}
    rule = (f"t95 below 2 Umf over t95 at 2 Umf at least {SHARP:g} and above every drop between neighbouring "
            "velocities above 2 Umf")
    if drop < SHARP:
        if bound:
            return {"finding": claim, "verdict": "open", "values": values, "rule": rule,
                    "why": f"AR-1 at {max(below):g} Umf not mixed by its end; the drop is only known to exceed {drop:.3g}"}
        return {"finding": claim, "verdict": "does not hold", "values": values, "rule": rule}
    holds = all(d < drop for d in later.values())
    return {"finding": claim, "verdict": "holds" if holds else "does not hold", "values": values, "rule": rule}


def _gap_shrinks(rows, slow, fast, claim, planned=None) -> dict:
    """The t95 difference between ``slow`` and ``fast`` at the highest velocity both ran (above 2 Umf) is smaller
    in size than at every velocity up to 2 Umf (the paper: "becoming negligible" at 2.9 Umf; a difference that
    changed sign and grew is not one that shrank). Up to 2 Umf a run not mixed by its end bounds the difference
    (``slow`` unmixed: ``slow - fast > L``; ``fast`` unmixed: ``< U``): a bound away from 0 bounds its size, and
    decides there where it exceeds the size at the top; else that velocity is unknown (``_at_every_velocity``:
    one velocity told against decides, an unknown one leaves it open). Sizes within their noise that are alike
    (their difference with it within ``CLOSE`` of the larger t95, where replicas give both a spread, as in
    ``_alike``) decide against it there: it did not shrink. ``planned``: every run of the study,
    those not started too; while the highest velocity it runs both families at has no result for both, the
    finding waits for it (the paper's claim is at its highest velocity, 2.9 Umf)."""
    a, b = _mean_t95(rows, slow), _mean_t95(rows, fast)
    common = sorted(set(a) & set(b))
    high = [v for v in common if v > 2.0]
    low = [v for v in common if v <= 2.0 and not (a[v][1] and b[v][1])]
    if not high or not low:
        return {"finding": claim, "verdict": "open",
                "why": f"needs {slow} and {fast} mixed both above 2 Umf and at or below it"}
    top = max(high)
    both = set(_by_velocity(planned or [], slow, "t95")) & set(_by_velocity(planned or [], fast, "t95"))
    if both and max(both) > top:
        return {"finding": claim, "verdict": "open",
                "why": f"waits for the study's highest velocity, {max(both):g} Umf (both mixed up to {top:g} so far)"}
    if a[top][1] or b[top][1]:
        return {"finding": claim, "verdict": "open", "why": f"not mixed by the run's end at {top:g} Umf (too short)"}
    gap = abs(a[top][0] - b[top][0])
    counted = {f: _counted(rows, f) for f in (slow, fast)}
    error = {v: _difference_error(counted[slow][v], counted[fast][v]) for v in (top, *low)}
    var = {v: _variances(counted[slow][v], counted[fast][v]) for v in (top, *low)}  # None: no spread known
    dfs = {v: _degrees(counted[slow][v], counted[fast][v]) or math.inf for v in (top, *low)}  # inf: the CLOSE rule
    gaps, told, untold, plans = {}, {}, [], []
    for v in low:
        difference = a[v][0] - b[v][0]  # exact, or a lower (slow unmixed) or upper (fast unmixed) bound
        bound = difference if a[v][1] else -difference if b[v][1] else None  # a lower bound of the size, if > 0
        gaps[f"{v:g}"] = f"> {difference:.3g}" if a[v][1] else f"< {difference:.3g}" if b[v][1] else difference
        k = _critical(_satterthwaite([error[top] ** 2, error[v] ** 2], [dfs[top], dfs[v]]))
        noise = k * math.hypot(error[top], error[v])  # of the two sizes' difference
        # alike (``_alike``): the sizes' difference with its noise within CLOSE of the larger t95, spreads known
        margin = CLOSE * max(a[v][0], b[v][0], a[top][0], b[top][0])
        spreads = var[top] is not None and var[v] is not None
        if bound is None and abs(abs(difference) - gap) > noise:
            told[v] = gap < abs(difference)
        elif bound is None and spreads and abs(abs(difference) - gap) + noise < margin:
            told[v] = False  # not smaller by what a single run's chaos leaves untold: it did not shrink
            gaps[f"{v:g}"] = (f"{difference:.3g}, alike in size: {abs(difference):.3g} s against {gap:.3g} s at "
                              f"{top:g} Umf, with {_errors(k)} ({noise:.3g} s) within "
                              f"{100 * CLOSE:.0f} % of the larger t95 ({margin:.3g} s)")
        elif bound is None:
            runs = [(f, x, len(counted[f][x]), _replica_cost(rows, f, x)) for x in (v, top) for f in (slow, fast)]
            series = [(f"{f} at {x:g} Umf", count, cost) for f, x, count, cost in runs]
            spreads_of = [s for x in (v, top) for s in var[x]] if spreads else []
            plan = _replicas_to_tell([(count, s, cost) for (_, count, cost), s in zip(series, spreads_of)],
                                     abs(difference) - gap, margin) if spreads else None
            if plan:
                plans.append(_plan_record(plan, runs, T95))
            untold.append(f"{v:g} Umf: {slow} minus {fast} {abs(difference):.3g} s in size against {gap:.3g} s at "
                          f"{top:g} Umf, within {_errors(k)} of their difference ({noise:.3g} s; "
                          f"{_to_tell(plan, series)})")
        elif gap < bound - noise:
            told[v] = True
        else:
            untold.append(f"{v:g} Umf: {slow} minus {fast} only bounded ({gaps[f'{v:g}']} s), not past the "
                          f"{gap:.3g} s at {top:g} Umf by {_errors(k)} ({noise:.3g} s; run the unmixed "
                          "longer: [[durations]])")
    values = {f"difference at {top:g} Umf": a[top][0] - b[top][0], "differences up to 2 Umf": gaps}
    rule = (f"t95 of {slow} minus {fast}: smaller in size at {top:g} Umf than at every velocity up to 2 Umf, by "
            f"more than t standard errors of the two differences ({_margin_words()}; from the replicas' spread; "
            f"without replicas, {100 * CLOSE:.0f} % of the larger t95 for {SPREAD:g} errors); sizes alike (their "
            f"difference with t errors within {100 * CLOSE:.0f} % of the larger t95, spreads known) did not shrink; "
            "where a run there did not mix, its bound decides only where it exceeds that size so")
    return _at_every_velocity(claim, told, untold, values, rule, plans)


EXPANSION = "_expansion"  # a family "<name>_expansion": <name>'s runs cut short after the bed-expansion window


def _expansion_runs(rows) -> list:
    """``rows`` with the runs of each family "<name>_expansion" (``EXPANSION``) counted as <name>'s (each keeps
    its own family's name as ``column``). Such a family runs <name>'s case from beds of its own (other insertion
    seeds) only as long as the window its bed expansion is measured over (``_bed_expansion``: 5 s with a 1 s
    ramp): more replicas of the one finding that needs many (AR-4 MP's beds at 1.6-1.7 Umf expand 1.6-2.6 times
    by chance of a spout, AR-1's 1.7-1.9) at a quarter of a 20 s run's cost. They count for the expansion
    alone: a run cut short says nothing of t95, and its void fractions are of other times than a whole run's."""
    return [_counted_as_base(r, EXPANSION) if r["family"].endswith(EXPANSION) else r for r in rows]


T95_ONLY = "_t95"  # a family "<name>_t95": <name>'s runs that end when they mix, for the t95 findings alone


def _t95_runs(rows) -> list:
    """``rows`` with the runs of each family "<name>_t95" (``T95_ONLY``) counted as <name>'s, flagged
    ``cut_at_t95`` (each keeps its own family's name as ``column``; "<name>_tall_t95" becomes "<name>_tall", a
    taller column's run, ``_tall_columns``). Such a family runs <name>'s case from beds of its own (other
    insertion seeds) and ends when it mixes (``time.stop_after_mixed = 0``: t95 is the entropy's first crossing
    of 0.95, ``mixing_time``, so it is the same as a whole run's), or unmixed at its duration: the replicas the
    t95 findings need by the dozen at 2 and 2.9 Umf (the differences' sizes), a quarter to two fifths cheaper
    than runs that go on 2 s past t95. They count for the t95 findings and Fig. 4 alone: their void fractions
    (over the second half of a run) and bed expansion (over a window they may not reach) are of other times
    than a whole run's."""
    return [{**_counted_as_base(r, T95_ONLY), "cut_at_t95": True} if r["family"].endswith(T95_ONLY) else r
            for r in rows]


def _counted_as_base(row: dict, suffix: str) -> dict:
    """A run of family "<name><suffix>" (``TALL``, ``EXPANSION``, ``T95_ONLY``) as <name>'s, its own family kept
    as ``column``."""
    return {**row, "family": row["family"][:-len(suffix)], "column": row["family"]}


def _expansion(rows) -> dict:
    """AR-4 MP beds expand more than AR-1 beds at the same U/Umf (§5.1): the bed's expansion (its height,
    ``bed_top`` over the same window of each run that reached its end, over its settled height at the start;
    ``_bed_expansion``) larger at every velocity both ran, the runs of "<family>_expansion" families counted as
    their family's (``_expansion_runs``); a run whose bed top stood at the outlet for half the window or more
    (``bed_at_roof``) is left out, and a velocity left without a measured run of either family stays open."""
    claim = "AR-4 beds expand more than AR-1 at the same U/Umf"
    rows = _expansion_runs(rows)
    measured, roofed = _expansion_sample(rows)
    a, b = _by_velocity(measured, "ar4_mp", "bed_expansion"), _by_velocity(measured, "ar1", "bed_expansion")
    roof = sorted({(r["gas.u_over_umf"], r["family"]) for r in roofed if r["family"] in ("ar4_mp", "ar1")})
    common = sorted(set(a) & set(b))
    if not common:
        return {"finding": claim, "verdict": "open", "why": "no velocity where AR-1 and AR-4 MP both ran to their end"}
    values, why, told, plans = {}, [], {}, []
    for v, family in roof:
        if v not in a or v not in b:
            why.append(f"{v:g} Umf: {family}'s bed top stood at the outlet (particles pinned at the roof), its "
                       "height unknown")
    for v in common:
        ma, mb = sum(a[v]) / len(a[v]), sum(b[v]) / len(b[v])
        values[f"{v:g}"] = {"ar4_mp": a[v], "ar1": b[v]}
        untold = _untold(v, a[v], b[v], _gap(ma, mb), "AR-4 MP against AR-1",
                         how=f"[[points]] of ar4_mp{EXPANSION} and ar1{EXPANSION}, runs cut short after the window",
                         names=("ar4_mp", "ar1"),
                         costs=tuple(_replica_cost(rows, f, v, f + EXPANSION) for f in ("ar4_mp", "ar1")),
                         plans=plans, kind=EXPANSION_KIND)
        alike = untold and _alike(a[v], b[v])
        if alike:  # alike within the noise: AR-4's does not expand more
            told[v], values[f"{v:g}"]["alike"] = False, alike
        elif untold:
            why.append(untold)
        else:
            told[v] = ma > mb
    rule = (f"mean bed expansion (bed_top from {WINDOW_START:g} s after the inlet ramp for {WINDOW:g} s, over "
            f"its settled value) of AR-4 MP above AR-1's at every velocity both ran, the means apart by more than "
            f"t standard errors ({_margin_words()}; within {100 * CLOSE:.0f} % without replicas: too noisy); one "
            f"velocity where AR-4 MP's is told lower, or alike (within {100 * CLOSE:.0f} % with t standard errors), "
            "decides; a bed whose top stood at the outlet for half the window or more is left out (its height is the "
            f"outlet's); the runs of a family \"<family>{EXPANSION}\" (<family>'s case from other beds, cut short "
            "after the window) count as <family>'s")
    finding = _at_every_velocity(claim, told, why, values, rule, plans)
    dense = _dense_bed_note(measured)
    return {**finding, "note": dense} if dense else finding


def _expansion_sample(rows) -> tuple[list, list]:
    """The runs whose bed expansion counts (ended, with ``bed_expansion``) and, apart, those left out because
    their bed's top stood at the outlet for most of the window (``_roofed``: no height of its own there)."""
    ended = [r for r in rows if row_ended(r) and r.get("bed_expansion") is not None]
    at_roof = [_roofed(r) for r in ended]
    return ([r for r, roof in zip(ended, at_roof) if not roof], [r for r, roof in zip(ended, at_roof) if roof])


def _table_figures(out: Path, rows: list) -> list:
    """Figures of the table's values, counted as the findings count them (``check_findings``: the runs that
    mixed or ended, a taller column's in place of the paper's column's at their point): the bed expansion
    against U/Umf, AR-1 against AR-4 MP (``bed_expansion.png``, ``plot_expansion``)."""
    counted = _tall_columns(_told_rows(rows))[0]
    measured, roofed = _expansion_sample(_expansion_runs(counted))
    families = ("ar1", "ar4_mp")
    if not any(r["family"] in families for r in measured):
        return []
    return [plot_expansion([r for r in measured if r["family"] in families],
                           [r for r in roofed if r["family"] in families], out / "bed_expansion.png")]


def plot_expansion(measured: list, roofed: list, path) -> Path:
    """Bed expansion against U/Umf, AR-1 against AR-4 MP, as the finding counts it (``_expansion``; §5.1, where
    the paper shows it in its snapshots, Figs. 5-6): the bed's top over the window (``_bed_expansion``) over
    the settled bed's. Each run is a marker (hollow: a run of a "<family>_expansion" family, cut short after the
    window), the line joins the means of the replicas at each U/Umf, with the standard error of each mean times
    Student's t (``_critical`` for ``n - 1`` degrees of freedom) as a bar; a run left out for its bed top at the
    outlet is a cross."""
    import numpy as np

    from ...analysis.plots import _pyplot, _save
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    cut_short = left_out = False
    for family, label in (("ar1", "AR-1"), ("ar4_mp", "AR-4 MP")):
        by = {}
        for r in measured:
            if r["family"] == family:
                by.setdefault(float(r["gas.u_over_umf"]), []).append(r)
        if not by:
            continue
        ratios = sorted(by)
        values = [[float(r["bed_expansion"]) for r in by[v]] for v in ratios]
        means = [float(np.mean(x)) for x in values]
        bars = [_critical(len(x) - 1) * float(np.std(x, ddof=1)) / len(x) ** 0.5 if len(x) > 1 else 0.0
                for x in values]
        line = ax.errorbar(ratios, means, yerr=bars, capsize=3, lw=1.5,
                           label=f"{label} (runs; the line: mean, bar: t standard errors, t at {100 * TOLD:.1f} %)")
        colour = line[0].get_color()
        for v in ratios:
            offsets = (np.arange(len(by[v])) - (len(by[v]) - 1) / 2) * 0.012
            for r, dx in zip(by[v], offsets):
                cut = r.get("column", r["family"]).endswith(EXPANSION)
                cut_short = cut_short or cut
                ax.plot(v + dx, r["bed_expansion"], "o", ms=4, color=colour, mfc="none" if cut else colour)
        for r in roofed:
            if r["family"] == family:
                left_out = True
                ax.plot(float(r["gas.u_over_umf"]), r["bed_expansion"], "x", ms=6, color=colour)
    if cut_short:
        ax.plot([], [], "o", ms=4, mfc="none", color="0.3", label="a run cut short after the window (its own bed)")
    if left_out:
        ax.plot([], [], "x", ms=6, color="0.3", label="left out: its bed top at the outlet most of the window")
    ax.set_xlabel("U / Umf")
    ax.set_ylabel("bed expansion (bed top over the settled bed's)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, Path(path))


def _dense_bed_note(rows) -> str | None:
    """The dense beds' expansion (``dense_bed_expansion``: the height under 90 % of the particle centres) of AR-4
    MP and AR-1 at each velocity both have it, as text beside the expansion finding: not its rule's measure (the
    bed's top), but where the two differ the bed's top is set by a few particles thrown up. None where no
    velocity has both."""
    a, b = (_by_velocity([r for r in rows if r.get("dense_bed_expansion") is not None], family, "dense_bed_expansion")
            for family in ("ar4_mp", "ar1"))
    common = sorted(set(a) & set(b))
    if not common:
        return None

    def listed(values):
        mean = f"{sum(values) / len(values):.3g}"
        return mean if len(values) == 1 else f"{mean} ({', '.join(f'{x:.3g}' for x in values)})"

    return (f"the dense bed, the height under {100 * DENSE:.0f} % of the particle centres over the same window over "
            "its settled value (runs with particle snapshots; not the rule's measure): " + "; ".join(
                f"{v:g}: AR-4 MP {listed(a[v])} against AR-1 {listed(b[v])}" for v in common))


def _velocities_in(values) -> set:
    """The U/Umf a finding's ``values`` hold numbers of: keys that are a velocity ("2.9") or name one ("difference
    at 2.9 Umf"), at any level."""
    found = set()
    if isinstance(values, dict):
        for key, value in values.items():
            match = re.fullmatch(r"\d+(?:\.\d+)?", key) or re.search(r"(\d+(?:\.\d+)?) Umf", key)
            if match and "up to" not in key:
                found.add(float(match.group(1) if match.groups() else match.group(0)))
            found |= _velocities_in(value)
    return found


def _roof_note(finding: dict, rows: list, families) -> dict:
    """``finding`` with a ``note`` naming the runs of ``families``, at a velocity its numbers hold, that reached
    their end with their bed's top at the outlet for half the window or more (``bed_at_roof``): their t95 counts
    (particles pinned at the roof are part of that column's mixing) but is the column's as much as the bed's,
    which the reader of a verdict should know (AR-4 MP at 2.9 Umf: 3 % of the rods, all of the upper colour, held
    at the 1.05 m outlet from 1.5 to 4 s)."""
    used = _velocities_in(finding.get("values"))
    roofed = {}
    for r in rows:
        if r["family"] in families and _among((r["gas.u_over_umf"],), used) and row_ended(r) and _roofed(r):
            roofed.setdefault((r["family"], r["gas.u_over_umf"]), []).append(r.get("roof_share"))
    if not roofed:
        return finding
    return {**finding, "note": "bed at the outlet, particles pinned at the roof: " + ", ".join(
        f"{family} at {v:g} Umf" + _shares(roofed[family, v]) for family, v in sorted(roofed))}


TALL = "_tall"  # a family "<name>_tall": <name>'s closures and bed in a column taller than the paper's 1.05 m


def _tall_columns(rows, at=lambda r: r.get("gas.u_over_umf")) -> tuple[list, dict]:
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


def _column_note(finding: dict, aside: dict, families) -> dict:
    """``finding`` with a note (after ``_roof_note``'s) naming the points of ``families``, at a velocity its
    numbers hold, whose t95 came from a taller column (``_tall_columns``), with what the paper's column's runs
    set aside there measured: t95 (or their end, unmixed) and the share of their particles pinned at its
    outlet."""
    used = _velocities_in(finding.get("values"))
    points = sorted(key for key in aside if key[0] in families and _among(key[1:], used))
    if not points:
        return finding
    parts = []
    for family, v in points:
        runs = aside[family, v]
        heights = sorted({r["column_height"] for r in runs if r.get("column_height")})
        measured = ", ".join(f"{r['t95']:.3g} s" if r.get("t95") is not None else
                             f"not mixed by {r.get('simulated_seconds') or 0:g} s" for r in runs)
        parts.append(f"{family} at {v:g} Umf from the taller column ({family}{TALL}); in the paper's "
                     + (f"{heights[0]:g} m " if len(heights) == 1 else "") + f"column t95 {measured}"
                     + _shares([r.get("roof_share") for r in runs], "pinned at its outlet at the end"))
    note = "t95 from a column without the roof: " + "; ".join(parts)
    return {**finding, "note": f"{finding['note']}; {note}" if finding.get("note") else note}


def _shares(shares: list, where: str = "there at the end") -> str:
    """The shares of the particles at the roof of a point's runs (``roof_share``), as a note's parenthesis."""
    known = [f"{100 * x:.1f}" for x in shares if x is not None]
    return f" ({', '.join(known)} % of the particles {where})" if known else ""


def _told_rows(rows) -> list:
    """The rows the findings count: a run that has mixed, or is no longer on its way (a run still running and
    not yet mixed, or not started, is left out, not taken as unmixed)."""
    return [r for r in rows if r.get("t95") is not None or not row_on_the_way(r)]


WINDOW_TIMES = tuple(1.0 + 0.5 * k for k in range(15))  # s: 1.0, 1.5, ..., 8.0: the entropy curve's window
ENTROPY_TIMES = (2.0, 4.0, 6.0, 8.0)  # s: the entropy at fixed times the table shows beside its window mean
LATER_READINGS: list = []  # later sets of rules, each ``(rows, whole) -> findings`` (``mema2020_readings``)


def entropy_columns(series, ended_mixed: bool) -> dict:
    """A run's mixing entropy at ``ENTROPY_TIMES`` (``mixing_entropy_at_<t>``) and averaged over ``WINDOW_TIMES``
    (``mixing_entropy_window``), from its time series; a time past the series' end holds the last value where
    the run ended mixed, else None (not reached yet)."""
    import numpy as np
    keys = [f"mixing_entropy_at_{t:g}" for t in ENTROPY_TIMES] + ["mixing_entropy_window"]
    if series is None or "mixing_entropy" not in series or not len(series["time"]):
        return dict.fromkeys(keys)
    time, entropy = np.asarray(series["time"], float), np.asarray(series["mixing_entropy"], float)

    def at(t):
        if t > time[-1] + 1e-9 and not ended_mixed:
            return None
        return float(np.interp(t, time, entropy))

    values = {f"mixing_entropy_at_{t:g}": at(t) for t in ENTROPY_TIMES}
    window = [at(t) for t in WINDOW_TIMES]
    values["mixing_entropy_window"] = None if None in window else float(sum(window) / len(window))
    return values



def check_findings(rows) -> list:
    """Each finding of Mema et al. (2020) (§5-§6), with fvdem's numbers and one word: holds, does not hold, or
    open (and why: runs missing, too short to mix, or differences within the noise without replicas).
    From the t95 table: AR-4 against AR-1 up to 2 Umf and their difference shrinking at the highest velocity,
    AR-1's sharp drop at 2 Umf, lift and torque (and their effect shrinking at the highest velocity), SP
    against MP (slight; MP faster above 2 Umf), the terminal t95 and its change above 2.3 Umf; from the bed
    height: AR-4 beds expand more; from the gas snapshots: AR-1's void fractions more binary than AR-4's
    (``void_fraction_binarity``, Fig. 7); and, in a study with a family ``ar1_paper`` (the paper's
    settings) beside ``ar1``, whether fvdem's defaults change the mixing (not a finding of the paper: absent
    otherwise). A run still on its way (or not started) counts once it has mixed; until then it is left
    out, not taken as unmixed. The runs of a family "<name>_t95" count as <name>'s in the t95 findings alone
    (``_t95_runs``), not in the bed expansion's nor the void fractions'."""
    whole = [r for r in rows if not r["family"].endswith(T95_ONLY)]  # the expansion's and the void fractions'
    table = rows  # as given: the later readings count their runs themselves
    rows = _t95_runs(rows)
    planned, rows = rows, _told_rows(rows)
    planned = _tall_columns(planned)[0]  # a taller column's runs in place of the paper's column's at their points
    rows, aside = _tall_columns(rows)

    def noted(finding, families):  # the roofed runs counted, the paper's column's runs set aside (the notes)
        return _column_note(_roof_note(finding, rows, families), aside, families)

    # each t95 finding with the families whose roofed or set-aside runs it notes
    findings = [noted(finding, families) for finding, families in (
        (_compare(rows, "ar4_mp", "ar1", lambda v: v <= 2.0, "AR-4 (MP) mixes faster than AR-1 up to 2 Umf"),
         ("ar4_mp", "ar1")),
        (_gap_shrinks(rows, "ar1", "ar4_mp", "the AR-1/AR-4 difference shrinks at the highest velocity (2.9 Umf)",
                      planned), ("ar4_mp", "ar1")),
        (_sharp_drop(rows), ("ar1",)),
        (_compare(rows, "ar4_mp", "ar4_mp_drag", lambda v: True, "lift and torque shorten AR-4 mixing"),
         ("ar4_mp", "ar4_mp_drag")),
        (_gap_shrinks(rows, "ar4_mp_drag", "ar4_mp", "the effect of lift and torque shrinks at the highest velocity",
                      planned), ("ar4_mp", "ar4_mp_drag")),
        (_compare(rows, "ar4_mp", "ar4_sp", lambda v: v > 2.0,
                  "MP closures widen the AR-1/AR-4 difference above 2 Umf (AR-4 MP mixes faster than SP)"),
         ("ar4_mp", "ar4_sp")),
        (_slight(rows), ("ar4_mp", "ar4_sp")))]
    for family, paper in PAPER_TERMINAL_T95.items():
        t = _t95(rows, family)
        high = sorted(v for v in t if v >= TERMINAL_FROM)
        claim = f"terminal t95 of {family} about {paper} s (paper)"
        change = f"{family}: little change of t95 above about 2.3 Umf"
        mine = []
        mixed = [v for v in high if None not in t[v]]
        means = {f"{v:g}": sum(t[v]) / len(t[v]) for v in mixed}
        # both rules are of every velocity from 2.3 Umf on: they wait for those the study plans and has no result at
        waiting = sorted(v for v in _t95(planned, family) if v >= TERMINAL_FROM and v not in t)
        if waiting and mixed:
            why = (f"waits for {', '.join(f'{v:g}' for v in waiting)} Umf (mixed so far at "
                   f"{', '.join(f'{v:g}' for v in mixed)})")
            findings += [{"finding": claim, "verdict": "open", "why": why},
                         {"finding": change, "verdict": "open", "why": why}]
            continue
        if not high:
            mine.append({"finding": claim, "verdict": "open", "why": f"no velocity at or above {TERMINAL_FROM:g} Umf"})
        elif not mixed:
            mine.append({"finding": claim, "verdict": "open", "why": "not mixed by the run's end (too short)"})
        else:
            terminal = sum(means.values()) / len(means)
            mine.append({"finding": claim, "verdict": "holds" if abs(terminal / paper - 1) < TERMINAL else "does not hold",
                         "values": means, "rule": f"mean t95 at or above {TERMINAL_FROM:g} Umf within "
                                                  f"{100 * TERMINAL:.0f} % of the paper"})
        if len(mixed) < 2:
            mine.append({"finding": change, "verdict": "open",
                         "why": f"fewer than two mixed velocities at or above {TERMINAL_FROM:g} Umf"})
        else:
            spread = (max(means.values()) - min(means.values())) / max(means.values())
            mine.append({"finding": change, "verdict": "holds" if spread < 0.2 else "does not hold",
                         "values": means, "rule": "spread below 20 %"})
        findings += [noted(f, (family,)) for f in mine]
    whole = _tall_columns(_told_rows(whole))[0]
    findings.append(_expansion(whole))
    findings.append(_compare_binarity(whole))
    if any(r["family"] == "ar1_paper" for r in rows):  # fvdem's own check, where a study runs that family
        findings.append(_defaults_against_paper_settings(rows))
    for readings in LATER_READINGS:  # later rules, beside these (never in their place)
        findings += readings(table, [r for r in table if not r["family"].endswith(T95_ONLY)])
    return findings


def _cheaper(kind: str) -> tuple:
    """The family suffix of the cheaper runs that count for a plan of ``kind``, if any: "<family>_t95" for a t95
    finding (``T95_ONLY``), "<family>_expansion" for the bed expansion (``EXPANSION``)."""
    return {T95: (T95_ONLY,), EXPANSION_KIND: (EXPANSION,), WHOLE: ()}[kind]


def _counted_as(rows, kind: str) -> list:
    """``rows`` as a finding of ``kind`` counts them (``check_findings``' mapping): each run under the family it
    counts as, "<family>_t95" runs only in the t95 findings (``_t95_runs``), "<family>_expansion" runs only in the
    bed expansion (``_expansion_runs``), a taller column's runs in place of the paper column's at their point
    (``_tall_columns``)."""
    if kind == T95:
        return _tall_columns(_t95_runs(rows))[0]
    whole = _tall_columns([r for r in rows if not r["family"].endswith(T95_ONLY)])[0]
    return _expansion_runs(whole) if kind == EXPANSION_KIND else whole


def _plan_family(base: str, v, kind: str, present: dict) -> str | None:
    """The study family that the replicas a plan adds to ``base`` at U/Umf ``v`` would be of: the cheapest that
    counts for ``kind`` and the study runs there (``present``: ``{(family, U/Umf): replicas}``), in the taller
    column where the study runs ``base`` in one there (``_tall_columns``); None where none runs there."""
    cheap = _cheaper(kind)
    tall = any((base + TALL + suffix, v) in present for suffix in ("", *cheap))
    column = base + TALL if tall else base
    return next((column + suffix for suffix in (*cheap, "") if (column + suffix, v) in present), None)


def _on_the_way(counted, base: str, v, kind: str) -> int:
    """How many of the study's runs that count as ``base``'s at ``v`` in a finding of ``kind`` (``counted``: the
    study's rows as ``_counted_as`` maps them for ``kind``) have no result yet (not started, or on their way and
    not mixed where ``kind`` is t95)."""
    return sum(r["family"] == base and r.get("gas.u_over_umf") == v and row_on_the_way(r)
               and (kind != T95 or r.get("t95") is None) for r in counted)


def plan_points(rows, findings, study: str | None = None) -> str:
    """The ``[[points]]`` tables that would add the replicas the open findings' plans ask (``findings.json``'s
    ``plans``, ``_replicas_to_tell``: how many of each family in all would tell a difference if the means and
    spread stay), as TOML to append to the study file: per family and velocity, the most any finding asks, less
    the runs counted so far and those the study already has on their way (``_on_the_way``), added to the study's
    replicas there; each replica of the cheapest study family that counts (``_plan_family``: "<family>_t95" for
    a t95 finding, "<family>_expansion" for the bed expansion, in the taller column where the study runs one).
    Each table says which findings ask it and what it costs at its point's runs so far; findings open without a
    plan (runs to lengthen, or more replicas than ``MAX_PLANNED``) are listed by name."""
    present = {}
    for r in rows:
        key = (r["family"], r.get("gas.u_over_umf"))
        present[key] = max(present.get(key, 0) + 1, r.get("replica") or 0)
    counted = {kind: _counted_as(rows, kind) for kind in (T95, EXPANSION_KIND, WHOLE)}
    tables, queued, lines = {}, [], []
    for finding in findings:
        if finding["verdict"] != "open":
            continue
        if not finding.get("plans"):
            lines.append(f"# - {finding['finding']}: no replicas planned (findings.md says why it is open)")
            continue
        for plan in finding["plans"]:
            for run in plan["runs"]:
                base, v = run["family"], run["u_over_umf"]
                way = _on_the_way(counted[plan["kind"]], base, v, plan["kind"])
                add = run["replicas"] - run["now"] - way
                said = (f"{finding['finding']}: {run['replicas']} of {base} at {v:g} Umf in all (now {run['now']}"
                        + (f", {way} on the way" if way else "") + ")")
                if add <= 0:
                    queued.append(said)
                    continue
                family = _plan_family(base, v, plan["kind"], present) or base
                table = tables.setdefault((family, v), {"from": present.get((family, v), 0), "replicas": 0,
                                                        "cost": run["cpu_seconds"], "why": []})
                table["replicas"] = max(table["replicas"], table["from"] + add)
                table["why"].append(said + ("" if (family, v) in present else
                                            f"; {family} does not run at {v:g} Umf in the study: an [[exclude]] "
                                            "may drop it"))
    hours = _core_hours([t["replicas"] for t in tables.values()], [t["from"] for t in tables.values()],
                        [t["cost"] for t in tables.values()])
    head = [f"# {study or 'study'}: the replicas that would decide the open findings if the means and spread stay",
            "# (`fvdem study --report` from findings.json's plans; findings.md says why each is open). Append these",
            "# tables to the study file and run it again: the last [[points]] table that matches a run sets its",
            "# replicas, and the runs so far are kept.",
            f"# {len(tables)} table{'' if len(tables) == 1 else 's'}"
            + ("" if hours is None else f", about {hours:.3g} core-hours at their points' runs so far") + ": each",
            "# velocity's plan on its own (where one velocity told against decides a finding, fewer may do)."]
    head += [f"# - in the study already: {said}" for said in queued] + lines
    body = []
    for (family, v), t in sorted(tables.items(), key=lambda kv: (kv[0][0], kv[0][1])):
        body += [""] + [f"# {why}" for why in t["why"]]
        more = t["replicas"] - t["from"]
        if t["cost"] is not None:
            body.append(f"# {more} more, about {more * t['cost'] / 3600:.3g} core-hours")
        body += ["[[points]]", f'family = "{family}"', f'"gas.u_over_umf" = {float(v)!r}',
                 f"replicas = {t['replicas']}  # {t['from']} in the study so far"]
    return "\n".join(head + body) + "\n"


def _live(series) -> dict:
    """A run in progress from its time series: t95 (None if not yet mixed), and the bed pressure drop over
    W/A and its fluctuation over the second half of what it holds."""
    import numpy as np
    from ...analysis.plots import series_t95
    times = series["time"]
    out = {"t95": series_t95(series)}
    if "pressure_drop_over_weight" in series and len(times) > 1:
        half = series["pressure_drop_over_weight"][times >= 0.5 * times[-1]]
        out["pressure_drop_over_weight"] = float(np.mean(half))
        out["pressure_drop_std_over_weight"] = float(np.std(half))
    return out


def _mixed_or_ended(r: dict) -> bool:
    """Whether the t95 chart shows a run (``report`` derived its status): mixed (its t95 known), or ended
    unmixed (its end a lower bound of t95); a run still on its way and not yet mixed is left out (its current
    time bounds nothing yet)."""
    return r.get("t95") is not None or row_ended(r)


# the paper's pairs of families, the second drawn solid and the first dashed as in its figures, and the velocities
# its figure shows: Fig. 3 AR-1 against AR-4 MP at 1.6, 1.7 and 2.9 Umf; Fig. 9 a AR-4 MP drag only against drag,
# lift and torque at every velocity the drag-only family ran
PAPER_PAIRS = {"fig3": ("ar1", "ar4_mp", (1.6, 1.7, 2.9)), "fig9": ("ar4_mp_drag", "ar4_mp", None)}


def _among(point: tuple, velocities) -> bool:
    """Whether an axes point (``_pairs``' keys) holds one of ``velocities`` (U/Umf, to rounding)."""
    return any(abs(v - w) < 1e-9 for v in point for w in velocities)


def _figures(out: Path, runs: list) -> list:
    """Mixing entropy per family, a colour per velocity (Fig. 2), t95 against U/Umf (Fig. 4: the runs that mixed
    or ended), the paper's pairs at its velocities on one chart each (``PAPER_PAIRS``: ``fig3_mixing.png``,
    ``fig9_mixing.png``), and at each velocity both families ran: AR-1 against AR-4 MP run by run (Fig. 3) with
    their void fractions below 0.3 m (Fig. 7), and AR-4 MP drag only against drag + lift + torque (Fig. 9). The
    pairs take a taller column's runs that mixed or ended for their family's, as the findings do
    (``_tall_columns``)."""
    from ...analysis.plots import plot_mixing, plot_mixing_by_velocity, plot_t95
    paths = []
    levels = [r["point"]["gas.u_over_umf"] for r in runs if "gas.u_over_umf" in r.get("point", {})] or None
    for family in sorted({r["family"] for r in runs}):
        mine = [r for r in runs if r["family"] == family]
        paths.append(plot_mixing_by_velocity([Path(r["folder"]) for r in mine], out / f"mixing_{family}.png",
                                             names=[family] * len(mine), levels=levels,
                                             ended=[row_ended(r) for r in mine]))
    # the paper's pairs as the findings take them: a taller column's runs that mixed or ended for their family's
    # at their point (``_tall_columns``), named as their own family on the charts
    standing = [r for r in runs if not r["family"].endswith(TALL) or _mixed_or_ended(r)]
    as_found = _tall_columns(standing, _point)[0]
    # Figs. 4 and 7 as the findings take them too, of the runs that mixed or ended, and the runs set aside
    # (a "<family>_expansion" family's runs, cut short after the bed-expansion window, tell no t95: ``EXPANSION``;
    # a "<family>_t95" family's, which end when they mix, count as <family>'s in Fig. 4 alone: ``T95_ONLY``)
    told = [r for r in standing if _mixed_or_ended(r) and not r["family"].endswith(EXPANSION)]
    shown, set_aside = _tall_columns(_t95_runs(told), _point)
    paired = {figure: sorted(_pairs(as_found, first, second).items())
              for figure, (first, second, _) in PAPER_PAIRS.items()}
    for figure, (first, second, velocities) in PAPER_PAIRS.items():
        pairs = [r for point, pair in paired[figure] for r in pair if velocities is None or _among(point, velocities)]
        if pairs:
            styles = {first: "--", second: "-", first + TALL: "--", second + TALL: "-"}
            paths.append(plot_mixing_by_velocity([Path(r["folder"]) for r in pairs], out / f"{figure}_mixing.png",
                                                 names=[_column(r) for r in pairs], styles=styles,
                                                 levels=levels, ended=[row_ended(r) for r in pairs]))
    if shown:
        paper = {family: (t95, TERMINAL_FROM, f"{family}: the paper's terminal t95, about {t95:g} s")
                 for family, t95 in PAPER_TERMINAL_T95.items()}
        # each family's line through the values its findings count (a taller column's runs in place of the paper's
        # column's at their point, ``_tall_columns``), the runs set aside as crosses in its colour
        drawn = shown + [{**r, "family": _set_aside(family)} for (family, _), rs in set_aside.items() for r in rs]
        paths.append(plot_t95([Path(r["folder"]) for r in drawn], out / "t95.png", names=[r["family"] for r in drawn],
                              references=paper, aside={_set_aside(family): family for family, _ in set_aside}))
    # the void fractions of the fluidized bed (Fig. 7): a run on its way and not yet mixed may still be in its
    # start-up (the second half of 0.8 s is the packed bed), so those runs wait, as in the findings
    whole = _tall_columns([r for r in told if not r["family"].endswith(T95_ONLY)], _point)[0]
    fluidized = sorted(_pairs(whole, *PAPER_PAIRS["fig3"][:2]).items())
    panels = {point[0]: pair for point, pair in fluidized if len(point) == 1 and _among(point, FIG7_VELOCITIES)}
    if panels:
        paths.append(plot_void_fraction_panels(panels, out / "fig7_void_fraction.png"))
    for figure in PAPER_PAIRS:
        for point, pair in paired[figure]:
            paths.append(plot_mixing([Path(r["folder"]) for r in pair], out / f"{figure}_mixing_{_tag(point)}.png"))
    for point, pair in fluidized:
        paths.append(plot_void_fractions(pair, out / f"fig7_void_fraction_{_tag(point)}.png"))
    return paths


def _set_aside(family: str) -> str:
    """The t95 chart's name of a family's runs set aside for a taller column's (``_tall_columns``)."""
    return f"{family}: the paper's column, set aside (particles pinned at its outlet)"


def _column(r: dict) -> str:
    """A run's family as a chart names it: a taller column's own (``_tall_columns``' ``column``) or its family."""
    return r.get("column", r["family"])


def _tag(point: tuple) -> str:
    """An axes point as a file name's part: its values joined by ``_`` (2.0 and 1.6 -> "2_1.6")."""
    return "_".join(f"{v:g}" for v in point)


def _columns(r: dict, folder: Path, data: dict, series) -> dict:
    """t95 and t95 counted from when the inlet passes Umf, the column's height (its outlet), the bed's pressure
    drop over W/A and its fluctuation, the bed height and expansion, the largest cell gas speed over the inlet
    velocity over the same window (a channel's mark: 3.1-3.5 in AR-1's beds at 1.6-2.9 Umf, 5.5-5.8 in AR-4 MP's
    at 1.6, 8 there from 8 s on, where corner and wall channels of void fraction 0.9-1 carry the gas up the bed),
    over the same window the share of its samples with the bed's top at the outlet (``_at_roof``) and, at its last
    snapshot, the share of its particles pinned there (``_roof_share``), the share of the rising gas in the corner
    and wall columns of the lower bed and the rods' mean |a_z| inside and in the corners (``channel_record``),
    the mixing entropy at the end and the one its bed would
    have with its colours shuffled at random (the grid's ceiling; runs that ended from 2026-12-04 on), the
    void fractions' binarity and the largest overlap's median, 99th percentile and maximum (``_overlaps``)."""
    record = void_fraction_record(folder) if not row_failed(r) else None
    case = folder_case(folder)
    gas, roof = (None, None) if case is None else (case.gas, case.domain.upper[2])
    passes, ramp = _inlet_passes_umf(gas), None if gas is None else gas.inlet_ramp
    fastest = _window_mean(series, "gas_max_speed", ramp)
    t95 = r.get("t95")
    # the colour-by-layer record (snapshots read unless archived), once: for the dense bed of an ended run and
    # the share pinned at the outlet of one whose top reached it
    layers = colour_layer_record(folder) if row_ended(r) or _reaches_roof(series, roof) else None
    return {"t95": t95, "inlet_passes_umf": passes, "column_height": roof, "cpu_seconds": data.get("cpu_seconds"),
            "t95_from_inlet_at_umf": None if t95 is None or passes is None else t95 - passes,
            "pressure_drop_over_weight": data.get("pressure_drop_over_weight"),
            "pressure_drop_std_over_weight": (data["bed_pressure_drop_std_second_half"] / data["bed_weight_per_area"]
                                              if "bed_pressure_drop_std_second_half" in data
                                              else data.get("pressure_drop_std_over_weight")),
            "bed_height": _bed_surface(series, ramp), "bed_expansion": _bed_expansion(series, ramp),
            "dense_bed_expansion": _dense_bed_expansion(layers, ramp) if row_ended(r) else None,
            "bed_at_roof": _at_roof(series, roof, ramp), "roof_share": _roof_share(series, roof, layers),
            "gas_max_speed_over_inlet": (None if fastest is None or gas is None or not gas.inlet_velocity
                                         else fastest / gas.inlet_velocity),
            **(_channel_means(folder, ramp) if not row_failed(r) else {}),
            "final_mixing_entropy": (float(series["mixing_entropy"][-1])
                                     if series is not None and "mixing_entropy" in series else None),
            "mixing_entropy_random": data.get("mixing_entropy_random"),
            "void_fraction_binarity": None if record is None else record["binarity"], **_overlaps(series),
            **entropy_columns(series, t95 is not None)}


def _overlaps(series) -> dict:
    """The contacts' depth over the whole run, from the largest overlap in the bed at each sample (fraction of
    a diameter): its median, 99th percentile and largest (``overlap_median``, ``overlap_p99``, ``overlap_max``;
    None without the column). The spring's softness at a glance: the defaults were chosen on 5.4 % (AR-1) and
    7.2 % (AR-4) in 2,000-particle beds (docs/speed-accuracy.md); single samples far above them are impacts."""
    import numpy as np
    keys = ("overlap_median", "overlap_p99", "overlap_max")
    if series is None or "max_overlap_over_diameter" not in series:
        return dict.fromkeys(keys)
    values = np.asarray(series["max_overlap_over_diameter"], float)
    return dict(zip(keys, (float(np.median(values)), float(np.percentile(values, 99)), float(values.max()))))


CHANNELS = "channels.json"  # an archived run's channel record (``channel_record``)
CHANNEL_LAYERS = (0.05, 0.2)  # m: the lower bed, where AR-4 MP's corner channels were found (2026-12-03)


def channel_record(folder, window: tuple | None = None) -> dict | None:
    """Per gas snapshot of a run (those at times in ``window`` [s], all without one): the share of the rising
    gas in the corner, wall and inside columns over ``CHANNEL_LAYERS`` and, for rods, their mean |a_z| there by
    the same classes (``fvdem.analysis.channels``). From the snapshots, else from an archived ``channels.json``;
    None without either. ``{"z_range", "cells", "rows": [{"time", "gas_corner", ..., "alignment_inside"}]}``."""
    import meshio
    import numpy as np

    from ...analysis.channels import gas_shares, rod_alignment
    from ...io.vtk import read_pvd
    folder = Path(folder)
    wanted = (lambda t: True) if window is None else (lambda t: window[0] - 1e-9 <= t <= window[1] + 1e-9)
    snapshots = [(t, name) for t, name in read_pvd(folder / "gas.pvd") if wanted(t)]
    if not snapshots:
        stored = folder / CHANNELS
        if not stored.exists():
            return None
        record = json.loads(stored.read_text())
        return {**record, "rows": [r for r in record["rows"] if wanted(r["time"])]}
    case = folder_case(folder)
    if case is None:
        return None
    lower, upper, cells = case.domain.lower, case.domain.upper, tuple(case.gas.cells)
    rods = case.particles.shape == "spherocylinder"
    particles = dict(read_pvd(folder / "particles.pvd")) if rods else {}
    rows = []
    for t, name in snapshots:
        grid = meshio.read(folder / name)
        centres = grid.points[grid.cells[0].data].mean(axis=1)
        if "superficial_velocity" not in grid.cell_data:  # not a gas snapshot fvdem wrote
            continue
        flux = np.asarray(grid.cell_data["superficial_velocity"][0])[:, 2]
        row = {"time": t, **{f"gas_{k}": v for k, v in
                             gas_shares(centres, flux, lower, upper, cells, CHANNEL_LAYERS).items()}}
        if t in particles and (folder / particles[t]).exists():
            state = meshio.read(folder / particles[t])
            row.update({f"alignment_{k}": v for k, v in rod_alignment(
                state.points, state.point_data["axis"], lower, upper, cells, CHANNEL_LAYERS).items()})
        rows.append(row)
    return {"z_range": list(CHANNEL_LAYERS), "cells": list(cells), "rows": rows}


def _channel_means(folder: Path, ramp: float | None) -> dict:
    """The channel record's means over the window of ``_window_mean`` (``WINDOW_START`` after the ramp, for
    ``WINDOW``): ``corner_gas_share``, ``wall_gas_share``, ``rod_alignment_inside`` and ``rod_alignment_corner``
    (None where the run has no snapshots in it, or no rods)."""
    keys = {"corner_gas_share": "gas_corner", "wall_gas_share": "gas_wall", "rod_alignment_inside": "alignment_inside",
            "rod_alignment_corner": "alignment_corner"}
    start = (ramp or 0.0) + WINDOW_START
    record = channel_record(folder, (start, start + WINDOW))
    rows = [] if record is None else record["rows"]
    means = {}
    for column, key in keys.items():
        values = [r[key] for r in rows if r.get(key) is not None]
        means[column] = float(sum(values) / len(values)) if values else None
    return means


def _archive_extra(folder: Path, target: Path) -> None:
    """What an archived run keeps of its snapshots: the void-fraction record, the channel record and the colour
    by layer (``fvdem report`` on the archived run draws ``colour_layers.png`` from it)."""
    record = void_fraction_record(folder)
    if record is not None:
        (target / VOID_FRACTION).write_text(json.dumps(record) + "\n")
    channels = channel_record(folder)
    if channels is not None:
        (target / CHANNELS).write_text(json.dumps(channels) + "\n")
    layers = colour_layer_record(folder)
    if layers is not None:
        (target / COLOUR_LAYERS).write_text(json.dumps(layers) + "\n")


def _headline(result: dict) -> str:
    return f"t95 {result['t95']:.3g} s" if result.get("t95") is not None else "t95 -"


MEMA2020 = register_report(StudyReport(
    "mema2020", "seed 000 (Mema et al., 2020): mixing and t95 figures, pressure drop, binarity, the paper's findings",
    run_values=lambda summary: {"t95": summary.get("t95")}, headline=_headline, live=_live, columns=_columns,
    figures=_figures, table_figures=_table_figures, findings=check_findings, plan=plan_points,
    archived_columns=("mixing_entropy", "lacey_index", "pressure_drop_over_weight", "bed_pressure_drop", "bed_top",
                      "rms_speed", "max_overlap_over_diameter", "gas_max_speed"),
    archived_summary=("t95", "pressure_drop_over_weight", "bed_pressure_drop_std_second_half", "bed_weight_per_area",
                      "bed_height", "mixing_cells", "mixing_entropy_random"),
    archive_extra=_archive_extra, archive_files=(VOID_FRACTION, CHANNELS, COLOUR_LAYERS), watch=("mixing_entropy",)))

# the same per-run table without the paper's figures and findings: a designed screening of a bed (its responses
# are these columns: t95, dense_bed_expansion, pressure_drop_std_over_weight, corner_gas_share, ...)
register_report(replace(
    MEMA2020, name="bed", summary="a fluidized bed's run table (t95, expansion, pressure-drop fluctuation, channels, "
    "rod alignment, overlaps) without the paper's findings: for screenings and studies of one's own bed",
    figures=None, table_figures=None, findings=None, plan=None))
