"""The first set of rules of Mema et al. (2020)'s findings (§5-§6; ``check_findings``): each finding a function of
the table's rows returning ``{"finding", "verdict": "holds" | "does not hold" | "open", "values", "rule" or
"why"}``. From the t95 table: AR-4 against AR-1 up to 2 Umf and their difference shrinking at the highest
velocity, AR-1's sharp drop at 2 Umf, lift and torque, SP against MP, the terminal t95; from the bed height: AR-4
beds expand more; from the gas snapshots: AR-1's void fractions more binary. The second set, fixed later, is
``readings`` (``LATER_READINGS``)."""
from __future__ import annotations

import math
import re

from .families import (EXPANSION, T95_ONLY, TALL, among, by_velocity, counted_t95, expansion_runs, expansion_sample,
                       is_roofed, mean_t95, row_ended, row_failed, t95_by_velocity, t95_runs, tall_columns, told_rows)
from .plan import EXPANSION_KIND, T95, WHOLE, plan_record
from .spread import (CLOSE, SPREAD, critical, degrees_of_freedom, difference_error, margin_words, relative_gap,
                     replicas_to_tell, satterthwaite, standard_errors, to_tell, told_alike, variances, within_spread)
from .table import DENSE, WINDOW, WINDOW_START


def replica_cost(rows, family: str, v, column: str | None = None) -> float | None:
    """A replica's CPU seconds at a point so far: the mean ``cpu_seconds`` of the runs of ``family`` at U/Umf ``v``
    that reached their end (of those whose own family, ``column``, is ``column`` alone where given: the runs cut
    short of ``expansion_runs``; without it, of the runs that ended when they mixed alone where the point has some,
    ``t95_runs``: the replicas a t95 finding's plan adds are of those); None without one."""
    ended = [r for r in rows if r["family"] == family and r.get("gas.u_over_umf") == v and row_ended(r)
             and r.get("cpu_seconds") and (column is None or r.get("column") == column)]
    cut = [r for r in ended if r.get("cut_at_t95")]
    cpu = [r["cpu_seconds"] for r in (cut if column is None and cut else ended)]
    return sum(cpu) / len(cpu) if cpu else None


def _untold(v, a: list, b: list, gap: float, pair: str, names: tuple, alike: bool = True, how: str = "[[points]]",
            costs: tuple = (None, None), bounded: bool = False, plans: list | None = None,
            kind: str = T95) -> str | None:
    """Why the order of two families' values ``a`` and ``b`` at U/Umf ``v`` (their relative difference ``gap``)
    cannot be told: within the replicas' spread (``within_spread``; ``pair`` names the two families), with how
    many replicas of each (``names``) would tell it at the least cost (``costs``: a replica's CPU seconds of each
    there, ``replica_cost``; ``how``: the study file's way to add them) or, where ``alike`` (the values' likeness
    is told: ``told_alike``), their likeness (``replicas_to_tell``; ``bounded``: ``a``'s mean a lower bound at or
    above ``b``'s, its likeness one-sided), the plan also appended to ``plans`` as data (``plan_record``, of runs
    of ``kind``); or within ``CLOSE`` without replicas. None where it can."""
    spread = within_spread(a, b)
    if spread:
        var, means = variances(a, b), [sum(x) / len(x) for x in (a, b)]
        series = list(zip(names, (len(a), len(b)), costs))
        plan = var and replicas_to_tell([(count, s, cost) for (_, count, cost), s in zip(series, var)],
                                         means[0] - means[1], CLOSE * max(means) if alike else None, bounded)
        if plan and plans is not None:
            plans.append(plan_record(plan, [(name, v, count, cost) for name, count, cost in series], kind))
        return f"{v:g} Umf within the replicas' spread ({pair}: {spread}; {to_tell(plan, series, how)})"
    if gap < CLOSE and max(len(a), len(b)) < 2:
        return f"{v:g} Umf within {100 * CLOSE:.0f} % without replicas (too noisy to tell)"
    return None


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
        return {"finding": claim, "verdict": "open",
                "why": "no velocity where AR-1 and AR-4 MP both have gas snapshots"}
    values, close, told, plans = {}, [], {}, []
    for v in common:
        a, b = (sum(by[v][f]) / len(by[v][f]) for f in ("ar1", "ar4_mp"))
        values[f"{v:g}"] = {"ar1": a, "ar4_mp": b}
        untold = _untold(v, by[v]["ar1"], by[v]["ar4_mp"], relative_gap(a, b), "AR-1 against AR-4 MP",
                         names=("ar1", "ar4_mp"),
                         costs=tuple(replica_cost(rows, f, v) for f in ("ar1", "ar4_mp")), plans=plans, kind=WHOLE)
        alike = untold and told_alike(by[v]["ar1"], by[v]["ar4_mp"])
        if alike:  # alike within the noise: AR-1's not more binary
            told[v], values[f"{v:g}"]["alike"] = False, alike
        elif untold:
            close.append(untold)
        else:
            told[v] = a > b
    rule = ("binarity var / ((mean - packed)(1 - mean)) of the cells below 0.3 m, second half of the run; means of "
            f"the replicas apart by more than t standard errors ({margin_words()}; within {100 * CLOSE:.0f} % "
            f"without replicas: too noisy); one velocity where AR-1's is told lower, or alike (within "
            f"{100 * CLOSE:.0f} % with t standard errors), decides")
    return _at_every_velocity(claim, told, close, values, rule, plans)


