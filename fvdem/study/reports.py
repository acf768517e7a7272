"""A study's results: reports registered by name, the table, figures and findings they make from the run
folders (``report``), the compact archive of a study folder (``archive``) and its results as one JSON file
(``results``).

The runner and the tasks know nothing of what a run measures; a report does. It says which values of a
run's summary ``study.json`` keeps (``run_values``), the detail of a finished run's progress line
(``headline``), what a run still in progress holds (``live``: from its time series), its table columns, its
figures and its findings (``findings.json``), and what an archive keeps beyond the generic (time-series
columns, summary keys, files). A study file names its report (``report = "..."``, ``fvdem laws report`` lists
them); ``"table"`` is the generic one and the default; published studies' reports are packages of their own
(``fvdem.reports``). Adding one: docs/ARCHITECTURE.md, "How to add a study report".
"""
from __future__ import annotations

import json
import re
import statistics
from pathlib import Path

from ..io.locks import LOCK_FILE
from ..io.run_folder import write_text_atomic
from ..provenance import processor_of
from .records import (Outcome, RunState, at_end, entry_folder, read_series, run_at_end, series_ahead,
                      simulated_so_far, state_of)
from .registry import DEFAULT_REPORT, REPORT_MODULES, REPORTS, StudyReport, register_report, report_for  # noqa: F401


# --------------------------------------------------------------------------- the report of a study folder


def _so_far(series, chosen: StudyReport) -> dict:
    """A run in progress from its time series: the simulated seconds it holds and its report's ``live``
    values."""
    times = series["time"]
    return {"simulated_time": float(times[-1]) if len(times) else 0.0,
            **(chosen.live(series) if chosen.live else {})}


def report(out) -> list:
    """The study's table (``table.csv`` / ``table.json``: per run its status, axes values, replica,
    simulated and wall seconds, and its report's columns), its report's figures and ``findings.json``,
    from its run folders (or an archive's, ``fvdem study DIR --archive DEST``). Returns the files written."""
    out = Path(out)
    result = json.loads((out / "study.json").read_text())
    chosen = report_for(result.get("report"))
    for r in result["runs"]:  # an archive's folders are relative to it
        r["folder"] = str(entry_folder(out, r))
    rows, drawn, spent, series_of = [], [], [], {}
    for r in result["runs"]:
        summary = Path(r["folder"]) / "summary.json"
        data = json.loads(summary.read_text()) if summary.exists() else {}
        cost = data  # the summary as read: what the run's CPU seconds bought (its status is derived below)
        series = read_series(Path(r["folder"]))
        if result.get("design"):
            series_of[r["name"]] = series  # the screening's responses at chosen times
        status = table_status(r, data, series)
        if series_ahead(data, series):  # a run on its way: what its time series holds (its summary is stale)
            data = _so_far(series, chosen)
            r = {**r, **(chosen.run_values(data) if chosen.run_values else {})}
        r = {**r, "status": status}
        drawable = status.state not in (RunState.FAILED, RunState.NOT_PLANNED)
        if drawable and (Path(r["folder"]) / "timeseries.csv").exists():
            drawn.append(r)  # the figures get each run with the status derived here (and its live values)
        row = {"name": r["name"], "family": r["family"], **r.get("point", {}), "status": r["status"]}
        if chosen.columns:
            row.update(chosen.columns(r, Path(r["folder"]), data, series))
        row.update({"wall_seconds": data.get("wall_seconds"), "simulated_seconds": data.get("simulated_time"),
                    "duration": r.get("duration"),
                    "replica": r.get("replica") or int((re.search(r"_r(\d+)$", r["name"]) or [0, 1])[1])})
        rows.append(row)
        if status.state is RunState.ENDED and r.get("planned") is not False:
            spent.append((r["family"], r.get("point", {}), cost))
    paths = list(chosen.figures(out, drawn)) if chosen.figures else []
    if chosen.table_figures:  # of the values the table and the findings count (the runs the study plans)
        paths += chosen.table_figures(out, [row for row in rows if row["status"] != Outcome.NOT_PLANNED])
    if result.get("design"):  # a designed study: the effects of its factors (``fvdem.study.screening``)
        from .screening import screening
        paths += screening(out, result["design"], rows, series_of)
    (out / "table.json").write_text(json.dumps(rows, indent=1) + "\n")
    columns = list(dict.fromkeys(k for row in rows for k in row))
    lines = [",".join(columns)] + [",".join("" if row.get(c) is None else str(row.get(c)) for c in columns) for row in rows]
    (out / "table.csv").write_text("\n".join(lines) + "\n")
    costs = cost_table(spent)
    (out / COSTS_FILE).write_text(json.dumps(costs, indent=1) + "\n")
    (out / COSTS_PAGE).write_text(costs_page(result.get("study"), costs))
    written = paths + [out / "table.csv", out / "table.json", out / COSTS_FILE, out / COSTS_PAGE]
    if chosen.findings:
        planned = [row for row in rows if row["status"] != Outcome.NOT_PLANNED]
        findings = chosen.findings(planned)
        (out / "findings.json").write_text(json.dumps(findings, indent=1) + "\n")
        plan = chosen.plan(planned, findings, result.get("study")) if chosen.plan else None
        if plan is not None:
            (out / PLAN_FILE).write_text(plan)
            written.append(out / PLAN_FILE)
        (out / FINDINGS_PAGE).write_text(findings_page(result.get("study"), rows, findings, paths, plan))
        written += [out / "findings.json", out / FINDINGS_PAGE]
    return written


