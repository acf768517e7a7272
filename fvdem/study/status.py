"""Where a study stands (``fvdem study OUT --status``), read from its folder alone and without writing anything:
whether a study runs there now (its folder's lock: who, where, since when), each run's state (ended, running
now, in progress from a checkpoint, not started, failed), the simulated seconds it holds against its duration
and its report's values (those it keeps of a run, and the time-series columns it watches), the CPU seconds per
simulated second
and peak memory each family has cost so far (and on which processors: where the study computes now on one its
other runs did not, its rates are scaled to it), and what is left: simulated seconds and core-hours at those
rates, at most (every run to its duration) and as expected (a run ends where the ended runs of its physics at its
point would make it end, or where a stop condition whose mark it has reached ends it: ``fvdem.scenes.stops``), the
hours that makes at the runs running now, and the runs that wait at a lower priority.
Works on a study folder while its study runs (a few file reads per run), on a stopped one and on an archive of
one (``fvdem study OUT --archive DEST``).
"""
from __future__ import annotations

import json
import statistics
import time
from pathlib import Path

from ..io.locks import describe_holder, holder
from ..io.run_folder import CHECKPOINT, FINAL_STATE
from ..provenance import UNRECORDED_CPU, processor_of
from ..scenes.stops import STOP_CONDITIONS
from .records import RunState, classify_run, entry_folder, folder_case, read_series, read_summary, simulated_so_far
from .registry import report_for


def study_status(out) -> dict:
    """The status of the study folder ``out`` (see the module): ``{"study", "folder", "running" (the lock's
    record of the study process, or None), "scheduler", "runs": [{"name", "family", "point", "replica", "priority"
    (the study file's, 0 in an older index), "state", "simulated_seconds", "duration", "left", "expected_left",
    "expected_cpu_seconds_left" (at its family's rate so far, else its kin's or the slowest family's; None before
    any), "expected_end" (a running run's, at the threads of its last summary, one without), <the report's values>,
    "cpu_per_simulated_second", "peak_memory_mb"}], "counts", "families": {family: {"cpu_per_simulated_second",
    "cpu_per_simulated_second_now" (where it differs: its rate on the processor the study computes on now,
    ``_rate_now``, which the estimates take), "rate_from" (where none is measured: the measured families of its
    physics whose rate it takes, ``_kin_families``),
    "runs_measured", "peak_memory_mb", "left_simulated_seconds", "left_core_hours", "expected_left_simulated_seconds",
    "expected_core_hours"}}, "left_simulated_seconds", "left_core_hours" (at most: every run to its duration),
    "expected_left_simulated_seconds", "expected_core_hours" (each run's ``expected_left``, ``_expect``),
    "unmeasured" (families left without a measured rate), "hours_at_running_now", "processors" (``{processor: runs}``
    of the runs the rates were measured on, ``processor_of`` their summaries: the same run costs 2-3 times more CPU
    seconds on one machine than on another), "processor_now"
    (``_processor_now``) and "processor_factor" (``_processor_factor``; None where the rates are taken as measured),
    "beds" (``_bed_status``)}``."""
    out = Path(out)
    index = json.loads((out / "study.json").read_text())
    chosen = report_for(index.get("report"))
    rows = [_run_status(out, r, chosen) for r in index["runs"]]
    runs = [row for row, _ in rows]
    families, processors = {}, {}
    for row, measured in rows:
        family = families.setdefault(row["family"], {"cpu_seconds": 0.0, "simulated": 0.0, "runs_measured": 0,
                                                     "peak_memory_mb": None, "left_simulated_seconds": 0.0,
                                                     "by_processor": {}})
        if measured is not None:
            family["cpu_seconds"] += measured[0]
            family["simulated"] += measured[1]
            family["runs_measured"] += 1
            processors[measured[2]] = processors.get(measured[2], 0) + 1
            on = family["by_processor"].setdefault(measured[2], [0.0, 0.0])
            on[0], on[1] = on[0] + measured[0], on[1] + measured[1]
        if row.get("peak_memory_mb") is not None:
            family["peak_memory_mb"] = max(family["peak_memory_mb"] or 0.0, row["peak_memory_mb"])
        family["left_simulated_seconds"] += row["left"]
    now_on, factor = _processor_now(rows), None
    if now_on is not None and len(processors) > 1 and now_on in processors:
        factor = _processor_factor(families.values(), now_on)
    rate_now = {name: _rate_now(f, now_on, factor) for name, f in families.items()}
    slowest = max((r for r in rate_now.values() if r is not None), default=None)
    kin = _kin_families(index["runs"])
    unmeasured, rates = [], {}  # rates: the CPU seconds per simulated second each family's runs are counted at
    for name, family in families.items():
        rate = family["cpu_seconds"] / family["simulated"] if family["simulated"] > 0 else None
        family["cpu_per_simulated_second"], used = rate, rate_now[name]
        if used is not None and rate is not None and abs(used - rate) > 1e-9 * rate:
            family["cpu_per_simulated_second_now"] = used
        lenders = [k for k in kin.get(name, ()) if families[k]["simulated"] > 0] if rate is None else []
        if lenders:  # a family not measured yet: the rate of those whose runs have its physics
            family["rate_from"] = lenders
            used = (sum(rate_now[k] * families[k]["simulated"] for k in lenders)
                    / sum(families[k]["simulated"] for k in lenders))
        elif rate is None:  # else the slowest family's
            used = slowest
            if family["left_simulated_seconds"] > 0:
                unmeasured.append(name)
        rates[name] = used
        family["left_core_hours"] = None if used is None else family["left_simulated_seconds"] * used / 3600.0
    for family in families.values():
        del family["cpu_seconds"], family["simulated"], family["by_processor"]
    _expect(runs, index["runs"], [entry_folder(out, r) for r in index["runs"]])
    now = time.time()
    for r in runs:  # the CPU seconds each run is expected to take yet, and a running run's end at its threads
        used = rates[r["family"]]
        r["expected_cpu_seconds_left"] = None if used is None else r["expected_left"] * used
        threads = r.pop("threads", None) or 1
        if r["state"] == RunState.RUNNING and used is not None:
            r["expected_end"] = clock(now + r["expected_cpu_seconds_left"] / threads)
    for name, family in families.items():
        family["expected_left_simulated_seconds"] = sum(r["expected_left"] for r in runs if r["family"] == name)
        used = rates[name]
        family["expected_core_hours"] = (None if used is None
                                         else family["expected_left_simulated_seconds"] * used / 3600.0)
    counts = {state.value: sum(row["state"] == state for row in runs) for state in RunState}
    left_hours = (None if any(f["left_core_hours"] is None for f in families.values())
                  else sum(f["left_core_hours"] for f in families.values()))
    expected_hours = (None if left_hours is None
                      else sum(f["expected_core_hours"] for f in families.values()))
    return {"study": index.get("study"), "folder": str(out), "running": holder(out),
            "scheduler": index.get("scheduler"), "runs": runs, "counts": counts, "families": families,
            "left_simulated_seconds": sum(row["left"] for row in runs), "left_core_hours": left_hours,
            "expected_left_simulated_seconds": sum(row["expected_left"] for row in runs),
            "expected_core_hours": expected_hours, "unmeasured": unmeasured,
            "hours_at_running_now": (left_hours / counts[RunState.RUNNING] if left_hours is not None
                                     and counts[RunState.RUNNING]
                                     else None),
            "processors": processors, "processor_now": now_on, "processor_factor": factor,
            "beds": [_bed_status(folder) for folder in sorted((out / "beds").glob("*")) if folder.is_dir()]}


