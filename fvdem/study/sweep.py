"""The sweep: a study file read and checked into its beds and runs (``Study``, ``RunSpec``, ``BedSpec``),
every case checked before anything runs."""
from __future__ import annotations

import itertools
import re
from dataclasses import replace
from pathlib import Path

from ..case import CaseError, load_case, to_toml
from ..io.run_folder import physics_fingerprint
from ..scenes.stops import stop_settings
from .checks import (PRIORITY_SPAN, REPLICAS_SPAN, did_you_mean, integer_in, priority_of, problem,  # noqa: F401
                     replicas_of, seconds_of, table_of, read_toml)
from .cluster import check_cluster
from .designed import designed_runs
from .registry import DEFAULT_REPORT, REPORTS, report_for
from .specs import BED_STATE, BedSpec, RunSpec, Study


STUDY_KEYS = {"name", "description", "duration", "replicas", "settings", "beds", "families", "axes", "exclude",
              "durations", "points", "cluster", "report", "design"}
BED_KEYS = {"case", "set"}  # a [beds.NAME] table's
FAMILY_KEYS = BED_KEYS | {"bed", "duration", "replicas", "priority"}  # a [families.NAME] table's
DESIGN_KEYS = FAMILY_KEYS | {"name", "factors", "generators", "fraction", "centre_points", "responses", "censored",
                            "confidence", "foldover"}  # the [design] table's (``fvdem.study.designed``)
POINT_KEYS = ("duration", "replicas", "priority")  # what a [[points]] table sets ([[durations]]: duration)


def load_study(path, out) -> Study:
    """Read and check a study file; ``CaseError`` with every problem (key path, value, what is allowed)."""
    return study_from_table(read_toml(path), Path(path), out)


