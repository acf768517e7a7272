"""A study file's ``[design]``: a two-level factorial (full or fractional) over named factors, each a pair of
case-override sets, expanded into the study's runs (``designed_runs``), with the record ``study.json`` keeps
(factors, letters, generators, defining relation, resolution, aliases, responses) for the screening report
(``fvdem.study.screening``).

    [design]
    name = "screen"                        # its runs' family and name prefix: screen_01_r1, screen_02_r1, ...
    case = "../cases/ar1.toml"             # the base run, as a family's: case, bed, set, duration, priority
    bed = "loose"
    fraction = 2                           # 2^(k-2): the standard generators; or generators = ["E = ABC", ...]
    replicas = 2                           # each design point k times, replica k from its own bed (seed + k - 1)
    centre_points = 0                      # runs with every factor at its ``centre`` (each factor needs one)
    foldover = ["packing"]                 # a second half with these factors' signs reversed ("all": every one)
    responses = ["onset_time", "kinetic_energy@3.0", "bed_expansion"]  # table columns, or series@time
    censored = ["onset_time"]              # responses a run may end without: its end time stands for them
    [design.factors.rolling]
    low = {}                               # the base run's own value
    high = {"contact.rolling_friction" = 0.0}
    [design.factors.packing]
    low = {}
    high = {bed = "dense"}                 # a level may start its runs from another of the study's beds

Factors are lettered A, B, C, ... in the file's order; the runs follow the design's standard order, every
point's first replica before any second one (a campaign cut short has the whole design once). A fold-over adds its
points after the design's own (``<name>_17``, ... for a 16-run fraction): a study extended by one keeps its runs."""
from __future__ import annotations

import re

from .checks import did_you_mean, integer_in, priority_of, problem, replicas_of, seconds_of
from .design import DesignError, fold_over, two_level

FACTOR_KEYS = {"low", "high", "centre", "doc"}
RESPONSE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*(@[0-9]+(\.[0-9]*)?)?$")  # column, or series column@time


