"""The runs that would decide the open findings: a finding's plan as data (``plan_record``, in ``findings.json``)
and the ``[[points]]`` tables of all the open findings' plans (``plan_points``: ``plan.toml``), each replica of
the cheapest family that counts where it is needed."""
from __future__ import annotations

from .families import (EXPANSION, T95_ONLY, TALL, expansion_runs, row_ended, row_on_the_way, series_base,
                       t95_runs, tall_columns)
from .spread import core_hours
from .table import WINDOW, WINDOW_START


# the runs a finding's plan adds (``plan_record``'s ``kind``, ``plan_points``): of the t95 findings (whole runs,
# or "<family>_t95"'s, which end when they mix), of the bed expansion (whole runs, or "<family>_expansion"'s, cut
# short after its window), of the void fractions (whole runs alone)
T95, EXPANSION_KIND, WHOLE = "t95", "expansion", "whole"


def plan_record(plan: list, runs: list, kind: str) -> dict:
    """A finding's plan as data (``findings.json``'s ``plans``, which ``plan_points`` turns into ``[[points]]``):
    ``plan`` (``replicas_to_tell``'s counts in all) for ``runs``, ``(family, U/Umf, runs so far, a replica's CPU
    seconds there or None)`` each; ``kind``: the runs that count there (``T95``, ``EXPANSION_KIND``, ``WHOLE``)."""
    hours = core_hours(plan, [count for _, _, count, _ in runs], [cost for *_, cost in runs])
    return {"kind": kind, "core_hours": hours, "runs": [
        {"family": family, "u_over_umf": v, "replicas": n, "now": count, "cpu_seconds": cost}
        for n, (family, v, count, cost) in zip(plan, runs)]}


# s: a "<family>_expansion" run's length (its [[durations]]): the 1 s inlet ramp, then the expansion's window
EXPANSION_SECONDS = 1.0 + WINDOW_START + WINDOW


def _whole_runs(rows, family: str, v) -> list:
    """The ended runs of ``family`` itself (not a series counted as it) at U/Umf ``v`` that hold their CPU seconds."""
    return [r for r in rows if r["family"] == family and r.get("gas.u_over_umf") == v and row_ended(r)
            and r.get("cpu_seconds") and r.get("simulated_seconds")]


def _priced(rows, family: str, v, kind: str, cost, runs_there: int):
    """A replica's CPU seconds for a table of ``family`` at ``v`` that a plan of ``kind`` asks (``cost``: the
    plan's own, at the runs its finding counts): the plan's where it is of runs like the table's;
    the base family's whole runs there where the table's family has none yet (stage 3, rule 3: an expansion run at
    its ``EXPANSION_SECONDS`` share of one, a t95 run at a whole run's cost, an upper bound) or where an expansion
    plan's replicas are whole runs (the study runs no expansion series there)."""
    cut_short = family.endswith(EXPANSION)
    if kind == EXPANSION_KIND and not cut_short:
        whole = _whole_runs(rows, family, v)
        return sum(r["cpu_seconds"] for r in whole) / len(whole) if whole else None
    if cost is not None or runs_there:
        return cost
    whole = _whole_runs(rows, series_base(family) or family, v)  # "<name>_tall_t95" at "<name>_tall"'s
    if not whole:
        return None
    if cut_short:
        return EXPANSION_SECONDS * sum(r["cpu_seconds"] / r["simulated_seconds"] for r in whole) / len(whole)
    return sum(r["cpu_seconds"] for r in whole) / len(whole)


def _cheaper(kind: str) -> tuple:
    """The family suffix of the cheaper runs that count for a plan of ``kind``, if any: "<family>_t95" for a t95
    finding (``T95_ONLY``), "<family>_expansion" for the bed expansion (``EXPANSION``)."""
    return {T95: (T95_ONLY,), EXPANSION_KIND: (EXPANSION,), WHOLE: ()}[kind]


def _counted_as(rows, kind: str) -> list:
    """``rows`` as a finding of ``kind`` counts them (``check_findings``' mapping): each run under the family it
    counts as, "<family>_t95" runs only in the t95 findings (``t95_runs``), "<family>_expansion" runs only in the
    bed expansion (``expansion_runs``), a taller column's runs in place of the paper column's at their point
    (``tall_columns``)."""
    if kind == T95:
        return tall_columns(t95_runs(rows))[0]
    whole = tall_columns([r for r in rows if not r["family"].endswith(T95_ONLY)])[0]
    return expansion_runs(whole) if kind == EXPANSION_KIND else whole


def _plan_family(base: str, v, kind: str, present: dict) -> str | None:
    """The study family that the replicas a plan adds to ``base`` at U/Umf ``v`` would be of: the cheapest that
    counts for ``kind`` and the study runs there (``present``: ``{(family, U/Umf): replicas}``), in the taller
    column where the study runs ``base`` in one there (``tall_columns``); None where none runs there."""
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


def plan_tables(rows, findings, addable=()) -> tuple[dict, list, list]:
    """The ``[[points]]`` tables that would add the replicas the open findings' plans ask (``findings.json``'s
    ``plans``, ``replicas_to_tell``: how many of each family in all would tell a difference if the means and
    spread stay), as data: ``{(family, U/Umf): {"from", "replicas", "cost", "why"}}`` per family and velocity, the
    most any finding asks, less the runs counted so far and those the study already has on their way
    (``_on_the_way``), added to the study's replicas there (``from``); each replica of the cheapest study family
    that counts (``_plan_family``: "<family>_t95" for a t95 finding, "<family>_expansion" for the bed expansion, in
    the taller column where the study runs one), ``cost`` a replica's CPU seconds at its point's runs so far. Also
    the findings' lines already on their way (``queued``) and the open findings without a plan (``lines``).
    ``addable``: replica series ("<family>_t95", "<family>_expansion") the study file does not hold yet that may be
    added to it, counted as present with no runs wherever their base family runs."""
    present = {}
    for r in rows:
        key = (r["family"], r.get("gas.u_over_umf"))
        present[key] = max(present.get(key, 0) + 1, r.get("replica") or 0)
    for name in addable:
        base = series_base(name)
        for family, v in list(present):
            if family == base:
                present.setdefault((name, v), 0)
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
                if add <= 0:  # enough so far (a plan adds to its other series), or on their way: listed
                    if way:
                        queued.append(said)
                    continue
                family = _plan_family(base, v, plan["kind"], present) or base
                cost = _priced(rows, family, v, plan["kind"], run["cpu_seconds"], present.get((family, v), 0))
                table = tables.setdefault((family, v), {"from": present.get((family, v), 0), "replicas": 0,
                                                        "cost": cost, "why": []})
                table["replicas"] = max(table["replicas"], table["from"] + add)
                table["why"].append(said + ("" if (family, v) in present else
                                            f"; {family} does not run at {v:g} Umf in the study: an [[exclude]] "
                                            "may drop it"))
    return tables, queued, lines


def plan_points(rows, findings, study: str | None = None) -> str:
    """The ``[[points]]`` tables of ``plan_tables`` as TOML to append to the study file (``plan.toml``). Each table
    says which findings ask it and what it costs at its point's runs so far; findings open without a plan (runs to
    lengthen, or more replicas than ``MAX_PLANNED``) are listed by name."""
    tables, queued, lines = plan_tables(rows, findings)
    hours = core_hours([t["replicas"] for t in tables.values()], [t["from"] for t in tables.values()],
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