def table_status(entry: dict, summary: dict, series) -> Outcome:
    """A run's status in the table: the word its ``study.json`` entry has on record (``Outcome``), corrected by
    what its folder holds, on the rules ``classify_run`` decides on (``at_end``, ``series_ahead``): "running"
    where its time series has passed a summary that is not a stop's (its duration raised since, and on its way
    again), "pending" where the record says ended but the summary is short of its duration (raised since: more to
    run), "finished" where the record says on its way but the summary shows its end (the index was written before
    its result); "not planned" where the study file no longer lists a run that has not ended."""
    status = Outcome(entry["status"])
    if series_ahead(summary, series):
        if summary and not summary.get("stopped_early") and not status.state.on_the_way:
            status = Outcome.RUNNING
    elif status.state is RunState.ENDED and not at_end(summary, entry.get("duration")):
        status = Outcome.PENDING
    elif status.state.on_the_way and at_end(summary, entry.get("duration")):
        status = Outcome.FINISHED
    if entry.get("planned") is False and status.state is not RunState.ENDED:
        status = Outcome.NOT_PLANNED  # out of the study file before its end: listed, neither drawn nor counted
    return status


FINDINGS_PAGE = "findings.md"  # the report's findings and figures as one page to read (``findings_page``)
COSTS_FILE = "costs.json"  # what the ended runs cost, per family, point and processor (``cost_table``)
COSTS_PAGE = "costs.md"  # the same as a page to read (``costs_page``)
PLAN_FILE = "plan.toml"  # the report's [[points]] tables that would decide its open findings (``StudyReport.plan``)
_VERDICT_ORDER = {"holds": 0, "does not hold": 1, "open": 2}
_VERDICT_PLURAL = {"holds": "hold", "does not hold": "do not hold"}  # "2 hold", "2 do not hold"; "open" stays


