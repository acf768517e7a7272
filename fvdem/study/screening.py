"""The screening report of a designed study (``[design]``, ``fvdem.study.designed``): each response of each run
read from the study's table and time series, each factor's main effect and the resolvable two-factor
interactions with their confidence intervals (``fvdem.study.design.analyse``), as ``screening.json``, a page
``screening.md`` and a Pareto chart of the standardized effects per response (``pareto_<response>.png``).

A response is a column of the study's table (its report's, e.g. ``bed_expansion``) or a time-series column at a
simulated time (``kinetic_energy@3.0``: interpolated; a run that has not reached the time holds none yet, one that
ended before it by its case's own stop condition, ``fvdem.scenes.stops``, holds its last value there). A
response listed as ``censored`` (a time a run may end before reaching: it holds none then) takes the run's
simulated end where the run ended without it, and says so: an effect with censored runs is a bound (the censored
runs would have taken longer). Effects are computed once every design point holds the response
in at least one run; until then the page says how many points wait."""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from .design import analyse, fold_over, two_level
from .records import RunState, state_of

SCREENING_FILE = "screening.json"
SCREENING_PAGE = "screening.md"


def response_value(response: str, row: dict, series, censored: bool):
    """``(value, censored?)`` of ``response`` for one run (its table ``row``, its time ``series`` or None); value
    None where the run does not hold it (yet)."""
    if "@" in response:
        column, at = response.split("@")
        at = float(at)
        if series is None or column not in series or not len(series["time"]):
            return None, False
        times = np.asarray(series["time"], float)
        if times[-1] < at - 1e-9 and not _ended_early(row):
            return None, False
        return float(np.interp(at, times, np.asarray(series[column], float))), False
    value = row.get(response)
    if value is not None:
        return float(value), False
    if censored and state_of(row.get("status")) is RunState.ENDED and row.get("simulated_seconds"):
        return float(row["simulated_seconds"]), True
    return None, False


def _ended_early(row: dict) -> bool:
    """Whether a run ended before its duration by its case's own stop condition (``fvdem.scenes.stops``: the state
    the condition declares final): a time-series response past its end takes its last value. A run stopped by the
    study (checkpointed) has not ended."""
    end, duration = row.get("simulated_seconds"), row.get("duration")
    return (state_of(row.get("status")) is RunState.ENDED and end is not None and duration is not None
            and end < duration - 1e-9)


def screening(out, design: dict, rows: list, series: dict) -> list:
    """Write the screening files of study folder ``out`` from its table ``rows`` (with the design's coded
    ``design.<factor>`` columns) and the runs' time ``series`` (name -> series or None). Returns the paths."""
    out = Path(out)
    names = list(design["factors"])
    letters = {f: design["factors"][f]["letter"] for f in names}
    built = two_level(len(names), design["generators"])
    if design.get("foldover"):
        built = fold_over(built, [letters[f] for f in design["foldover"]])
    factor_of = {letters[f]: f for f in names}
    runs, results = [], {}
    planned = [r for r in rows if r.get("family") == design["name"] and r.get("status") != "not planned"]
    for row in planned:
        coded = [row.get(f"design.{f}") for f in names]
        entry = {"name": row["name"], "status": row.get("status"), "coded": coded, "responses": {}, "censored": []}
        for response in design["responses"]:
            value, cut = response_value(response, row, series.get(row["name"]), response in design["censored"])
            entry["responses"][response] = value
            if cut:
                entry["censored"].append(response)
        runs.append(entry)
    points = {tuple(int(c) for c in row) for row in built.matrix}
    paths = []
    for response in design["responses"]:
        held = [r for r in runs if r["responses"][response] is not None and all(c is not None for c in r["coded"])]
        factorial = [r for r in held if any(c != 0 for c in r["coded"])]
        centre = [r["responses"][response] for r in held if all(c == 0 for c in r["coded"])]
        covered = {tuple(int(c) for c in r["coded"]) for r in factorial} & points
        result = {"runs": len(factorial), "centre_runs": len(centre), "points_covered": len(covered),
                  "points": len(points),
                  "censored_runs": [r["name"] for r in held if response in r["censored"]]}
        if len(covered) < len(points):
            result["waiting"] = f"{len(points) - len(covered)} of {len(points)} design points hold no run with it yet"
            results[response] = result
            continue
        coded = np.array([r["coded"] for r in factorial], float)
        y = np.array([r["responses"][response] for r in factorial], float)
        analysis = analyse(built, coded, y, confidence=design.get("confidence", 0.95),
                           centre=np.array(centre) if centre else None)
        cut = {r["name"] for r in factorial if response in r["censored"]}
        effects = []
        for e in analysis.effects:
            column = np.prod([coded[:, built.letters.index(x)] for x in e.term], axis=0)
            at_low = sum(1 for r, c in zip(factorial, column) if c < 0 and r["name"] in cut)
            at_high = sum(1 for r, c in zip(factorial, column) if c > 0 and r["name"] in cut)
            effects.append({"term": e.term, "factors": [factor_of[x] for x in e.term], "aliases": list(e.aliases),
                            "estimate": e.estimate, "se": e.se, "low": e.low, "high": e.high, "t": e.t,
                            "decided": e.decided(), "censored_low": at_low, "censored_high": at_high,
                            **_to_tell(e, analysis.mean, len(factorial) / len(points))})
        result.update({"mean": analysis.mean, "error": analysis.error, "error_df": analysis.error_df,
                       "sigma": analysis.sigma, "confidence": analysis.confidence, "effects": effects})
        if centre:
            result["centre_mean"] = float(np.mean(centre))
            result["curvature"] = float(np.mean(centre) - np.mean(y))  # centre mean less the factorial mean
        results[response] = result
        paths.append(pareto_chart(out / f"pareto_{_file_safe(response)}.png", response, result, letters))
    record = {"design": design, "runs": runs, "results": results}
    (out / SCREENING_FILE).write_text(json.dumps(record, indent=1) + "\n")
    (out / SCREENING_PAGE).write_text(screening_page(record, paths))
    return paths + [out / SCREENING_FILE, out / SCREENING_PAGE]