def study_from_table(table: dict, path, out) -> Study:
    """A study from its parsed file (``path``: where it is, for relative case paths and its name);
    ``CaseError`` with every problem."""
    path = Path(path)
    problems: list[str] = []
    for key in sorted(set(table) - STUDY_KEYS):
        problem(problems, key, table[key], f"unknown key{did_you_mean(key, STUDY_KEYS)}; a study has "
                 f"{', '.join(sorted(STUDY_KEYS))}")
    for key in ("name", "description"):
        if key in table and not isinstance(table[key], str):
            problem(problems, key, table[key], "a string")
    name = table.get("name", path.stem)
    report_for(None)  # the registered reports (the report packages register theirs on first use)
    report = table.get("report", DEFAULT_REPORT)
    if not isinstance(report, str) or report not in REPORTS:
        problem(problems, "report", report, f"a registered report{did_you_mean(report, REPORTS)}: "
                 f"{', '.join(sorted(REPORTS))}")
        report = DEFAULT_REPORT
    duration = table.get("duration")
    seconds_of(duration, "duration", problems)
    replicas = replicas_of(table, "replicas", 1, problems)
    settings = table_of(table, "settings", problems)
    axes = table_of(table, "axes", problems)
    for key, values in axes.items():
        if not isinstance(values, list) or not values:
            problem(problems, f"axes.{key}", values, "a non-empty list of values")
    axes = {k: v for k, v in axes.items() if isinstance(v, list) and v}  # the others are reported
    families = table_of(table, "families", problems)
    if not families and "design" not in table:
        problems.append("families: a study needs at least one family ([families.NAME] with case = ...) or a "
                        "[design]")
    beds_table = table_of(table, "beds", problems)
    out = Path(out).resolve()  # run folders and bed states are read from other folders (the cases')
    base = path.parent

    def entry(kind, key, spec):  # key None: the table is ``kind`` itself ([design])
        where = kind if key is None else f"{kind}.{key}"
        if not isinstance(spec, dict) or "case" not in spec:
            problem(problems, f"{where}", spec, "a table with case = 'path of a case file'")
            return None, {}
        if not isinstance(spec["case"], str) or not spec["case"].strip():
            problem(problems, f"{where}.case", spec["case"], "the path of a case file (a string)")
            return None, {}
        allowed = {"families": FAMILY_KEYS, "beds": BED_KEYS}.get(kind, DESIGN_KEYS)
        for k in sorted(set(spec) - allowed):
            problem(problems, f"{where}.{k}", spec[k], f"unknown key{did_you_mean(k, allowed)}; allowed: "
                     + ", ".join(sorted(allowed)))
        case_path = (base / spec["case"]).resolve()
        if not case_path.is_file():
            problem(problems, f"{where}.case", spec["case"], f"no such case file ({case_path})")
        sets = spec.get("set", {})
        if not isinstance(sets, dict):
            problem(problems, f"{where}.set", sets, "a table of case keys and values")
            sets = {}
        return str(case_path), sets

    beds = []
    for key, spec in beds_table.items():
        case_path, sets = entry("beds", key, spec)
        if case_path:
            beds.append(BedSpec(key, case_path, {**settings, **sets}, str(out / "beds" / key)))
    bed_names = {b.name for b in beds}
    replica_beds: dict[tuple, str] = {}  # (bed, replica) -> the name of that replica's own bed

    def replica_bed(bed_name, replica):
        """Replica k >= 2 of a run that starts from a bed starts from its own bed, settled like the first
        but with insertion seed (the bed's seed + k - 1): another realization of the same packing, so
        replicas differ from the first step (a replica from one settled bed would be a bit-for-bit copy)."""
        if replica == 1 or bed_name not in bed_names:
            return bed_name
        if (bed_name, replica) not in replica_beds:
            first = next(b for b in beds if b.name == bed_name)
            try:
                seed = int(load_case(first.case, dict(first.overrides)).particles.insertion.seed)
            except CaseError:
                seed = 1  # the bed's own problems are reported below
            name = f"{bed_name}_r{replica}"
            if name in bed_names:
                problem(problems, f"beds.{name}", "...", f"a bed name that replica {replica} of bed {bed_name} "
                         "needs for its own settled bed; rename it")
            overrides = {**first.overrides, "particles.insertion.seed": seed + replica - 1}
            beds.append(BedSpec(name, first.case, overrides, str(out / "beds" / name), replica))
            replica_beds[(bed_name, replica)] = name
        return replica_beds[(bed_name, replica)]

    exclusions = _exclusions(table.get("exclude", []), families, axes, problems)
    # [[durations]] (duration) and [[points]] (duration, replicas, priority): the last table that matches a run
    # decides
    chosen = (_point_tables(table.get("durations", []), "durations", ("duration",), families, axes, problems)
              + _point_tables(table.get("points", []), "points", POINT_KEYS, families, axes, problems))
    runs = []
    names = list(axes)
    for family, spec in families.items():
        case_path, sets = entry("families", family, spec)
        if not case_path:
            continue
        bed = spec.get("bed")
        if bed is not None and not isinstance(bed, str):
            problem(problems, f"families.{family}.bed", bed, "the name of one of the study's beds (a string)")
            bed = None
        family_duration = spec.get("duration", duration)
        if "duration" in spec and not seconds_of(family_duration, f"families.{family}.duration", problems):
            family_duration = duration
        if bed is not None and bed not in bed_names:
            problem(problems, f"families.{family}.bed", bed, f"one of the study's beds: {', '.join(sorted(bed_names)) or 'none'}")
        family_replicas = replicas_of(spec, f"families.{family}.replicas", replicas, problems)
        family_priority = priority_of(spec, f"families.{family}.priority", problems)
        for values in itertools.product(*(axes[k] for k in names)) if names else [()]:
            point = dict(zip(names, values))
            if any(excluded(family, point) for excluded in exclusions):
                continue
            run_duration = float(family_duration) if isinstance(family_duration, (int, float)) else 0.0
            point_replicas, point_priority = family_replicas, family_priority
            for match, values in chosen:
                if match(family, point):
                    run_duration = values.get("duration", run_duration)
                    point_replicas = values.get("replicas", point_replicas)
                    point_priority = values.get("priority", point_priority)
            for replica in range(1, point_replicas + 1):
                label = "_".join(f"{k.split('.')[-1]}{v:g}" if isinstance(v, (int, float)) else f"{k.split('.')[-1]}{v}"
                                 for k, v in point.items())
                # the first replica's name is the family's (unsuffixed where the family has one replica), so that
                # replicas added at a point later ([[points]]) leave the folders of the runs before them alone
                suffix = f"r{replica}" if family_replicas > 1 or replica > 1 else ""
                run_name = "_".join(x for x in (family, label, suffix) if x)
                overrides = {**settings, **sets, **point, "time.end": run_duration}
                if point_replicas > 1 and bed is None:  # a run that inserts its own particles
                    overrides["particles.insertion.seed"] = replica
                runs.append(RunSpec(run_name, family, case_path, overrides, str(out / "runs" / run_name),
                                    replica_bed(bed, replica) if bed is not None else None, point, run_duration,
                                    replica, report, priority=point_priority))
    design = None
    if "design" in table:
        design_runs, design = designed_runs(table["design"], settings, duration, replicas, entry, bed_names, out,
                                            problems)
        if design is not None and design["name"] in families:
            problem(problems, "design.name", design["name"], "a name no family has (it names the design's runs)")
        runs += [RunSpec(**{**spec, "report": report, "bed": replica_bed(spec["bed"], spec["replica"])
                            if spec["bed"] is not None else None}) for spec in design_runs]
    _check_names(runs, beds, problems)
    cluster = table_of(table, "cluster", problems)
    check_cluster(cluster, problems)
    # every case is checked before anything runs (a bed's final state does not exist yet: not loaded)
    checked = {}  # id(spec) -> (its physics fingerprint, its case's early-end settings)
    for spec in list(beds) + runs:
        overrides = dict(spec.overrides)
        try:
            case = load_case(spec.case, overrides)
            checked[id(spec)] = physics_fingerprint(to_toml(case), BED_STATE), stop_settings(case)
        except CaseError as exc:
            label = spec.name if SAFE_NAME.match(spec.name) else f"[{spec.name!r}]"  # refused above as well
            problems += [f"{label}: {p}" for p in exc.problems]
    if problems:
        raise CaseError(problems)
    beds = [replace(s, physics=checked[id(s)][0]) for s in beds]
    runs = [replace(s, physics=checked[id(s)][0], stops=checked[id(s)][1]) for s in runs]
    return Study(name, str(path), float(duration), tuple(beds), tuple(runs), cluster, report, design=design)


