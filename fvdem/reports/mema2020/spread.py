"""Replicas and their spread, as the findings tell orders and likeness: the standard error of a difference of
two families' means and its margin (Student's t for the Welch-Satterthwaite degrees of freedom: ``critical``,
``order_margin``), an order within the spread (``within_spread``), likeness (``told_alike``, an equivalence test),
and how many replicas would tell (``replicas_to_tell``, ``to_tell``)."""
from __future__ import annotations

import math


CLOSE = 0.10  # relative differences below this need replicas to be told from chaos

SPREAD = 2.0  # with many replicas, an order is told where the means differ by more than this many standard errors
# with few, by more than Student's t at the same one-sided level (the normal distribution's at 2: 97.7 %) for the
# Welch-Satterthwaite degrees of freedom of the difference (``critical``): 4.53 with two replicas a side (df 2),
# 2.87 with three (df 4), 2.15 with ten (df 18); a replica's spread is itself a guess
TOLD = 0.977249868051821  # Phi(SPREAD)


def critical(df: float | None) -> float:
    """How many standard errors tell a difference (``SPREAD`` for ``df`` None or infinite: no spread estimated
    from the replicas, the ``CLOSE`` rule's error; else Student's t at ``TOLD`` for ``df`` degrees of freedom)."""
    if df is None or not math.isfinite(df):
        return SPREAD
    from scipy.stats import t
    return float(t.ppf(TOLD, max(df, 1.0)))


def satterthwaite(terms: list, dfs: list) -> float | None:
    """The Welch-Satterthwaite degrees of freedom of a sum of variance terms (``terms``: each ``var / n``, with its
    estimate's degrees of freedom in ``dfs``); None where every term is 0."""
    total = sum(terms)
    below = sum(t * t / d for t, d in zip(terms, dfs) if t > 0)
    return total * total / below if below > 0 else None


def degrees_of_freedom(a: list, b: list) -> float | None:
    """The degrees of freedom of ``_replica_error``'s difference (``satterthwaite``): each family's variance with
    ``n - 1``, a borrowed one (``variances``: one run, or replicas all counted at one end) with its lender's; None
    without a spread."""
    var = variances(a, b)
    if var is None:
        return None
    own = [len(v) - 1 if len(v) > 1 and sample_variance(v) > 0 else None for v in (a, b)]
    dfs = [d if d else other for d, other in zip(own, reversed(own))]
    return satterthwaite([v / len(x) for v, x in zip(var, (a, b))], dfs)


def sample_variance(values: list) -> float:
    mean = sum(values) / len(values)
    return sum((x - mean) ** 2 for x in values) / (len(values) - 1)


def standard_errors(k: float) -> str:
    """``k`` standard errors as the findings say it: "2 standard errors", "4.53 standard errors"."""
    return f"{k:.3g} standard errors"


def margin_words() -> str:
    """The rules' words for the margin (``critical``)."""
    return (f"Student's t at {100 * TOLD:.1f} % one-sided for the Welch-Satterthwaite degrees of freedom "
            f"({critical(2):.3g} with two replicas a side, {SPREAD:g} with many)")


def order_margin(a: list, b: list) -> tuple[float, float] | None:
    """The standard error of the difference of two families' means (``_replica_error``) and how many of it tell a
    difference (``critical`` for its degrees of freedom, ``degrees_of_freedom``); None without a spread."""
    error = _replica_error(a, b)
    return None if error is None else (error, critical(degrees_of_freedom(a, b)))