def designed_runs(spec, settings: dict, duration, replicas: int, entry, bed_names: set, out,
                  problems: list) -> tuple[list, dict | None]:
    """The runs of a ``[design]`` table (``spec``), each as the keyword arguments of a ``sweep.RunSpec`` (its
    ``bed`` the first replica's: the study reader gives replica k its own), and the design's record for
    ``study.json``; every problem (key path, value, what is allowed) appended to ``problems``. ``entry``: the
    study reader's (a family's case and overrides)."""
    if not isinstance(spec, dict):
        problem(problems, "design", spec, "a table ([design] with case, factors, ...)")
        return [], None
    case_path, sets = entry("design", None, spec)
    name = spec.get("name", "design")
    if not isinstance(name, str) or not re.match(r"^[A-Za-z][A-Za-z0-9_]*$", name):
        problem(problems, "design.name", name, "a plain name (letters, digits, _): it names the design's runs")
        name = "design"
    base_bed = spec.get("bed")
    if base_bed is not None and (not isinstance(base_bed, str) or base_bed not in bed_names):
        problem(problems, "design.bed", base_bed, f"one of the study's beds: {', '.join(sorted(bed_names)) or 'none'}")
        base_bed = None
    run_duration = spec.get("duration", duration)
    if "duration" in spec and not seconds_of(run_duration, "design.duration", problems):
        run_duration = duration
    run_duration = float(run_duration) if isinstance(run_duration, (int, float)) else 0.0
    design_replicas = replicas_of(spec, "design.replicas", replicas, problems)
    priority = priority_of(spec, "design.priority", problems)
    centre_points = integer_in(spec, "centre_points", "design.centre_points", 0, (0, 100), 0, problems)
    factors = spec.get("factors")
    if not isinstance(factors, dict) or len(factors) < 2:
        problem(problems, "design.factors", factors, "a table of two or more factors ([design.factors.NAME] with "
                 "low = {...} and high = {...})")
        return [], None
    levels = {}
    for factor, table in factors.items():
        where = f"design.factors.{factor}"
        if not re.match(r"^[A-Za-z][A-Za-z0-9_]*$", factor):
            problem(problems, where, "...", "a plain factor name (letters, digits, _)")
            continue
        if not isinstance(table, dict) or "low" not in table or "high" not in table:
            problem(problems, where, table, "a table with low = {...} and high = {...} (case keys and values; "
                     "bed = 'NAME' to start from another of the study's beds)")
            continue
        for k in sorted(set(table) - FACTOR_KEYS):
            problem(problems, f"{where}.{k}", table[k], f"unknown key{did_you_mean(k, FACTOR_KEYS)}; allowed: "
                     + ", ".join(sorted(FACTOR_KEYS)))
        levels[factor] = {}
        for level in ("low", "high", "centre"):
            if level not in table:
                continue
            value = table[level]
            if not isinstance(value, dict):
                problem(problems, f"{where}.{level}", value, "a table of case keys and values ({} for the base run's)")
                continue
            bed = value.get("bed")
            if bed is not None and (not isinstance(bed, str) or bed not in bed_names):
                problem(problems, f"{where}.{level}.bed", bed,
                         f"one of the study's beds: {', '.join(sorted(bed_names)) or 'none'}")
                continue
            levels[factor][level] = value
        if table.get("low") == table.get("high"):
            problem(problems, where, table, "two different levels (low and high set the same)")
    if centre_points and any("centre" not in v for v in levels.values()):
        lacking = [f for f, v in levels.items() if "centre" not in v]
        problem(problems, "design.centre_points", centre_points, "centre points need every factor's centre = {...}; "
                 f"{', '.join(lacking)} have none (a factor of two settings, e.g. a model on or off, has no centre)")
        centre_points = 0
    responses = spec.get("responses", [])
    if not isinstance(responses, list) or not responses or not all(isinstance(r, str) and RESPONSE.match(r)
                                                                   for r in responses):
        problem(problems, "design.responses", responses, "a non-empty list of responses: table columns of the "
                 "study's report (e.g. 'bed_expansion') or a time-series column at a time ('kinetic_energy@3.0')")
        responses = []
    censored = spec.get("censored", [])
    if not isinstance(censored, list) or any(c not in responses for c in censored):
        problem(problems, "design.censored", censored, "a list of the design's responses that a run may end "
                 "without (its end time stands for them: a lower bound)")
        censored = []
    confidence = spec.get("confidence", 0.95)
    if not isinstance(confidence, float) or not 0.5 <= confidence < 1.0:
        problem(problems, "design.confidence", confidence, "a number in [0.5, 1), e.g. 0.95")
        confidence = 0.95
    names = list(factors)
    letters_of = {}
    try:
        fraction = spec.get("fraction")
        if fraction is not None and (not isinstance(fraction, int) or isinstance(fraction, bool) or fraction < 1):
            raise DesignError(f"fraction = {fraction!r}: an integer p >= 1 (a 2^(k-p) fraction)")
        generators = spec.get("generators", [])
        if not isinstance(generators, list):
            raise DesignError(f"generators = {generators!r}: a list of strings such as 'E = ABC'")
        letters_of = {n: letter for n, letter in zip(names, "ABCDEFGHJKLMNOPQRSTUVWXYZ")}
        design = two_level(len(names), generators, names=letters_of, fraction=fraction)
    except DesignError as exc:
        problem(problems, "design", f"{len(names)} factors", str(exc))
        return [], None
    foldover = spec.get("foldover")
    if foldover is not None:
        folded = names if foldover == "all" else foldover
        if not isinstance(folded, list) or not folded or any(f not in names for f in folded):
            problem(problems, "design.foldover", foldover, f"'all' or a list of the design's factors "
                     f"({', '.join(names)}): a second half of runs with their signs reversed")
            return [], None
        try:
            design = fold_over(design, [letters_of[f] for f in folded])
        except DesignError as exc:
            problem(problems, "design.foldover", foldover, str(exc))
            return [], None
        foldover = list(folded)
    if case_path is None or len(levels) != len(names) or any(
            not {"low", "high"} <= set(levels[f]) or centre_points and "centre" not in levels[f] for f in names):
        return [], None  # each problem is reported above
    runs = []
    points = [(f"{name}_{i + 1:02d}", dict(zip(names, map(int, row)))) for i, row in enumerate(design.matrix)]
    points += [(f"{name}_c{j + 1}", dict.fromkeys(names, 0)) for j in range(centre_points)]
    for replica in range(1, design_replicas + 1):
        for point_name, coded in points:
            overrides, bed = {**settings, **sets}, base_bed
            for factor, code in coded.items():
                level = dict(levels[factor][{-1: "low", 1: "high", 0: "centre"}[code]])
                bed = level.pop("bed", bed)
                overrides.update(level)
            overrides["time.end"] = run_duration
            if design_replicas > 1 and bed is None:
                overrides["particles.insertion.seed"] = replica
            run = f"{point_name}_r{replica}"
            runs.append(dict(name=run, family=name, case=case_path, overrides=overrides, folder=str(out / "runs" / run),
                             bed=bed, point={f"design.{f}": c for f, c in coded.items()}, duration=run_duration,
                             replica=replica, priority=priority - (replica - 1)))
    record = {"name": name, "label": design.label(), "letters": letters_of, "generators": list(design.generators),
              "defining_relation": design.defining_relation(), "resolution": design.resolution,
              "factors": {f: {"letter": letters_of[f], **{k: v for k, v in factors[f].items() if k in FACTOR_KEYS}}
                          for f in names},
              "aliases": {design.letters[j]: design.aliases(design.letters[j]) for j in range(len(names))},
              "replicas": design_replicas, "centre_points": centre_points, "responses": responses,
              "censored": censored, "confidence": confidence, **({"foldover": foldover} if foldover else {})}
    return runs, record