def findings_page(study, rows: list, findings: list, figures: list, plan: str | None = None) -> str:
    """The findings as a Markdown page: where the study stands (runs at their end, on the way, not started), a
    table of each finding's verdict, the numbers it was decided on and, where it is open, why (its ``note``
    beside them) and its rule, the runs that would decide the open ones (``plan``, the report's ``PLAN_FILE``)
    and the report's figures (linked by name: the page lies beside them)."""
    ended, started, planned = _ran(rows)
    verdicts = {}
    for f in findings:
        verdicts[f["verdict"]] = verdicts.get(f["verdict"], 0) + 1
    lines = [f"# {study or 'study'}: findings", "",
             f"{ended} of {planned} runs at their end, {started} on the way, {planned - ended - started} not "
             f"started{_unplanned(rows)}; {len(findings)} finding{'' if len(findings) == 1 else 's'}: " + ", ".join(
                 f"{n} {v if n == 1 else _VERDICT_PLURAL.get(v, v)}"
                 for v, n in sorted(verdicts.items(), key=lambda kv: _VERDICT_ORDER.get(kv[0], 3))) + ".",
             "", "| finding | verdict | numbers | rule |", "|---|---|---|---|"]
    for f in findings:
        numbers = "; ".join(part for part in (describe_values(f["values"]) if f.get("values") is not None else "",
                                              f.get("why", "")) if part)
        numbers += f" ({f['note']})" if f.get("note") else ""
        lines.append("| " + " | ".join(cell.replace("|", "/") for cell in (
            f["finding"], f["verdict"], numbers, f.get("rule", ""))) + " |")
    if plan and any(f["verdict"] == "open" for f in findings):
        lines += ["", "## What would decide the open findings", "",
                  f"[{PLAN_FILE}]({PLAN_FILE}), written beside this page: the replicas the open findings' plans ask, "
                  "as `[[points]]` tables to append to the study file.", "", "```toml", plan.rstrip("\n"), "```"]
    if figures:
        lines += ["", "## Figures", "", "Drawn beside this page by `fvdem study <this folder> --report` (an archive "
                  "keeps the data they are drawn from, not the images).", ""]
        lines += [f"![{Path(p).stem}]({Path(p).name})" for p in figures]
    return "\n".join(lines) + "\n"


def cost_table(spent: list) -> list:
    """What the ended runs cost, to size a workstation or a batch allocation: ``spent`` holds ``(family, point,
    summary)`` per ended run (its ``summary.json``); one entry per family, point (the study file's axes values) and
    processor (the summary's ``provenance.cpu``, "not recorded" before fvdem recorded it), by family in the study's
    order, then point:
    ``{"family", "point", "processor", "runs", "threads", "simulated_seconds" ([least, most] a run),
    "cpu_per_simulated_second" ({"median", "min", "max"}), "core_hours_per_run" (the mean CPU seconds over 3600),
    "wall_per_simulated_second" (the median: above the CPU's where runs shared their cores), "peak_memory_mb"
    (the largest; a study worker's peak over the runs it held)}``. Runs without ``cpu_seconds`` are left out."""
    groups = {}
    for family, point, summary in spent:
        cpu, simulated = summary.get("cpu_seconds"), summary.get("simulated_time")
        if not cpu or not simulated:
            continue
        processor = processor_of(summary)
        key = (family, json.dumps(point, sort_keys=True), processor)
        groups.setdefault(key, {"family": family, "point": point, "processor": processor, "runs": []})
        groups[key]["runs"].append(summary)
    families = list(dict.fromkeys(family for family, _, _ in spent))

    def order(group):  # the families in the study's order, each point's values ascending, then the processor
        values = [(k, (0, v, "") if isinstance(v, (int, float)) else (1, 0, str(v)))
                  for k, v in sorted(group["point"].items())]
        return families.index(group["family"]), values, group["processor"]

    table = []
    for group in sorted(groups.values(), key=order):
        runs = group.pop("runs")
        rates = sorted(float(s["cpu_seconds"]) / float(s["simulated_time"]) for s in runs)
        walls = [float(s["wall_seconds"]) / float(s["simulated_time"]) for s in runs if s.get("wall_seconds")]
        memory = [float(s["peak_memory_mb"]) for s in runs if s.get("peak_memory_mb") is not None]
        threads = sorted({s.get("threads") for s in runs if s.get("threads") is not None})
        table.append({**group, "runs": len(runs), "threads": threads[0] if len(threads) == 1 else threads or None,
                      "simulated_seconds": [min(float(s["simulated_time"]) for s in runs),
                                            max(float(s["simulated_time"]) for s in runs)],
                      "cpu_per_simulated_second": {"median": statistics.median(rates), "min": rates[0],
                                                   "max": rates[-1]},
                      "core_hours_per_run": sum(float(s["cpu_seconds"]) for s in runs) / len(runs) / 3600.0,
                      "wall_per_simulated_second": statistics.median(walls) if walls else None,
                      "peak_memory_mb": max(memory) if memory else None})
    return table