# a bed's state in the status: its final state written (its runs start from it); a process settling it now; a
# checkpoint it resumes from; begun, neither
BED_STATES = ("settled", "settling", "in progress", "begun")


def _bed_status(folder: Path) -> dict:
    """A bed's folder in the study's ``beds/`` (beds the study has not begun have none yet; an archive keeps none):
    ``{"name", "state" (``BED_STATES``), "simulated_seconds", "cpu_seconds"}``. Beds settle before the runs that
    start from them: a study whose runs wait with none running is settling their beds."""
    summary = read_summary(folder) or {}
    if holder(folder) is not None:
        state = "settling"
    elif (folder / FINAL_STATE).exists() and summary and not summary.get("stopped_early"):
        state = "settled"
    else:
        state = "in progress" if (folder / CHECKPOINT).exists() else "begun"
    return {"name": folder.name, "state": state, "simulated_seconds": simulated_so_far(folder, live=True),
            "cpu_seconds": summary.get("cpu_seconds")}


def _processor_now(rows: list) -> str | None:
    """The processor the study computes on now: that of most of its running runs (their summaries, written at
    each checkpoint, name the machine of the segment that wrote them), else this process's (``cpu_model``: a
    study that runs here between runs); None where nothing names one."""
    running = [m[2] for row, m in rows if row["state"] == RunState.RUNNING and m is not None
               and m[2] != UNRECORDED_CPU]
    if running:
        return max(set(running), key=running.count)
    from ..provenance import cpu_model
    return cpu_model()