def within_spread(a: list, b: list) -> str | None:
    """Whether two families' replica values at one velocity (a run not mixed by its end counted at its end) lie
    within their spread, where either has replicas: the difference of the means within ``critical`` standard
    errors of it (Student's t for the difference's degrees of freedom, ``degrees_of_freedom``; 2 for many replicas),
    ``sqrt(var_a / n_a + var_b / n_b)`` with each family's sample variance (a family of one run
    takes the other's: the same chaos; so does a family whose variance is 0, its replicas all unmixed and
    counted at the same end, where the spread is unknown, not absent). More replicas shrink the error, so an
    order that exists is told in the end. Returns the means and the bound as text, or None where the difference
    is beyond it, or neither family has replicas (the ``CLOSE`` rule then). Within it the two may yet be alike
    (``told_alike``), which decides against a claimed order."""
    if max(len(a), len(b)) < 2:
        return None
    means = [sum(v) / len(v) for v in (a, b)]
    told = (f"means {means[0]:.3g} ({', '.join(f'{x:.3g}' for x in a)}) against {means[1]:.3g} "
            f"({', '.join(f'{x:.3g}' for x in b)})")
    margin = order_margin(a, b)
    if margin is None:  # no spread known on either side: the CLOSE rule
        return None if relative_gap(*means) >= CLOSE else f"{told}, within {100 * CLOSE:.0f} % and no spread known"
    error, k = margin
    if abs(means[0] - means[1]) > k * error:
        return None
    return f"{told}, within {standard_errors(k)} ({k * error:.3g})"


def told_alike(a: list, b: list, bounded: bool = False) -> str | None:
    """Whether two families' replica values at one velocity, whose order lies within their spread
    (``within_spread``), are alike: the difference of the means with ``critical`` standard errors either side
    (``_replica_error``) within ``CLOSE`` of the larger mean, the difference a single run's chaos leaves
    untold (an equivalence test, two one-sided at about 98 % each). A claimed order then does not hold there:
    a difference of ``CLOSE`` or more is ruled out. Without a spread known, None: one run each tells nothing of
    likeness. More replicas shrink the error, so two values that are alike are told alike in the end, as an order
    that exists is told: with enough replicas every comparison decides. ``bounded``: ``a`` holds runs counted at
    their end (not mixed by then), its mean a lower bound at or above ``b``'s: its true mean may lie anywhere above,
    so only one side is told, that ``b``'s mean lies at most ``CLOSE`` above it (``a`` does not lie below ``b`` by as
    much: against a claim that ``a`` is the lower, as decisive as alike). Returns the numbers as text, or None."""
    told = alike_reach(a, b, bounded)
    if told is None or told[0] >= told[1]:
        return None
    reach, margin, k = told
    means = [sum(v) / len(v) for v in (a, b)]
    within = f"within {100 * CLOSE:.0f} % of the larger ({margin:.3g})"
    if bounded:
        return (f"not below: the mean {means[0]:.3g}, a lower bound (runs not mixed by their end), against "
                f"{means[1]:.3g}, which with {standard_errors(k)} lies at most {reach:.3g} above it, {within}")
    return (f"alike: the means {means[0]:.3g} and {means[1]:.3g} differ by {abs(means[0] - means[1]):.3g}, with "
            f"{standard_errors(k)} at most {reach:.3g}, {within}")


def alike_reach(a: list, b: list, bounded: bool = False) -> tuple[float, float, float] | None:
    """The numbers ``told_alike`` decides on: how far the difference of the means reaches with ``critical``
    standard errors (``b``'s mean above ``a``'s alone where ``bounded``), the margin it must stay below (``CLOSE``
    of the larger mean) and how many standard errors that is; None without a spread (``order_margin``)."""
    spread = order_margin(a, b)
    if spread is None:
        return None
    error, k = spread
    means = [sum(v) / len(v) for v in (a, b)]
    return (means[1] - means[0] if bounded else abs(means[0] - means[1])) + k * error, CLOSE * max(means), k


def variances(a: list, b: list) -> list | None:
    """The sample variances of two families' replica values at one velocity, a family of one run, or of replicas
    all counted at one end (variance 0: its spread unknown, not absent), taking the other's (the same chaos);
    None where neither has one."""
    var = [sample_variance(v) if len(v) > 1 else None for v in (a, b)]
    var = [x if x else y for x, y in zip(var, reversed(var))]
    return var if all(var) else None