def _matches(key, wanted, value) -> bool:
    """Whether a run's ``value`` of ``key`` (its family or an axis) is ``wanted``: one value or a list of them."""
    return value in wanted if isinstance(wanted, list) else value == wanted


def _point_tables(tables, name: str, keys: tuple, families: dict, axes: dict, problems) -> list:
    """The ``[[durations]]`` or ``[[points]]`` tables (``name``) as ``(match(family, point), {key: value})``: each
    gives the runs that match all its selectors (``family`` and axis keys, each a value or a list of values)
    its values of ``keys``: ``duration`` (simulated seconds, e.g. the slower points of a study run
    longer) and, in ``[[points]]``, ``replicas`` (e.g. a third replica where two lie within their spread) and
    ``priority`` (the queue's tier of those runs while not started, higher first: a later tranche at -1). A
    key that is neither a selector nor one of ``keys``, a family or axis value the study lacks, a table that
    sets none of ``keys`` and a wrong value are problems."""
    if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        problem(problems, name, tables, f"a list of tables ([[{name}]] with {' and/or '.join(keys)} and the family "
                 "and axis values of the runs it applies to)")
        return []
    out = []
    allowed = {"family", *keys, *axes}
    for k, spec in enumerate(tables):
        where = f"{name}[{k}]"
        values, found = {}, len(problems)
        if "duration" in spec and seconds_of(spec["duration"], f"{where}.duration", problems):
            values["duration"] = float(spec["duration"])
        if "replicas" in spec and "replicas" in keys:
            values["replicas"] = replicas_of(spec, f"{where}.replicas", 1, problems)
        if "priority" in spec and "priority" in keys:
            values["priority"] = priority_of(spec, f"{where}.priority", problems)
        selectors = {key: wanted for key, wanted in spec.items() if key not in keys}
        bad = len(problems) > found or not _selectors_known(selectors, where, families, axes, allowed, problems)
        if not bad and not values:
            problem(problems, where, spec, f"sets none of {', '.join(keys)}")
            bad = True
        if not bad:
            out.append((_selecting(selectors), values))
    return out