def _at_every_velocity(claim: str, told: dict, untold: list, values: dict, rule: str, plans=()) -> dict:
    """The verdict of a claimed order at every velocity both families ran: ``told`` (velocity -> whether the
    order holds there, where it could be told), ``untold`` (the velocities within the noise, as text). One
    velocity where it is told not to hold decides ``does not hold``, whatever the others leave open; else any
    untold velocity leaves it open (with ``plans``, the replicas that would tell them as data, ``plan_record``);
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
    a, b = t95_by_velocity(rows, "ar1"), t95_by_velocity(rows, "ar1_paper")
    common = sorted(set(a) & set(b))
    if not common:
        return {"finding": claim, "verdict": "open",
                "why": "no velocity run both at the defaults and the paper's settings"}
    drop = {r["family"]: r.get("pressure_drop_over_weight") for r in rows
            if r["family"] in ("ar1", "ar1_paper") and r.get("gas.u_over_umf") in common}
    values = {f"{v:g}": {"defaults": a[v], "paper": b[v]} for v in common}
    values["pressure_drop_over_weight"] = drop
    if any(None in a[v] or None in b[v] for v in common):
        return {"finding": claim, "verdict": "open", "why": "not mixed by the run's end (too short)", "values": values}
    gaps = {f"{v:g}": abs(sum(a[v]) / len(a[v]) - sum(b[v]) / len(b[v])) / (sum(b[v]) / len(b[v])) for v in common}
    return {"finding": claim, "verdict": "holds" if max(gaps.values()) < SETTINGS_TOLERANCE else "does not hold",
            "values": values, "gaps": gaps, "rule": f"t95 within {100 * SETTINGS_TOLERANCE:.0f} %"}


def compare(rows, faster, slower, velocities, claim):
    """``faster`` mixes sooner than ``slower`` at every velocity of ``velocities`` both ran: the mean t95 of
    each family's replicas, a run not mixed by its end counted at its end (its t95 lies beyond: the mean is
    then a lower bound, with no upper one). At a velocity, ``faster`` is faster where its mean (known) lies
    below ``slower``'s lower bound, not faster where its lower bound reaches ``slower``'s mean; where either
    family has replicas, only beyond their spread (``within_spread``: within it the order is open), and
    without replicas a difference within ``CLOSE`` is too noisy to tell. Where neither mixed by the same end,
    the higher mixing entropy there is the faster (``_entropy_order``), told by the same rules. One velocity
    where it is not faster decides."""
    a, b = mean_t95(rows, faster), mean_t95(rows, slower)
    common = sorted(v for v in set(a) & set(b) if velocities(v))
    if not common:
        return {"finding": claim, "verdict": "open", "why": f"no velocity where both {faster} and {slower} ran"}
    values, why, faster_at, plans = {}, [], {}, []
    counted = {f: counted_t95(rows, f) for f in (faster, slower)}  # read once, not per velocity
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
            entropy = {f: by_velocity(rows, f, "final_mixing_entropy")[v] for f in pair}
            ends = {f: by_velocity(rows, f, "simulated_seconds")[v] for f in pair}
            values[f"{v:g}"] = {"mixing_entropy_at_end": entropy, "end_time": ends}
            order = _entropy_order(entropy, ends)
            if order is None:
                why.append(f"neither mixed by its end at {v:g} Umf, and their ends differ (too short)")
                continue
            faster_at[v], gap = order
            untold = _untold(v, entropy[faster], entropy[slower], gap, f"neither mixed: {faster} against {slower}, "
                             f"mixing entropy at their end, {ends[faster][0]:g} s", alike=False, names=pair,
                             costs=tuple(replica_cost(rows, f, v) for f in pair), plans=plans)
            if untold:  # never alike (``told_alike``): near its ceiling 10 % of the entropy spans nearly to fully mixed
                why.append(untold)
                del faster_at[v]
            continue
        else:  # one side's lower bound passes the other's mean only once its unmixed runs go on
            unmixed, low, other = (faster, low_a, mean_b) if mean_a is None else (slower, low_b, mean_a)
            why.append(f"{unmixed} not mixed by its end at {v:g} Umf: its mean t95 is only known to exceed "
                       f"{low:.3g} s, against {other:.3g} s (run it longer: [[durations]])")
            continue
        bounded = mean_a is None and mean_b is not None  # faster's mean a bound at or above slower's (``told_alike``)
        untold = _untold(v, counted[faster][v], counted[slower][v], gap, f"{faster} against {slower}, t95 [s]",
                         names=(faster, slower), costs=tuple(replica_cost(rows, f, v) for f in (faster, slower)),
                         bounded=bounded, plans=plans)
        # alike within the noise: not faster; where only ``faster``'s mean is a bound (at or above the other's, as
        # here), not below by 10 % is told as well; ``slower``'s bound would bound the wrong side
        alike = untold and mean_b is not None and told_alike(counted[faster][v], counted[slower][v], bounded)
        if alike:
            faster_at[v], values[f"{v:g}"]["alike"] = False, alike
        elif untold:
            why.append(untold)
            del faster_at[v]
    rule = ("mean t95 of the replicas, a run not mixed by its end counted at its end (a lower bound), apart by "
            f"more than t standard errors ({margin_words()}); differences within {100 * CLOSE:.0f} % need replicas; "
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
    return first > second, relative_gap(first, second)


def _unmixed(rows, family, v) -> str:
    """"k of n not mixed by their end (at 20 s, ...)" of a family's replicas at ``v``."""
    t95 = t95_by_velocity(rows, family)[v]
    ends = [e for t, e in zip(t95, by_velocity(rows, family, "simulated_seconds")[v]) if t is None]
    return (f"{len(ends)} of {len(t95)} not mixed by {'their' if len(ends) > 1 else 'its'} end, at "
            + ", ".join(f"{e:g}" for e in ends) + " s")