MATTERS = 0.10  # an effect of this share of the response's mean matters (docs/bed-dynamics.md's rule 2)


def _to_tell(effect, mean: float, replicas: float) -> dict:
    """Whether an untold effect lies within its interval of mattering (the interval reaches both zero and
    ``MATTERS`` of the mean: ``undecided``), and about how many replicas a point would tell it either way if the
    estimate and the spread stay (``replicas_to_tell``: the interval's half-width shrinks as 1/sqrt(replicas),
    until it clears zero or, for an effect smaller than what matters, until it falls inside +- that size)."""
    if effect.low is None or effect.decided():
        return {"undecided": False, "replicas_to_tell": None}
    size = MATTERS * abs(mean)
    undecided = effect.low <= 0 <= effect.high and (effect.high >= size or effect.low <= -size)
    half = (effect.high - effect.low) / 2
    target = abs(effect.estimate) if abs(effect.estimate) > size / 2 else size - abs(effect.estimate)
    need = None if target <= 0 or half <= 0 else math.ceil(replicas * (half / target) ** 2)
    return {"undecided": undecided, "replicas_to_tell": need if undecided else None}


def _file_safe(response: str) -> str:
    return response.replace("@", "_at_").replace(".", "p")


def _term_label(effect: dict) -> str:
    chain = [effect["term"], *[a for a in effect["aliases"] if len(a) == 2]]
    factors = " x ".join(effect["factors"])
    return f"{' + '.join(chain)} ({factors})"


def pareto_chart(path: Path, response: str, result: dict, letters: dict) -> Path:
    """The standardized effects |estimate / se| of one response, largest first, with the critical t of the
    confidence level (the effects beyond it are told from nothing); without an error term, |estimate|."""
    from scipy import stats

    from ..analysis.plots import pyplot, save_figure
    plt = pyplot()
    effects = sorted(result["effects"], key=lambda e: -abs(e["t"] if e["t"] is not None else e["estimate"]))
    standardized = all(e["t"] is not None for e in effects)
    values = [abs(e["t"]) if standardized else abs(e["estimate"]) for e in effects]
    fig, ax = plt.subplots(figsize=(7.5, 0.35 * len(effects) + 1.6))
    colours = ["tab:red" if e["decided"] else "tab:gray" for e in effects]
    ax.barh(range(len(effects)), values, color=colours)
    ax.set_yticks(range(len(effects)), [_term_label(e) for e in effects], fontsize=8)
    ax.invert_yaxis()
    if standardized and result["error_df"] > 0:
        critical = stats.t.ppf(1 - (1 - result["confidence"]) / 2, result["error_df"])
        ax.axvline(critical, color="k", ls="--", lw=1, label=f"t = {critical:.2f} ({result['error']}, "
                   f"{result['error_df']:.3g} df)")
        ax.legend(loc="lower right", fontsize=8)
    ax.set_xlabel("|effect| / standard error" if standardized else "|effect|")
    censored = len(result["censored_runs"])
    ax.set_title(f"{response}: {result['runs']} runs" + (f", {censored} censored at their end" if censored else ""),
                 fontsize=10)
    return save_figure(fig, path)