def _replica_error(a: list, b: list) -> float | None:
    """The standard error of the difference of two families' means at one velocity (``a``, ``b``: their replica
    values), ``sqrt(var_a / n_a + var_b / n_b)`` from the replicas' spread (``variances``); None without one."""
    var = variances(a, b)
    return None if var is None else (var[0] / len(a) + var[1] / len(b)) ** 0.5


def difference_error(a: list, b: list) -> float:
    """``_replica_error``, or without a spread known the error at which ``SPREAD`` errors are ``CLOSE`` of the
    larger mean (the rule for values without replicas: a difference within 10 % is noise)."""
    error = _replica_error(a, b)
    return CLOSE * max(sum(a) / len(a), sum(b) / len(b)) / SPREAD if error is None else error


MAX_PLANNED = 5000  # replicas: a difference that would take more is "more replicas would tell"


def replicas_to_tell(series, difference: float, margin: float | None, bounded: bool = False) -> list | None:
    """How many replicas each series of runs would need in all (its runs so far and the ones to add) to tell a
    difference (of two means, or of two differences' sizes) either way if the means and the spread stay as they
    are, at the least cost: the standard error ``sqrt(sum var_i / n_i)`` times ``critical`` (at the plan's
    degrees of freedom, each series' ``n_i - 1``) below ``|difference|`` (an order told) or, with a ``margin``
    (``told_alike``: None where likeness is not told), below ``margin - |difference|`` (alike), whichever is the
    larger. ``bounded``: the first mean is a lower bound at or above the second (runs not mixed by their end,
    ``told_alike(bounded=True)``), whose likeness is one-sided (the second does not lie above it by ``margin``):
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

    def short(counts):  # the margin (``critical`` at the plan's degrees of freedom) times the error above ``need``
        terms = [var / n for (_, var, _), n in zip(series, counts)]
        k = critical(satterthwaite(terms, [max(n - 1, 1) for n in counts]))
        return k * k * sum(terms) > need ** 2

    while short(counts):
        if sum(counts) - sum(start) >= MAX_PLANNED:
            return None
        best = max(range(len(series)), key=lambda i: series[i][1] / (counts[i] * (counts[i] + 1)) / costs[i])
        counts[best] += 1
    return None if counts == start else counts


def to_tell(plan: list | None, series=(), how: str = "[[points]]") -> str:
    """"about 17 of ar4_mp and 4 of ar1 in all would tell (now 3 and 4) ..." (``replicas_to_tell``'s ``plan``
    for ``series``: ``(name, runs so far, a replica's CPU seconds there or None)`` each), with the core-hours
    the replicas to add would take at those costs (where all are known), or "more replicas would tell"; ``how``:
    the study file's way to add them."""
    if plan is None:
        return f"more replicas would tell: {how}"
    names = [f"{n} of {name}" for n, (name, _, _) in zip(plan, series)]
    now = [str(count) for _, count, _ in series]
    hours = core_hours(plan, [count for _, count, _ in series], [cost for _, _, cost in series])
    return (f"about {_and(names)} in all would tell (now {_and(now)}), if the means and spread stay: {how}"
            + ("" if hours is None else f"; about {hours:.3g} core-hours at their runs' cost so far"))


def core_hours(plan: list, counts: list, costs: list) -> float | None:
    """The core-hours of the replicas a plan adds (``plan``: in all; ``counts``: so far; ``costs``: a replica's CPU
    seconds of each), None where a cost is unknown."""
    if any(cost is None for cost in costs):
        return None
    return sum((n - count) * cost for n, count, cost in zip(plan, counts, costs)) / 3600.0


def _and(items: list) -> str:
    """"a", "a and b", "a, b and c"."""
    return items[0] if len(items) == 1 else ", ".join(items[:-1]) + " and " + items[-1]


def relative_gap(a: float, b: float) -> float:
    """The relative difference of two positive means (infinite where both are 0: nothing to tell apart)."""
    return abs(a - b) / max(a, b) if max(a, b) > 0 else float("inf")