def costs_page(study, costs: list) -> str:
    """``cost_table`` as a Markdown page: one row per family, point and processor."""
    lines = [f"# {study or 'study'}: what the runs cost", "",
             f"{sum(c['runs'] for c in costs)} ended run(s) with their CPU seconds, per family, point and processor "
             "(`fvdem study <this folder> --report`, from each run's `summary.json`; `costs.json` beside this page). "
             "CPU seconds are the cost of a core of one's own; wall seconds run above them where runs shared their "
             "cores. A core-hour a run is its mean CPU seconds over 3600: to size an allocation, multiply by the "
             "runs, divided by the cores each run uses (`threads`).", "",
             "| family | point | processor | runs | threads | simulated s a run | CPU s per simulated s: median "
             "(range) | core-hours a run | wall s per simulated s | peak memory MB |", "|---" * 10 + "|"]
    for c in costs:
        rate = c["cpu_per_simulated_second"]
        span = c["simulated_seconds"]
        lines.append("| " + " | ".join(str(cell) for cell in (
            c["family"], describe_values(c["point"]) or "-", c["processor"], c["runs"],
            "-" if c["threads"] is None else describe_values(c["threads"]),
            f"{span[0]:.3g}" if span[0] == span[1] else f"{span[0]:.3g}-{span[1]:.3g}",
            f"{rate['median']:.0f}" + ("" if c["runs"] == 1 else f" ({rate['min']:.0f}-{rate['max']:.0f})"),
            f"{c['core_hours_per_run']:.2f}",
            "-" if c["wall_per_simulated_second"] is None else f"{c['wall_per_simulated_second']:.0f}",
            "-" if c["peak_memory_mb"] is None else f"{c['peak_memory_mb']:.0f}")) + " |")
    return "\n".join(lines) + "\n"


def _ran(rows: list) -> tuple[int, int, int]:
    """How many of the table's runs reached their end, how many others hold simulated time (on the way), and
    how many the study plans (all but those not planned)."""
    rows = [r for r in rows if r["status"] != Outcome.NOT_PLANNED]
    ended = [state_of(r["status"]) is RunState.ENDED for r in rows]
    return sum(ended), sum(not e and (r.get("simulated_seconds") or 0) > 0 for e, r in zip(ended, rows)), len(rows)


def _unplanned(rows: list) -> str:
    """", and N not planned (...)" where the table lists runs out of the study file that have not ended."""
    n = sum(r["status"] == Outcome.NOT_PLANNED for r in rows)
    return (f", and {n} not planned (out of the study file before their end: listed, neither counted nor drawn; "
            "fvdem study --supersede moves them to superseded/)") if n else ""


def describe_values(values) -> str:
    """A finding's ``values`` as one line: numbers to 3 significant digits, ``key: value`` pairs, nested levels
    in parentheses."""
    if isinstance(values, dict):
        return "; ".join(f"{k}: " + (f"({describe_values(v)})" if isinstance(v, dict) else describe_values(v))
                         for k, v in values.items())
    if isinstance(values, (list, tuple)):
        return ", ".join(describe_values(v) for v in values)
    if isinstance(values, float):
        return f"{values:.3g}"
    return str(values)


# --------------------------------------------------------------------------- archive (compact results)
ARCHIVED_SUMMARY = ("case", "simulated_time", "steps", "settled", "ended", "stopped_early", "threads",
                    "wall_seconds", "cpu_seconds", "timings", "provenance", "peak_memory_mb")