def _number(x) -> str:
    return "-" if x is None or (isinstance(x, float) and not math.isfinite(x)) else f"{x:.3g}"


def screening_page(record: dict, figures: list) -> str:
    """The screening as a Markdown page: the design, its aliases, per response a table of effects with their
    intervals (red in the chart: the interval excludes zero), and the charts."""
    d = record["design"]
    lines = [f"# {d['name']}: screening", "",
             f"{d['label']}, {d['replicas']} replica(s) a point" + (f", {d['centre_points']} centre point(s)"
                                                                   if d["centre_points"] else "") + ". Defining "
             f"relation {d['defining_relation']}" + (f" (generators {', '.join(d['generators'])})" if d["generators"]
                                                     else "") + ".", "",
             "| letter | factor | low | high | aliases (to three-factor interactions) |", "|---|---|---|---|---|"]
    for name, f in d["factors"].items():
        aliases = ", ".join(d["aliases"].get(f["letter"], [])) or "none"
        lines.append(f"| {f['letter']} | {name} | `{_level(f['low'])}` | `{_level(f['high'])}` | {aliases} |")
    ended = sum(state_of(r["status"]) is RunState.ENDED for r in record["runs"])
    lines += ["", f"{ended} of {len(record['runs'])} runs at their end. An effect is the mean at high less the "
              "mean at low; its interval is the design's confidence level (red in the chart where it excludes "
              "zero)."]
    for response, result in record["results"].items():
        lines += ["", f"## {response}", ""]
        if "waiting" in result:
            lines.append(f"Not yet: {result['waiting']}.")
            continue
        error = result["error"] + (f", {result['error_df']:.3g} df" if result["error_df"] else "")
        sigma = f"; run-to-run SD {_number(result['sigma'])}" if result.get("sigma") is not None else ""
        lines.append(f"{result['runs']} runs, mean {_number(result['mean'])}; error term: {error}{sigma}."
                     + (f" Centre points: mean {_number(result['centre_mean'])} (curvature "
                        f"{_number(result['curvature'])})." if "centre_mean" in result else ""))
        if result["censored_runs"]:
            lines.append(f"Censored: {len(result['censored_runs'])} run(s) ended without it and count at their end "
                         f"({', '.join(result['censored_runs'])}): effects with censored runs on one side are bounds.")
        lines += ["", f"| effect | factors | estimate | {int(round(100 * result['confidence']))} % interval | "
                  "t | told | censored (low/high) |", "|---|---|---|---|---|---|---|"]
        for e in sorted(result["effects"], key=lambda e: -abs(e["t"] if e["t"] is not None else e["estimate"])):
            interval = "-" if e["low"] is None else f"{_number(e['low'])} to {_number(e['high'])}"
            told = "yes" if e["decided"] else (f"within its interval of mattering: about {e['replicas_to_tell']} "
                                               "replicas a point would tell" if e.get("undecided") else "no")
            cut = f"{e['censored_low']}/{e['censored_high']}" if e["censored_low"] or e["censored_high"] else "-"
            lines.append(f"| {_term_label(e)} | {', '.join(e['factors'])} | {_number(e['estimate'])} | {interval} | "
                         f"{_number(e['t'])} | {told} | {cut} |")
    if figures:
        lines += ["", "## Charts", ""] + [f"![{Path(p).stem}]({Path(p).name})" for p in figures]
    return "\n".join(lines) + "\n"


def _level(level: dict) -> str:
    return ", ".join(f"{k} = {v}" for k, v in level.items()) or "the base run's"