def _processor_factor(families, now_on: str) -> float | None:
    """How much faster or slower ``now_on`` runs the study than the machines its other runs ran on: the median,
    over the families with runs measured both on ``now_on`` and elsewhere, of the ratio of their CPU seconds per
    simulated second there to elsewhere (None where no family has both)."""
    ratios = []
    for family in families:
        here = family["by_processor"].get(now_on)
        there = [sum(v[k] for p, v in family["by_processor"].items() if p != now_on) for k in (0, 1)]
        if here is not None and here[1] > 0 and there[1] > 0 and there[0] > 0:
            ratios.append((here[0] / here[1]) / (there[0] / there[1]))
    return statistics.median(ratios) if ratios else None


def _rate_now(family: dict, now_on: str | None, factor: float | None) -> float | None:
    """A family's CPU seconds per simulated second on the processor the study computes on now: its runs' there
    where it has any; else its runs' elsewhere times ``factor`` (``_processor_factor``); else, with no factor,
    its runs' as measured wherever they ran. None where it has no measured run."""
    if family["simulated"] <= 0:
        return None
    here = family["by_processor"].get(now_on) if factor is not None else None
    if here is not None and here[1] > 0:
        return here[0] / here[1]
    return family["cpu_seconds"] / family["simulated"] * (factor if factor is not None else 1.0)


def _kin_families(entries: list) -> dict:
    """Each family's kin, by name: the other families with a run of the same physics as one of its runs (the index's
    ``physics``: the same case at the same point but for time and output settings, e.g. a family of runs that end
    when they mix beside the family it repeats)."""
    by_physics = {}
    for entry in entries:
        if entry.get("physics"):
            by_physics.setdefault(entry["physics"], set()).add(entry["family"])
    kin = {}
    for names in by_physics.values():
        for name in names:
            kin.setdefault(name, set()).update(names - {name})
    return {name: sorted(others) for name, others in kin.items() if others}


def _expect(runs: list, entries: list, folders: list) -> None:
    """Each run's ``expected_left``: the simulated seconds it is likely to run yet, where ``left`` is the most
    (its duration). A run ends where a stop condition its case sets ends it (``fvdem.scenes.stops``: one whose
    ``mark`` the run's values hold, e.g. a margin past a time it has reached); where it has not reached the mark,
    where the ended runs of its physics at its point (its family's replicas, and the runs of another family that
    differs in time settings alone: the index's ``physics``) would make it end on average: each one that reached
    the mark where the condition, at this run's own setting (the study file's, listed in the index), ends it, one
    that did not at its duration (one that ended without it short of this run's duration, cut short, is left out);
    without the setting it runs to its duration. An older index lists no setting: a run's case.toml tells it once it
    began; before, the run ends where its family's ended replicas at its point did. Any other run ends at its
    duration."""
    def point(r):
        return r["family"], json.dumps(r["point"], sort_keys=True)

    expecting = [c for c in STOP_CONDITIONS.values() if c.index_key and c.mark]
    ended, siblings = {}, {}
    for r, entry in zip(runs, entries):
        if r["state"] == RunState.ENDED:
            if entry.get("physics"):
                ended.setdefault(entry["physics"], []).append(r)
            siblings.setdefault(point(r), []).append(r["simulated_seconds"])
    for r, entry, folder in zip(runs, entries, folders):
        if r["state"] in (RunState.ENDED, RunState.NOT_PLANNED) or r["duration"] is None:
            r["expected_left"] = r["left"]
            continue
        duration = end = r["duration"]
        settings = _stop_settings(entry, folder, expecting)
        if settings is None:
            ends = siblings.get(point(r))
            end = min(end, sum(ends) / len(ends)) if ends else end
        for condition, setting in (settings or {}).items():
            if setting is None or setting is False:
                continue  # it runs to its duration, whether it reaches the mark or not
            own = condition.end_time(r, setting)
            # a run that ended without the mark before this one's duration (one cut short) bounds nothing
            kin = [k for k in ended.get(entry.get("physics"), ())
                   if k.get(condition.mark) is not None or k["simulated_seconds"] >= duration]
            if own is not None:
                end = min(end, own)
            elif kin:
                end = min(end, sum(duration if condition.end_time(k, setting) is None
                                   else min(duration, condition.end_time(k, setting)) for k in kin) / len(kin))
        held = 0.0 if r["state"] == RunState.PARTIAL else r["simulated_seconds"]  # a partial run starts again
        r["expected_left"] = max(0.0, end - held)