SHARP = 1.3  # t95 just below 2 Umf over t95 at 2 Umf: a fall to 1 / 1.3 (by 23 %) or more is sharp

SLIGHT = 0.2  # "only a slight effect": mean t95s within this fraction of MP's


def _slight(rows) -> dict:
    """SP against MP closures only a slight effect on AR-4 mixing (§5.3): at every velocity both ran, the mean
    t95s (``mean_t95``) within ``SLIGHT`` of MP's. Where one family has not mixed by its end, its mean is a
    lower bound: the gap is then at least ``1 - SP / MP_low`` (MP unmixed) or ``SP_low / MP - 1`` (SP unmixed),
    enough to decide where that reaches ``SLIGHT``."""
    claim = "single- against multi-particle closures: only a slight effect on AR-4 mixing"
    sp, mp = mean_t95(rows, "ar4_sp"), mean_t95(rows, "ar4_mp")
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
    t = mean_t95(rows, "ar1")
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
                    "why": f"AR-1 at {max(below):g} Umf not mixed by its end; the drop is only known to exceed "
                           f"{drop:.3g}"}
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
    ``told_alike``) decide against it there: it did not shrink. ``planned``: every run of the study,
    those not started too; while the highest velocity it runs both families at has no result for both, the
    finding waits for it (the paper's claim is at its highest velocity, 2.9 Umf)."""
    a, b = mean_t95(rows, slow), mean_t95(rows, fast)
    common = sorted(set(a) & set(b))
    high = [v for v in common if v > 2.0]
    low = [v for v in common if v <= 2.0 and not (a[v][1] and b[v][1])]
    if not high or not low:
        return {"finding": claim, "verdict": "open",
                "why": f"needs {slow} and {fast} mixed both above 2 Umf and at or below it"}
    top = max(high)
    both = set(by_velocity(planned or [], slow, "t95")) & set(by_velocity(planned or [], fast, "t95"))
    if both and max(both) > top:
        return {"finding": claim, "verdict": "open",
                "why": f"waits for the study's highest velocity, {max(both):g} Umf (both mixed up to {top:g} so far)"}
    if a[top][1] or b[top][1]:
        return {"finding": claim, "verdict": "open", "why": f"not mixed by the run's end at {top:g} Umf (too short)"}
    gap = abs(a[top][0] - b[top][0])
    counted = {f: counted_t95(rows, f) for f in (slow, fast)}
    error = {v: difference_error(counted[slow][v], counted[fast][v]) for v in (top, *low)}
    var = {v: variances(counted[slow][v], counted[fast][v]) for v in (top, *low)}  # None: no spread known
    # inf: the CLOSE rule
    dfs = {v: degrees_of_freedom(counted[slow][v], counted[fast][v]) or math.inf for v in (top, *low)}
    gaps, told, untold, plans = {}, {}, [], []
    for v in low:
        difference = a[v][0] - b[v][0]  # exact, or a lower (slow unmixed) or upper (fast unmixed) bound
        bound = difference if a[v][1] else -difference if b[v][1] else None  # a lower bound of the size, if > 0
        gaps[f"{v:g}"] = f"> {difference:.3g}" if a[v][1] else f"< {difference:.3g}" if b[v][1] else difference
        k = critical(satterthwaite([error[top] ** 2, error[v] ** 2], [dfs[top], dfs[v]]))
        noise = k * math.hypot(error[top], error[v])  # of the two sizes' difference
        # alike (``told_alike``): the sizes' difference with its noise within CLOSE of the larger t95, spreads known
        margin = CLOSE * max(a[v][0], b[v][0], a[top][0], b[top][0])
        spreads = var[top] is not None and var[v] is not None
        if bound is None and abs(abs(difference) - gap) > noise:
            told[v] = gap < abs(difference)
        elif bound is None and spreads and abs(abs(difference) - gap) + noise < margin:
            told[v] = False  # not smaller by what a single run's chaos leaves untold: it did not shrink
            gaps[f"{v:g}"] = (f"{difference:.3g}, alike in size: {abs(difference):.3g} s against {gap:.3g} s at "
                              f"{top:g} Umf, with {standard_errors(k)} ({noise:.3g} s) within "
                              f"{100 * CLOSE:.0f} % of the larger t95 ({margin:.3g} s)")
        elif bound is None:
            runs = [(f, x, len(counted[f][x]), replica_cost(rows, f, x)) for x in (v, top) for f in (slow, fast)]
            series = [(f"{f} at {x:g} Umf", count, cost) for f, x, count, cost in runs]
            spreads_of = [s for x in (v, top) for s in var[x]] if spreads else []
            plan = replicas_to_tell([(count, s, cost) for (_, count, cost), s in zip(series, spreads_of)],
                                     abs(difference) - gap, margin) if spreads else None
            if plan:
                plans.append(plan_record(plan, runs, T95))
            untold.append(f"{v:g} Umf: {slow} minus {fast} {abs(difference):.3g} s in size against {gap:.3g} s at "
                          f"{top:g} Umf, within {standard_errors(k)} of their difference ({noise:.3g} s; "
                          f"{to_tell(plan, series)})")
        elif gap < bound - noise:
            told[v] = True
        else:
            untold.append(f"{v:g} Umf: {slow} minus {fast} only bounded ({gaps[f'{v:g}']} s), not past the "
                          f"{gap:.3g} s at {top:g} Umf by {standard_errors(k)} ({noise:.3g} s; run the unmixed "
                          "longer: [[durations]])")
    values = {f"difference at {top:g} Umf": a[top][0] - b[top][0], "differences up to 2 Umf": gaps}
    rule = (f"t95 of {slow} minus {fast}: smaller in size at {top:g} Umf than at every velocity up to 2 Umf, by "
            f"more than t standard errors of the two differences ({margin_words()}; from the replicas' spread; "
            f"without replicas, {100 * CLOSE:.0f} % of the larger t95 for {SPREAD:g} errors); sizes alike (their "
            f"difference with t errors within {100 * CLOSE:.0f} % of the larger t95, spreads known) did not shrink; "
            "where a run there did not mix, its bound decides only where it exceeds that size so")
    return _at_every_velocity(claim, told, untold, values, rule, plans)


def _expansion(rows) -> dict:
    """AR-4 MP beds expand more than AR-1 beds at the same U/Umf (§5.1): the bed's expansion (its height,
    ``bed_top`` over the same window of each run that reached its end, over its settled height at the start;
    ``_bed_expansion``) larger at every velocity both ran, the runs of "<family>_expansion" families counted as
    their family's (``expansion_runs``); a run whose bed top stood at the outlet for half the window or more
    (``bed_at_roof``) is left out, and a velocity left without a measured run of either family stays open."""
    claim = "AR-4 beds expand more than AR-1 at the same U/Umf"
    rows = expansion_runs(rows)
    measured, roofed = expansion_sample(rows)
    a, b = by_velocity(measured, "ar4_mp", "bed_expansion"), by_velocity(measured, "ar1", "bed_expansion")
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
        untold = _untold(v, a[v], b[v], relative_gap(ma, mb), "AR-4 MP against AR-1",
                         how=f"[[points]] of ar4_mp{EXPANSION} and ar1{EXPANSION}, runs cut short after the window",
                         names=("ar4_mp", "ar1"),
                         costs=tuple(replica_cost(rows, f, v, f + EXPANSION) for f in ("ar4_mp", "ar1")),
                         plans=plans, kind=EXPANSION_KIND)
        alike = untold and told_alike(a[v], b[v])
        if alike:  # alike within the noise: AR-4's does not expand more
            told[v], values[f"{v:g}"]["alike"] = False, alike
        elif untold:
            why.append(untold)
        else:
            told[v] = ma > mb
    rule = (f"mean bed expansion (bed_top from {WINDOW_START:g} s after the inlet ramp for {WINDOW:g} s, over "
            f"its settled value) of AR-4 MP above AR-1's at every velocity both ran, the means apart by more than "
            f"t standard errors ({margin_words()}; within {100 * CLOSE:.0f} % without replicas: too noisy); one "
            f"velocity where AR-4 MP's is told lower, or alike (within {100 * CLOSE:.0f} % with t standard errors), "
            "decides; a bed whose top stood at the outlet for half the window or more is left out (its height is the "
            f"outlet's); the runs of a family \"<family>{EXPANSION}\" (<family>'s case from other beds, cut short "
            "after the window) count as <family>'s")
    finding = _at_every_velocity(claim, told, why, values, rule, plans)
    dense = _dense_bed_note(measured)
    return {**finding, "note": dense} if dense else finding


def _dense_bed_note(rows) -> str | None:
    """The dense beds' expansion (``dense_bed_expansion``: the height under 90 % of the particle centres) of AR-4
    MP and AR-1 at each velocity both have it, as text beside the expansion finding: not its rule's measure (the
    bed's top), but where the two differ the bed's top is set by a few particles thrown up. None where no
    velocity has both."""
    a, b = (by_velocity([r for r in rows if r.get("dense_bed_expansion") is not None], family, "dense_bed_expansion")
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
        if r["family"] in families and among((r["gas.u_over_umf"],), used) and row_ended(r) and is_roofed(r):
            roofed.setdefault((r["family"], r["gas.u_over_umf"]), []).append(r.get("roof_share"))
    if not roofed:
        return finding
    return {**finding, "note": "bed at the outlet, particles pinned at the roof: " + ", ".join(
        f"{family} at {v:g} Umf" + _shares(roofed[family, v]) for family, v in sorted(roofed))}


def _column_note(finding: dict, aside: dict, families) -> dict:
    """``finding`` with a note (after ``_roof_note``'s) naming the points of ``families``, at a velocity its
    numbers hold, whose t95 came from a taller column (``tall_columns``), with what the paper's column's runs
    set aside there measured: t95 (or their end, unmixed) and the share of their particles pinned at its
    outlet."""
    used = _velocities_in(finding.get("values"))
    points = sorted(key for key in aside if key[0] in families and among(key[1:], used))
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


LATER_READINGS: list = []  # later sets of rules, each ``(rows, whole) -> findings`` (``mema2020_readings``)


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
    (``t95_runs``), not in the bed expansion's nor the void fractions'."""
    whole = [r for r in rows if not r["family"].endswith(T95_ONLY)]  # the expansion's and the void fractions'
    table = rows  # as given: the later readings count their runs themselves
    rows = t95_runs(rows)
    planned, rows = rows, told_rows(rows)
    planned = tall_columns(planned)[0]  # a taller column's runs in place of the paper's column's at their points
    rows, aside = tall_columns(rows)

    def noted(finding, families):  # the roofed runs counted, the paper's column's runs set aside (the notes)
        return _column_note(_roof_note(finding, rows, families), aside, families)

    # each t95 finding with the families whose roofed or set-aside runs it notes
    findings = [noted(finding, families) for finding, families in (
        (compare(rows, "ar4_mp", "ar1", lambda v: v <= 2.0, "AR-4 (MP) mixes faster than AR-1 up to 2 Umf"),
         ("ar4_mp", "ar1")),
        (_gap_shrinks(rows, "ar1", "ar4_mp", "the AR-1/AR-4 difference shrinks at the highest velocity (2.9 Umf)",
                      planned), ("ar4_mp", "ar1")),
        (_sharp_drop(rows), ("ar1",)),
        (compare(rows, "ar4_mp", "ar4_mp_drag", lambda v: True, "lift and torque shorten AR-4 mixing"),
         ("ar4_mp", "ar4_mp_drag")),
        (_gap_shrinks(rows, "ar4_mp_drag", "ar4_mp", "the effect of lift and torque shrinks at the highest velocity",
                      planned), ("ar4_mp", "ar4_mp_drag")),
        (compare(rows, "ar4_mp", "ar4_sp", lambda v: v > 2.0,
                  "MP closures widen the AR-1/AR-4 difference above 2 Umf (AR-4 MP mixes faster than SP)"),
         ("ar4_mp", "ar4_sp")),
        (_slight(rows), ("ar4_mp", "ar4_sp")))]
    for family, paper in PAPER_TERMINAL_T95.items():
        t = t95_by_velocity(rows, family)
        high = sorted(v for v in t if v >= TERMINAL_FROM)
        claim = f"terminal t95 of {family} about {paper} s (paper)"
        change = f"{family}: little change of t95 above about 2.3 Umf"
        mine = []
        mixed = [v for v in high if None not in t[v]]
        means = {f"{v:g}": sum(t[v]) / len(t[v]) for v in mixed}
        # both rules are of every velocity from 2.3 Umf on: they wait for those the study plans and has no result at
        waiting = sorted(v for v in t95_by_velocity(planned, family) if v >= TERMINAL_FROM and v not in t)
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
            verdict = "holds" if abs(terminal / paper - 1) < TERMINAL else "does not hold"
            mine.append({"finding": claim, "verdict": verdict,
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
    whole = tall_columns(told_rows(whole))[0]
    findings.append(_expansion(whole))
    findings.append(_compare_binarity(whole))
    if any(r["family"] == "ar1_paper" for r in rows):  # fvdem's own check, where a study runs that family
        findings.append(_defaults_against_paper_settings(rows))
    for readings in LATER_READINGS:  # later rules, beside these (never in their place)
        findings += readings(table, [r for r in table if not r["family"].endswith(T95_ONLY)])
    return findings