def _selectors_known(selectors: dict, where: str, families: dict, axes: dict, allowed, problems) -> bool:
    """Whether each selector of a ``[[durations]]``, ``[[points]]`` or ``[[exclude]]`` table (``where``) is the
    family or an axis key with one of the study's values or a list of them; each one that is not is a problem
    (a misspelt key would select nothing, silently)."""
    good = True
    for key, wanted in selectors.items():
        known = list(families) if key == "family" else axes.get(key)
        if known is None:
            problem(problems, f"{where}.{key}", wanted, f"unknown key{did_you_mean(key, allowed)}; allowed: "
                     + ", ".join(sorted(allowed)))
            good = False
        elif any(w not in known for w in (wanted if isinstance(wanted, list) else [wanted])):
            problem(problems, f"{where}.{key}", wanted, "one of the study's values or a list of them: "
                     + ", ".join(map(str, known)))
            good = False
    return good


def _selecting(selectors: dict):
    """``match(family, point)``: whether a run matches every selector (each one value or a list of them)."""
    return lambda family, point: all(_matches(key, wanted, family if key == "family" else point.get(key))
                                     for key, wanted in selectors.items())


def _exclusions(tables, families: dict, axes: dict, problems) -> list:
    """The ``[[exclude]]`` tables as ``match(family, point)`` functions: a run matching every key of one is not
    run. Keys are ``family`` and the axis keys, each a value or a list of values; a key or value the study
    lacks, and a table without keys (it would drop every run), are problems."""
    if not isinstance(tables, list) or not all(isinstance(t, dict) for t in tables):
        problem(problems, "exclude", tables, "a list of tables ([[exclude]] with family and axis values)")
        return []
    out = []
    for k, spec in enumerate(tables):
        where = f"exclude[{k}]"
        if not spec:
            problem(problems, where, spec, "the family and/or axis values of the runs to leave out (an empty "
                     "table would leave out every run)")
        elif _selectors_known(spec, where, families, axes, {"family", *axes}, problems):
            out.append(_selecting(spec))
    return out


SAFE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._+-]*$")  # a run's or bed's folder name


def _check_names(runs, beds, problems) -> None:
    """Every run and bed has its own folder with a plain name: two runs whose axis values print alike
    (names show 6 significant digits: 2.0 and 2.0000001) or a name with brackets, spaces or slashes (a
    list- or string-valued axis) are refused, with the family and axis values that make them."""
    seen = {}
    for spec in beds:
        if not SAFE_NAME.match(spec.name):
            problems.append(f"beds.{spec.name}: the bed's folder name {spec.name!r} is not plain; use letters, "
                            "digits and . _ + - only")
    for run in runs:
        values = ", ".join(f"{k} = {v!r}" for k, v in run.point.items()) or "no axes"
        if not SAFE_NAME.match(run.name):
            problems.append(f"families.{run.family}: run {run.name!r} ({values}) is not a plain folder name; a "
                            "list- or string-valued axis puts brackets, spaces or slashes into it; use numbers or "
                            "plain words (letters, digits and . _ + -)")
        elif run.name in seen:
            other = seen[run.name]
            others = ", ".join(f"{k} = {v!r}" for k, v in other.point.items())
            problems.append(f"axes: runs of family {run.family} ({values}) and {other.family} ({others}) are both "
                            f"named {run.name!r}: run names show values to 6 significant digits; make them differ "
                            "there")
        else:
            seen[run.name] = run


def select_runs(study: Study, only) -> Study:
    """The study with only the runs named in ``only`` (and the beds they start from); ``CaseError``
    naming the study's runs for a name it does not have."""
    if not only:
        return study
    names = {r.name for r in study.runs}
    unknown = [n for n in only if n not in names]
    if unknown:
        raise CaseError([f"--only: {', '.join(unknown)}: not a run of study {study.name}; its runs are "
                         f"{', '.join(r.name for r in study.runs)}"])
    runs = tuple(r for r in study.runs if r.name in set(only))
    beds = tuple(b for b in study.beds if b.name in {r.bed for r in runs})
    left_out = study.left_out + tuple(r for r in study.runs if r.name not in set(only))
    return replace(study, runs=runs, beds=beds, left_out=left_out)