def archive(out, dest) -> list:
    """The compact results of a study folder's runs in ``dest`` (small enough to commit, e.g. under
    ``docs/data/``): per run its ``case.toml``, its time series thinned to ``time`` and its report's
    ``archived_columns`` (6 significant digits), its summary's ``ARCHIVED_SUMMARY`` and report keys, its
    report's extra files (``archive_extra``) and its ``run.log``; plus the study's
    ``study.json`` (folders relative to ``dest``) and ``study.toml``, and the report made from them. No
    checkpoints, states or VTU files. ``fvdem study DEST --report`` rebuilds the report and findings from
    ``dest`` alone. A run already in ``dest`` is replaced only by one that holds more simulated time, or moved
    to ``dest/superseded/`` where the study now sets other physics for it (``fvdem study --supersede``).
    Returns the files written."""
    out, dest = Path(out), Path(dest)
    index = json.loads((out / "study.json").read_text())
    chosen = report_for(index.get("report"))
    dest.mkdir(parents=True, exist_ok=True)
    kept = json.loads((dest / "study.json").read_text()) if (dest / "study.json").exists() else {"runs": []}
    runs = {r["name"]: r for r in kept["runs"]}
    written = []
    for r in index["runs"]:
        folder, target = Path(r["folder"]), dest / "runs" / r["name"]
        moved = _supersede_archived(target, r, dest, folder)  # archived under an older definition of the run
        if moved:
            runs.pop(r["name"], None)
            written.append(moved)
        series = read_series(folder)
        if series is None:  # listed without a folder (not started yet): the archive still counts every run
            runs.setdefault(r["name"], {**r, "folder": f"runs/{r['name']}", "simulated_seconds": 0.0})
            _refresh_duration(runs[r["name"]], r)
            continue
        held = simulated_so_far(target, live=True) if target.exists() else -1.0
        columns = [c for c in dict.fromkeys(("time", *chosen.archived_columns, *_design_series(index))) if c in series]
        if float(series["time"][-1]) < held or float(series["time"][-1]) == held and not _lacks(target, columns):
            # what the archive holds is as far along (a later invocation lost nothing); the study's word on
            # the run (its status, its duration) is refreshed where the folder holds as much as the archive
            if float(series["time"][-1]) == held:
                runs[r["name"]] = {**r, "folder": f"runs/{r['name']}", "simulated_seconds": held}
                if chosen.archive_extra and any(not (target / n).exists() for n in chosen.archive_files):
                    chosen.archive_extra(folder, target)  # a record the report keeps since the run was archived
            _refresh_duration(runs.setdefault(r["name"], {**r, "folder": f"runs/{r['name']}"}), r)
            continue
        target.mkdir(parents=True, exist_ok=True)
        rows = zip(*(series[c] for c in columns))
        (target / "timeseries.csv").write_text(",".join(columns) + "\n" + "".join(
            ",".join(f"{v:.6g}" for v in row) + "\n" for row in rows))
        if (folder / "summary.json").exists():
            summary = json.loads((folder / "summary.json").read_text())
            summary = {k: summary[k] for k in (*ARCHIVED_SUMMARY, *chosen.archived_summary) if k in summary}
            if summary.get("stopped_early"):
                summary.update(_so_far(series, chosen))
            (target / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
        for name in ("case.toml", "run.log"):
            if (folder / name).exists():
                (target / name).write_text((folder / name).read_text())
        if chosen.archive_extra:
            chosen.archive_extra(folder, target)
        runs[r["name"]] = {**r, "folder": f"runs/{r['name']}", "simulated_seconds": float(series["time"][-1])}
        written.append(target)
    listed = {r["name"] for r in index["runs"]}  # a run the study no longer lists and the archive holds nothing of
    runs = {n: r for n, r in runs.items() if n in listed or (dest / "runs" / n).is_dir()}  # (taken out of the file)
    write_text_atomic(dest / "study.json", json.dumps({**{k: v for k, v in index.items() if k != "runs"},
                                                      "archived_from": str(out), "runs": list(runs.values())},
                                                     indent=1) + "\n")
    if (out / "study.toml").exists():
        (dest / "study.toml").write_text((out / "study.toml").read_text())
    return written + report(dest)


def _design_series(index: dict) -> tuple:
    """The time-series columns a designed study's responses read at chosen times (``column@time``): the
    archive keeps them whatever its report keeps, so that the screening rebuilds from it."""
    responses = (index.get("design") or {}).get("responses", [])
    return tuple(r.split("@")[0] for r in responses if "@" in r)


def _supersede_archived(target: Path, entry: dict, dest: Path, folder: Path) -> Path | None:
    """Move an archived run to ``dest/superseded/`` (as ``fvdem study --supersede`` moves a run folder) where the
    study now sets other physics for it (``entry["physics"]``, written by ``write_index``; an entry without one,
    from an older ``study.json``, is taken as current) than it was archived with; its results stay, out of the
    report. ``folder``: the run's folder in the study, whose ``case.toml`` names the keys. Returns the new place."""
    from ..io.run_folder import case_text_changes, physics_fingerprint
    from ..provenance import describe, provenance
    from .folders import supersede
    from .specs import BED_STATE
    if not entry.get("physics") or not (target / "case.toml").exists():
        return None
    held = (target / "case.toml").read_text()
    if physics_fingerprint(held, BED_STATE) == entry["physics"]:
        return None
    now = Path(folder) / "case.toml"
    keys = case_text_changes(held, now.read_text(), BED_STATE) if now.exists() else "the study file changed"
    if not keys:  # the study folder's run is of the archived definition too (not superseded there yet)
        return None
    return supersede(dest, [(entry["name"], str(target), keys)], describe(provenance()))[0]


def _lacks(target: Path, columns: list) -> bool:
    """Whether an archived run's time series lacks one of ``columns`` (archived before its report kept it)."""
    try:
        with open(target / "timeseries.csv") as f:
            header = f.readline().strip().split(",")
    except OSError:
        return True
    return any(c not in header for c in columns)


def _refresh_duration(entry: dict, current: dict) -> None:
    """An archived run's duration as the study now sets it (a ``[[durations]]`` table may have raised it)."""
    if current.get("duration") is not None:
        entry["duration"] = current["duration"]


def restore(study, source, adopt: bool = False) -> list:
    """``archive``'s way back, for a study folder lost with its machine: each run that the archive ``source``
    holds at its end under the study's current case is copied into its run folder (its compact results:
    summary, time series, case, log, the report's extra files), so that the study skips it and settles no bed
    for it. Never over a run folder that exists. An archived run still in progress starts again (an archive
    has no checkpoint); the archive keeps its results until the new run passes them. Returns one
    ``(run, outcome)`` per archived run: "restored", "exists", "in progress" or "case differs: <keys>".

    ``adopt``: ``source`` is the archive of another study (an earlier stage whose runs a later one counts as they
    are): a run it holds at its end is copied where this study has a run of the same name, case and bed
    ("adopted"), on the same terms; a run in progress there is not copied (this study runs its own)."""
    import shutil

    from ..case import load_case
    from ..io.run_folder import physics_changes
    from ..provenance import describe, provenance
    source = Path(source)
    index = json.loads((source / "study.json").read_text())
    if index.get("study") != study.name and not adopt:
        raise ValueError(f"--restore {source}: an archive of study {index.get('study')!r}, not {study.name!r} "
                         "(--adopt counts another study's ended runs)")
    outcomes = []
    for run in study.runs:
        held = source / "runs" / run.name
        if not (held / "summary.json").exists():
            continue
        case = load_case(run.case, {**run.overrides, "output.progress": False})
        bed = _bed_of(held)
        changed = physics_changes(case, held, also_safe=("particles.initial_state",))
        if run.bed and bed != run.bed:  # its bed, not only its settings: the replica's own bed
            changed = "; ".join(x for x in (changed, f"its bed: {bed!r} -> {run.bed!r}") if x)
        folder = Path(run.folder)
        if folder.exists() and any(p.name != LOCK_FILE for p in folder.iterdir()):
            # the study's own folder (more than a lock file): its run resumes or is skipped
            outcomes.append((run.name, "exists"))
        elif changed:
            outcomes.append((run.name, f"case differs: {changed}"))
        elif not run_at_end(held, case):
            outcomes.append((run.name, "in progress"))
        else:
            folder.parent.mkdir(parents=True, exist_ok=True)
            shutil.copytree(held, folder, dirs_exist_ok=True)
            how = f"adopted from the archive of study {index.get('study')!r}" if adopt else "restored from the archive"
            with open(folder / "run.log", "a") as log:
                log.write(f"{how} {source.resolve()} (compact results: no checkpoint, state or snapshots; the run "
                          f"had ended) by {describe(provenance())}\n")
            outcomes.append((run.name, "adopted" if adopt else "restored"))
    return outcomes


def _bed_of(folder: Path) -> str | None:
    """The bed a run folder's run started from: the folder of its ``particles.initial_state`` (``beds/<bed>/``)."""
    import tomllib
    try:
        state = tomllib.loads((folder / "case.toml").read_text()).get("particles", {}).get("initial_state")
    except (OSError, tomllib.TOMLDecodeError):
        return None
    return Path(state).parent.name if state else None


# --------------------------------------------------------------------------- the results as one file


def results(out, dest) -> Path:
    """The study's results as one JSON file ``dest`` (e.g. under ``docs/data/``), rebuilt from the
    study folder or its archive (its report first): ``study``, ``file``, ``date``, ``code`` (the commits the
    runs ran with, short, and how many runs each), ``machine`` (hosts, their processors where recorded, threads,
    libraries of the runs),
    ``ran`` (how many runs reached their end, how many are on the way, how many have not started), ``runs``
    (the table's rows without folders), ``costs`` (``cost_table``) and ``findings`` (the report's, if it has
    them). Returns ``dest``."""
    import datetime

    out, dest = Path(out), Path(dest)
    report(out)
    index = json.loads((out / "study.json").read_text())
    rows = json.loads((out / "table.json").read_text())
    commits, hosts, libraries, commands = {}, set(), set(), []
    for r in index["runs"]:
        folder = entry_folder(out, r)
        summary = folder / "summary.json"
        made = json.loads(summary.read_text()).get("provenance", {}) if summary.exists() else {}
        commands.append(made.get("command") or "")
        if made.get("commit"):
            commits[made["commit"][:7]] = commits.get(made["commit"][:7], 0) + 1
        if made.get("host"):
            cpu = f"{made['cpu']}, " if made.get("cpu") else ""
            hosts.add(f"{made['host']} ({cpu}{made.get('threads')} thread(s) a run)")
            libraries.add(", ".join(f"{k} {made[k]}" for k in ("fvdem", "python", "numpy", "numba", "fipy") if k in made))
    ended, started, planned = _ran(rows)
    findings = json.loads((out / "findings.json").read_text()) if (out / "findings.json").exists() else None
    decided = None if findings is None else sum(f["verdict"] != "open" for f in findings)
    study = {
        "study": index.get("study"), "file": index.get("file") or _study_file(commands),
        "date": datetime.date.today().isoformat(),
        "code": {commit: f"{count} run(s)" for commit, count in commits.items()},
        "machine": {"hosts": sorted(hosts), "libraries": sorted(libraries)},
        "ran": f"{ended} of {planned} runs reached their end, {started} on the way, "
               f"{planned - ended - started} not started{_unplanned(rows)}"
               + ("" if findings is None else f"; {decided} of {len(findings)} findings decided"),
        "runs": [{k: v for k, v in row.items() if k != "folder"} for row in rows],
        "costs": json.loads((out / COSTS_FILE).read_text()),
    }
    if findings is not None:
        study["findings"] = findings
    dest.parent.mkdir(parents=True, exist_ok=True)
    dest.write_text(json.dumps(study, indent=1) + "\n")
    return dest


def _study_file(commands) -> str | None:
    """The study file named by the runs' commands (``fvdem study FILE ...``; an index written before it
    recorded its file)."""
    for command in commands:
        match = re.search(r"\bstudy\s+(\S+\.toml)", command)
        if match:
            return match[1]
    return None