def _stop_settings(entry: dict, folder: Path, conditions: list) -> dict | None:
    """Each of ``conditions``' setting for a run: as its index entry lists it (``index_key``), else as its folder's
    case.toml sets it; None where neither tells (an older index, a run not begun)."""
    settings, case = {}, None
    for condition in conditions:
        if condition.index_key in entry:
            settings[condition] = entry[condition.index_key]
            continue
        case = case or folder_case(folder)
        if case is None:
            return None
        settings[condition] = condition.setting_of(case)
    return settings


def _expected_ends() -> str:
    """", or <how each stop condition ends a run>" for the status lines on expected ends."""
    return "".join(f", or {c.expected}" for c in STOP_CONDITIONS.values() if c.expected)


def clock(epoch: float, timespec: str = "minutes") -> str:
    """Local date and time of ``epoch`` (to the minute, or ``timespec``), ISO 8601 with its offset."""
    from datetime import datetime
    return datetime.fromtimestamp(epoch).astimezone().isoformat(timespec=timespec)


def _run_status(out: Path, r: dict, chosen) -> tuple:
    """One run's row (``study_status``), and the CPU seconds and simulated seconds its summary measured (None
    without), which the family's rate sums."""
    folder = entry_folder(out, r)
    summary = read_summary(folder) or {}
    series = read_series(folder)
    held = float(series["time"][-1]) if series is not None else float(summary.get("simulated_time") or 0.0)
    duration = r.get("duration")
    writer = holder(folder)
    state = classify_run(folder, r, summary, series)
    if state == RunState.ENDED:
        values = chosen.run_values(summary) if chosen.run_values else {}
    elif series is not None and chosen.live and chosen.run_values:
        values = chosen.run_values(chosen.live(series))
    else:
        values = {}
    watched = {c: float(series[c][-1]) for c in chosen.watch if series is not None and c in series}
    cpu, measured = summary.get("cpu_seconds"), float(summary.get("simulated_time") or 0.0)
    row = {"name": r["name"], "family": r["family"], "point": r.get("point", {}), "replica": r.get("replica"),
           "priority": r.get("priority", 0), "state": state.value, "simulated_seconds": held, "duration": duration,
           "left": (0.0 if state in (RunState.ENDED, RunState.NOT_PLANNED) or duration is None
                    else duration if state == RunState.PARTIAL else max(0.0, duration - held)),
           **values, **watched,
           "cpu_per_simulated_second": cpu / measured if cpu and measured > 0 else None,
           "peak_memory_mb": summary.get("peak_memory_mb"), "threads": summary.get("threads"),
           **({"error": r.get("error")} if state == RunState.FAILED else {}),
           **({"writer": writer} if writer else {})}
    return row, ((float(cpu), measured, processor_of(summary)) if cpu and measured > 0 else None)


def format_status(status: dict) -> str:
    """``study_status`` as a terminal table and three lines of totals."""
    chosen_columns = _value_columns(status["runs"])
    lines = [f"study {status['study']} in {status['folder']}: "
             + (f"running: {describe_holder(status['running'])}" if status["running"] is not None
                else "not running (no fvdem study holds its folder)")]
    if status.get("scheduler"):
        lines.append(f"  last scheduler: {status['scheduler']}")
    width = max([len(r["name"]) for r in status["runs"]] + [3])
    header = (f"{'run':<{width}}  {'state':<11}  {'simulated s':>13}  "
              + "".join(f"{c:>15}  " for c in chosen_columns) + f"{'CPU s/sim s':>11}  {'peak MB':>7}")
    lines += ["", header]
    for r in status["runs"]:
        done = f"{r['simulated_seconds']:.4g} / {r['duration']:g}" if r["duration"] is not None \
            else f"{r['simulated_seconds']:.4g}"
        values = "".join(f"{_cell(r.get(c)):>15}  " for c in chosen_columns)
        lines.append(f"{r['name']:<{width}}  {r['state']:<11}  {done:>13}  {values}"
                     f"{_cell(r['cpu_per_simulated_second'], '.0f'):>11}  {_cell(r['peak_memory_mb'], '.0f'):>7}")
    counts = status["counts"]
    planned = [r for r in status["runs"] if r["state"] != RunState.NOT_PLANNED]
    total = sum(r["duration"] or r["simulated_seconds"] for r in planned)
    by_family = ", ".join(f"{name} {f['left_simulated_seconds']:.4g}" for name, f in status["families"].items()
                          if f["left_simulated_seconds"] > 0)
    lines += ["", ", ".join(f"{n} {state}" for state, n in counts.items() if n and state != RunState.NOT_PLANNED)
              + f" of {len(planned)} runs; {total - status['left_simulated_seconds']:.4g} of {total:.4g} simulated s "
              f"done, {status['left_simulated_seconds']:.4g} left" + (f" ({by_family})" if by_family else "")]
    waiting = [r for r in planned if r["state"] == RunState.NOT_STARTED]
    top = max((r["priority"] for r in planned), default=0)
    later = {}
    for r in waiting:
        if r["priority"] < top:
            later.setdefault(r["priority"], []).append(r)
    for tier, runs in sorted(later.items(), reverse=True):
        lines.append(f"{len(runs)} of the runs not started wait at priority {tier} (the study file's), until every run "
                     f"of a higher priority has started: {', '.join(dict.fromkeys(r['family'] for r in runs))}")
    unplanned = counts[RunState.NOT_PLANNED]
    if unplanned:
        lines.append(f"{unplanned} run(s) not planned: the study file no longer lists them and they have not "
                     "ended; their folders are kept and not counted (fvdem study STUDY.toml --out "
                     f"{status['folder']} --supersede moves them to superseded/)")
    lines.append("CPU s per simulated s so far: " + "; ".join(
        f"{name} " + (f"{f['cpu_per_simulated_second']:.0f} ({f['runs_measured']} run(s))"
                      if f["cpu_per_simulated_second"] is not None else "not measured")
        + (f", peak {f['peak_memory_mb']:.0f} MB" if f["peak_memory_mb"] is not None else "")
        for name, f in status["families"].items()))
    processors = status.get("processors") or {}
    if processors:
        lines.append("measured on: " + "; ".join(
            (cpu if cpu != UNRECORDED_CPU else "a processor not recorded (runs made before fvdem recorded it)")
            + f" ({n} run(s))"
            for cpu, n in sorted(processors.items(), key=lambda item: -item[1])))
    if status.get("processor_factor") is not None:
        scaled = [f"{name} {f['cpu_per_simulated_second_now']:.0f}" for name, f in status["families"].items()
                  if f.get("cpu_per_simulated_second_now") is not None]
        lines.append(f"the estimates below at the rates on {status['processor_now']}, where the study computes now: "
                     f"{status['processor_factor']:.2g} times those elsewhere (the median over the families measured "
                     "both there and elsewhere; a family measured there at its own rate there)"
                     + (f": {'; '.join(scaled)}" if scaled else ""))
    if status["left_core_hours"] is not None and status["left_simulated_seconds"] > 0:
        line = f"left: at most {status['left_core_hours']:.1f} core-hours at these rates"
        if status["unmeasured"]:
            line += f" ({', '.join(status['unmeasured'])} at the slowest family's rate: none measured yet)"
        borrowed = [f"{name} at {' and '.join(f['rate_from'])}'s" for name, f in status["families"].items()
                    if f.get("rate_from") and f["left_simulated_seconds"] > 0]
        if borrowed:
            line += f" ({', '.join(borrowed)}: the same physics, none measured yet)"
        if status["hours_at_running_now"] is not None:
            line += f", {status['hours_at_running_now']:.1f} h at the {counts[RunState.RUNNING]} run(s) running now"
        line += (f"; about {status['expected_core_hours']:.1f} core-hours if each run ends where its point's ended "
                 f"runs of its physics would{_expected_ends()}")
        lines.append(line)
    elif status["left_simulated_seconds"] > 0:
        lines.append("left: no run has a measured rate yet")
    beds = status.get("beds") or []
    if beds:
        unsettled = [f"{b['name']} {b['state']} ({b['simulated_seconds']:.3g} s)" for b in beds
                     if b["state"] != "settled"]
        lines.append(f"beds: {sum(b['state'] == 'settled' for b in beds)} of {len(beds)} begun settled"
                     + (f"; {', '.join(unsettled)}" if unsettled else ""))
    ends = [f"{r['name']} about {r['expected_end'][11:16]}" for r in status["runs"] if r.get("expected_end")]
    if ends:
        lines.append("expected to end (at their family's CPU seconds per simulated s over the threads of their last "
                     f"run, where the ended runs of their physics at their point would make them end{_expected_ends()}"
                     "): " + ", ".join(ends))
    return "\n".join(lines)


def _value_columns(runs: list) -> list:
    """The report's value columns the runs have (in the first run's order)."""
    skip = {"name", "family", "point", "replica", "priority", "state", "simulated_seconds", "duration", "left",
            "expected_left", "expected_cpu_seconds_left", "expected_end", "cpu_per_simulated_second", "peak_memory_mb",
            "error", "writer"}
    return list(dict.fromkeys(k for r in runs for k in r if k not in skip))


def _cell(value, spec: str = ".3g") -> str:
    return "-" if value is None else format(value, spec) if isinstance(value, (int, float)) else str(value)
