"""Studies: a sweep of runs over families of cases and axes of settings, run as tasks on Dask.

A study file (TOML) names its families (a base case and its own settings), the settled beds some of
them start from, the axes to vary, exclusions, the duration and replicas::

    name = "smoke"
    duration = 0.04                    # simulated seconds of every run (time.end)
    replicas = 1                       # repeats, each from its own bed (insertion seed + k - 1)
    [settings]                         # for every run and bed
    "output.vtk" = false
    [beds.small]                       # prepared once, before the runs that start from it
    case = "../cases/bed_ar1.toml"
    set = {"particles.count" = 300}
    [families.ar1]
    case = "../cases/ar1.toml"
    bed = "small"                      # particles.initial_state = the bed's final state
    set = {"particles.count" = 300}
    duration = 0.08                    # optional: this family's own duration
    [axes]
    "gas.u_over_umf" = [2.0, 2.9]
    [[exclude]]                        # drop the runs that match every key given
    family = "ar1"
    "gas.u_over_umf" = 2.9
    [cluster]                          # optional: where the tasks run
    kind = "local"                     # or "slurm", "pbs", "sge", "lsf" (dask-jobqueue), with its options
    workers = 2

Every run and every bed is one task on Dask distributed: a ``LocalCluster`` sized to the machine by
default, the ``--scheduler`` of a running cluster, or a dask-jobqueue cluster from ``[cluster]``. A
run's folder is ``OUT/runs/<name>``, a bed's ``OUT/beds/<name>``. A finished run (its summary
reached the duration) is skipped, an interrupted one resumed from its checkpoint (also when Dask
retries a task whose worker died), and a failed one reported with its cause without stopping the
others. Every case is checked before anything runs. Runs start longest first (most DEM steps
left), so the last to finish is not a long one begun late.

Stopping: Ctrl-C or SIGTERM to ``fvdem study``, or ``fvdem study OUT --stop`` from anywhere, writes
``OUT/STOP``; each running run then checkpoints at its next chunk and returns ``stopped``, runs not
started do not start, and the same command continues later. ``--only NAME ...`` runs some of the
runs; ``study.json`` keeps the others' last results. ``study.json`` lists every run from the start
(``pending`` until its result comes), so ``fvdem study DIR --report`` works while a study runs.
"""
from __future__ import annotations

import itertools
import json
import math
import re
import signal
import sys
import threading
import os
import time
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

from .case import CaseError, load_case

STOP_FILE = "STOP"  # in a study folder: running runs checkpoint and stop, queued ones do not start

STUDY_KEYS = {"name", "description", "duration", "replicas", "settings", "beds", "families", "axes", "exclude",
              "cluster"}
CLUSTER_KINDS = ("local", "slurm", "pbs", "sge", "lsf")


@dataclass(frozen=True)
class RunSpec:
    """One run of a study: where its case is, what it changes, and where it writes."""

    name: str
    family: str
    case: str  # path of the base case file
    overrides: dict
    folder: str
    bed: str | None = None  # name of the bed it starts from
    point: dict = field(default_factory=dict)  # the axes' values of this run
    duration: float = 0.0  # simulated seconds (the study's, or its family's own)
    replica: int = 1  # 1, 2, ...: replica k >= 2 starts from its own bed (insertion seed + k - 1)


@dataclass(frozen=True)
class BedSpec:
    name: str
    case: str
    overrides: dict
    folder: str
    replica: int = 1  # the replica whose runs start from it (``_bed_priority``)


@dataclass(frozen=True)
class Study:
    name: str
    path: str
    duration: float
    beds: tuple
    runs: tuple
    cluster: dict


def _problem(problems, key, value, allowed):
    problems.append(f"{key} = {value!r}: {allowed}")


def read_toml(path, what: str = "") -> dict:
    """A TOML file's table; ``CaseError`` naming the file (after ``what``, e.g. "--cluster ") when it
    cannot be read or parsed."""
    try:
        return tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseError([f"{what}{path}: cannot be read ({exc})"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{what}{path}: not valid TOML ({exc})"]) from None


def load_study(path, out) -> Study:
    """Read and check a study file; ``CaseError`` with every problem (key path, value, what is allowed)."""
    return study_from_table(read_toml(path), Path(path), out)


def study_from_table(table: dict, path, out) -> Study:
    """A study from its parsed file (``path``: where it is, for relative case paths and its name);
    ``CaseError`` with every problem."""
    path = Path(path)
    problems: list[str] = []
    for key in sorted(set(table) - STUDY_KEYS):
        _problem(problems, key, table[key], f"unknown key{_did_you_mean(key, STUDY_KEYS)}; a study has "
                 f"{', '.join(sorted(STUDY_KEYS))}")
    for key in ("name", "description"):
        if key in table and not isinstance(table[key], str):
            _problem(problems, key, table[key], "a string")
    name = table.get("name", path.stem)
    duration = table.get("duration")
    if not isinstance(duration, (int, float)) or isinstance(duration, bool) or not 0 < duration < 1e6:
        _problem(problems, "duration", duration, "a number of simulated seconds > 0")
    replicas = _replicas(table, "replicas", 1, problems)
    settings = _table(table, "settings", problems)
    axes = _table(table, "axes", problems)
    for key, values in axes.items():
        if not isinstance(values, list) or not values:
            _problem(problems, f"axes.{key}", values, "a non-empty list of values")
    axes = {k: v for k, v in axes.items() if isinstance(v, list) and v}  # the others are reported
    families = _table(table, "families", problems)
    if not families:
        problems.append("families: a study needs at least one family ([families.NAME] with case = ...)")
    beds_table = _table(table, "beds", problems)
    out = Path(out).resolve()  # run folders and bed states are read from other folders (the cases')
    base = path.parent

    def entry(kind, key, spec):
        if not isinstance(spec, dict) or "case" not in spec:
            _problem(problems, f"{kind}.{key}", spec, "a table with case = 'path of a case file'")
            return None, {}
        if not isinstance(spec["case"], str) or not spec["case"].strip():
            _problem(problems, f"{kind}.{key}.case", spec["case"], "the path of a case file (a string)")
            return None, {}
        allowed = {"case", "set"} | ({"bed", "duration", "replicas"} if kind == "families" else set())
        for k in sorted(set(spec) - allowed):
            _problem(problems, f"{kind}.{key}.{k}", spec[k], f"unknown key{_did_you_mean(k, allowed)}; allowed: "
                     + ", ".join(sorted(allowed)))
        case_path = (base / spec["case"]).resolve()
        if not case_path.is_file():
            _problem(problems, f"{kind}.{key}.case", spec["case"], f"no such case file ({case_path})")
        sets = spec.get("set", {})
        if not isinstance(sets, dict):
            _problem(problems, f"{kind}.{key}.set", sets, "a table of case keys and values")
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
                _problem(problems, f"beds.{name}", "...", f"a bed name that replica {replica} of bed {bed_name} "
                         "needs for its own settled bed; rename it")
            overrides = {**first.overrides, "particles.insertion.seed": seed + replica - 1}
            beds.append(BedSpec(name, first.case, overrides, str(out / "beds" / name), replica))
            replica_beds[(bed_name, replica)] = name
        return replica_beds[(bed_name, replica)]

    exclusions = table.get("exclude", [])
    if not isinstance(exclusions, list) or not all(isinstance(e, dict) for e in exclusions):
        _problem(problems, "exclude", exclusions, "a list of tables ([[exclude]] with family and axis values)")
        exclusions = []
    runs = []
    names = list(axes)
    for family, spec in families.items():
        case_path, sets = entry("families", family, spec)
        if not case_path:
            continue
        bed = spec.get("bed")
        if bed is not None and not isinstance(bed, str):
            _problem(problems, f"families.{family}.bed", bed, "the name of one of the study's beds (a string)")
            bed = None
        family_duration = spec.get("duration", duration)
        if "duration" in spec and (not isinstance(family_duration, (int, float)) or isinstance(family_duration, bool)
                                   or not 0 < family_duration < 1e6):
            _problem(problems, f"families.{family}.duration", family_duration, "a number of simulated seconds > 0")
            family_duration = duration
        if bed is not None and bed not in bed_names:
            _problem(problems, f"families.{family}.bed", bed, f"one of the study's beds: {', '.join(sorted(bed_names)) or 'none'}")
        family_replicas = _replicas(spec, f"families.{family}.replicas", replicas, problems)
        for values in itertools.product(*(axes[k] for k in names)) if names else [()]:
            point = dict(zip(names, values))
            if any(all((family if k == "family" else point.get(k)) == v for k, v in e.items()) for e in exclusions):
                continue
            for replica in range(1, family_replicas + 1):
                label = "_".join(f"{k.split('.')[-1]}{v:g}" if isinstance(v, (int, float)) else f"{k.split('.')[-1]}{v}"
                                 for k, v in point.items())
                run_name = "_".join(x for x in (family, label, f"r{replica}" if family_replicas > 1 else "") if x)
                run_duration = float(family_duration) if isinstance(family_duration, (int, float)) else 0.0
                overrides = {**settings, **sets, **point, "time.end": run_duration}
                if family_replicas > 1 and bed is None:  # a run that inserts its own particles
                    overrides["particles.insertion.seed"] = replica
                runs.append(RunSpec(run_name, family, case_path, overrides, str(out / "runs" / run_name),
                                    replica_bed(bed, replica) if bed is not None else None, point, run_duration,
                                    replica))
    _check_names(runs, beds, problems)
    cluster = _table(table, "cluster", problems)
    check_cluster(cluster, problems)
    # every case is checked before anything runs (a bed's final state does not exist yet: not loaded)
    for spec in list(beds) + runs:
        overrides = dict(spec.overrides)
        try:
            load_case(spec.case, overrides)
        except CaseError as exc:
            label = spec.name if SAFE_NAME.match(spec.name) else f"[{spec.name!r}]"  # refused above as well
            problems += [f"{label}: {p}" for p in exc.problems]
    if problems:
        raise CaseError(problems)
    return Study(name, str(path), float(duration), tuple(beds), tuple(runs), cluster)


def _replicas(table: dict, path: str, default: int, problems) -> int:
    """``table``'s ``replicas`` (``default`` when absent): an integer 1-1000, else a problem and 1."""
    value = table.get("replicas", default)
    if not isinstance(value, int) or isinstance(value, bool) or not 1 <= value <= 1000:
        _problem(problems, path, value, "an integer 1-1000")
        return 1
    return value


def _did_you_mean(key, allowed) -> str:
    import difflib
    close = difflib.get_close_matches(str(key), sorted(allowed), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


# what a [cluster] table's keys must be, where fvdem knows (dask-jobqueue checks the rest of its own)
CLUSTER_TYPES = {"workers": (int, "an integer >= 1 (jobs, or local worker processes)", lambda v: v >= 1),
                 "cores": (int, "an integer >= 1 (task slots of a job's worker)", lambda v: v >= 1),
                 "processes": (int, "an integer >= 1", lambda v: v >= 1),
                 "job_cpu": (int, "an integer >= 1 (CPUs a job books)", lambda v: v >= 1),
                 "memory": (str, "a memory size such as \"4GB\"",
                            lambda v: re.fullmatch(r"\s*\d+(\.\d+)?\s*([kKmMgGtT]i?[bB]?|[bB])\s*", v) is not None),
                 "walltime": (str, "a walltime such as \"24:00:00\" or \"1-00:00:00\"",
                              lambda v: walltime_seconds(v) is not None),
                 "queue": (str, "a queue or partition name", lambda v: bool(v.strip())),
                 "account": (str, "an account name", lambda v: bool(v.strip())),
                 "job_extra_directives": (list, "a list of strings", lambda v: all(isinstance(x, str) for x in v)),
                 "log_directory": (str, "a folder", lambda v: bool(v.strip())),
                 "stop_before_walltime": (str, "a duration such as \"5m\", \"300s\" or \"00:05:00\" (fvdem's: a run "
                                          "checkpoints and pauses this long before its job's walltime)",
                                          lambda v: _duration_seconds(v) is not None)}


def cluster_keys(kind: str) -> set:
    """The keys a ``[cluster]`` table of this kind takes: ``kind`` and ``workers``, and for a dask-jobqueue
    kind the options of its cluster and job classes."""
    if kind == "local":
        return {"kind", "workers"}
    try:
        import inspect

        import dask_jobqueue
    except ImportError:  # pragma: no cover - a dependency
        return set(CLUSTER_TYPES) | {"kind"}
    cls = getattr(dask_jobqueue, {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster",
                                  "lsf": "LSFCluster"}[kind])
    names = {"kind", "workers", "stop_before_walltime"}
    for k in (cls, *cls.__mro__, *cls.job_cls.__mro__):
        if k is not object and "__init__" in k.__dict__:
            names |= {n for n, prm in inspect.signature(k.__init__).parameters.items()
                      if n != "self" and prm.kind not in (prm.VAR_KEYWORD, prm.VAR_POSITIONAL)}
    return names - {"loop", "asynchronous", "scheduler_cls", "job_cls", "n_workers", "config_name"}


def check_cluster(cluster: dict, problems) -> None:
    """A study's ``[cluster]``: its kind, every key known for that kind (did-you-mean), the types fvdem
    knows, and ``memory`` for a batch scheduler."""
    kind = cluster.get("kind", "local")
    if not isinstance(kind, str) or kind not in CLUSTER_KINDS:
        _problem(problems, "cluster.kind", kind, f"one of {', '.join(CLUSTER_KINDS)}")
        return
    allowed = cluster_keys(kind)
    for key in sorted(set(cluster) - allowed, key=str):
        _problem(problems, f"cluster.{key}", cluster[key], f"unknown key for kind = {kind!r}"
                 f"{_did_you_mean(key, allowed)}; allowed: {', '.join(sorted(allowed))}")
    for key, (kind_of, what, ok) in CLUSTER_TYPES.items():
        if key in cluster and key in allowed:
            value = cluster[key]
            if not isinstance(value, kind_of) or isinstance(value, bool) or not ok(value):
                _problem(problems, f"cluster.{key}", value, what)
    if kind != "local" and "memory" not in cluster:
        problems.append(f"cluster.memory: missing; a {kind} job needs the memory it books, e.g. memory = \"4GB\" "
                        "(one run of the paper's bed needs about 1 GB: README, \"What a run costs\")")


def walltime_seconds(text: str) -> int | None:
    """Seconds of a batch walltime, SLURM's forms: ``minutes``, ``minutes:seconds``, ``hours:minutes:seconds``,
    ``days-hours``, ``days-hours:minutes``, ``days-hours:minutes:seconds`` (PBS, SGE and LSF's ``HH:MM:SS``
    among them); None if it is none of these."""
    match = re.fullmatch(r"\s*(?:(\d+)-)?(\d+(?::\d{2}){0,2})\s*", str(text))
    if match is None:
        return None
    days, parts = match[1], [int(x) for x in match[2].split(":")]
    if days is None:  # minutes | minutes:seconds | hours:minutes:seconds
        scale = {1: [60], 2: [60, 1], 3: [3600, 60, 1]}[len(parts)]
    else:  # days-hours | days-hours:minutes | days-hours:minutes:seconds
        scale = [3600, 60, 1][:len(parts)]
    return int(days or 0) * 86400 + sum(a * b for a, b in zip(parts, scale))


def _duration_seconds(text) -> float | None:
    """Seconds of ``"5m"``, ``"300s"``, ``"1h"`` (Dask's forms) or ``"00:05:00"``; None if it is not one."""
    if not isinstance(text, str):
        return None
    if ":" in text:
        return walltime_seconds(text)
    from dask.utils import parse_timedelta
    try:
        value = parse_timedelta(text.strip())
    except (ValueError, KeyError, TypeError):
        return None
    return float(value) if value is not None and value >= 0 else None


# a run inside a batch job pauses this long before the job's walltime unless the cluster table says
# (stop_before_walltime): the current chunk, the checkpoint and the worker's shutdown must fit in it
DEFAULT_STOP_BEFORE_WALLTIME = 300.0
JOB_END_ENV, STOP_MARGIN_ENV = "FVDEM_JOB_END", "FVDEM_STOP_MARGIN"
# s: how long a worker past its job's deadline holds a run it cannot start before it gives it back; the study
# retires such a worker (``_retire``), so this only paces the returns when Dask declined to retire it
PAUSED_RETURN_DELAY = 2.0
MAX_STALLS = 3  # paused attempts in a row that started and made no progress: the walltime is too short


def job_deadline(environ=None) -> float | None:
    """When a run in this process must have paused (epoch seconds): the job's end less the margin, both
    exported by the job script's prologue (``jobqueue_options``); None outside such a job."""
    environ = os.environ if environ is None else environ
    try:
        return float(environ[JOB_END_ENV]) - float(environ.get(STOP_MARGIN_ENV, DEFAULT_STOP_BEFORE_WALLTIME))
    except (KeyError, ValueError):
        return None


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


def _table(table, key, problems):
    value = table.get(key, {})
    if not isinstance(value, dict):
        _problem(problems, key, value, "a table")
        return {}
    return value


# --------------------------------------------------------------------------- tasks (run on workers)
def _finished(folder: Path, end: float) -> bool:
    summary = folder / "summary.json"
    if not summary.exists():
        return False
    try:
        data = json.loads(summary.read_text())
    except (OSError, json.JSONDecodeError):
        return False
    return not data.get("stopped_early") and (data.get("settled") or data["simulated_time"] >= end * (1 - 1e-9))


def _study_stop_file(folder) -> Path:
    """``OUT/STOP`` of the study that ``folder`` (``OUT/runs/<name>`` or ``OUT/beds/<name>``) belongs to."""
    return Path(folder).parent.parent / STOP_FILE


def _simulated_so_far(folder: Path, live: bool = False) -> float:
    """Simulated seconds a run folder holds: its summary's, else its checkpoint's (0 for a new run);
    ``live``: the last line of its time series instead of the checkpoint (a run in progress)."""
    try:
        summary = json.loads((folder / "summary.json").read_text()) if (folder / "summary.json").exists() else None
        if summary is not None and not summary.get("stopped_early"):
            return float(summary["simulated_time"])
        if live and (folder / "timeseries.csv").exists():
            return _last_time(folder / "timeseries.csv")
        if summary is not None:
            return float(summary["simulated_time"])
        if (folder / "checkpoint.npz").exists():
            import numpy as np
            with np.load(folder / "checkpoint.npz") as data:
                return float(json.loads(bytes(data["__meta__"]).decode())["time"]) if "__meta__" in data.files else 0.0
    except (OSError, KeyError, ValueError):
        pass
    return 0.0


def _last_time(path: Path) -> float:
    """The time column of a time series' last complete line (read from the end of the file)."""
    from .io.run_log import tail_lines
    for line in reversed(tail_lines(path, 4096)):
        try:
            return float(line.split(",", 1)[0])
        except ValueError:
            continue
    return 0.0


def _simulate(case_path, overrides, folder, threads, deadline: float | None = None) -> dict:
    """Run (or resume, or skip) one case into ``folder``; returns status and summary. A run stopped
    through the study's stop file checkpoints and comes back ``stopped``; one that would run past
    ``deadline`` (epoch seconds: its batch job's walltime less a margin, ``job_deadline``) checkpoints
    before it and comes back ``paused``, for the study to resubmit in another job."""
    from .simulation import Simulation
    folder = Path(folder)
    case = load_case(case_path, {**overrides, "output.progress": False})
    if _finished(folder, case.time.end):
        return {"status": "skipped", "summary": json.loads((folder / "summary.json").read_text())}
    stop_file = _study_stop_file(folder)
    so_far = {"simulated_time": _simulated_so_far(folder), "stopped_early": True}
    if stop_file.exists():
        return {"status": "stopped", "summary": so_far}
    if deadline is not None and time.time() >= deadline:
        # a job on its way out took the run: give it back (the study then retires this worker)
        time.sleep(PAUSED_RETURN_DELAY)
        return {"status": "paused", "started": False, "summary": so_far}
    stop = _StopWhen(stop_file, deadline)
    resume = (folder / "checkpoint.npz").exists()
    summary = Simulation(case, folder, resume=resume, overwrite=not resume, threads=threads, progress=False,
                         stop_file=stop).run()
    if summary.get("stopped_early"):
        return {"status": "paused" if stop.deadline_reached else "stopped", "started": True, "summary": summary}
    return {"status": "resumed" if resume else "finished", "summary": summary}


class _StopWhen:
    """A run's stop condition, checked once per chunk: the study's stop file, or a chunk that would end past
    ``deadline`` (the next chunk taken to last as long as the last one did, with half as much again)."""

    def __init__(self, stop_file: Path, deadline: float | None):
        self.stop_file, self.deadline = stop_file, deadline
        self.deadline_reached = False
        self._last = time.time()

    def __call__(self) -> bool:
        if self.stop_file.exists():
            return True
        now = time.time()
        chunk, self._last = now - self._last, now
        if self.deadline is not None and now + 1.5 * chunk >= self.deadline:
            self.deadline_reached = True
        return self.deadline_reached


def prepare_bed(bed: BedSpec, threads: int) -> str:
    """A settled bed's final state (prepared once; the runs starting from it depend on this task)."""
    outcome = _simulate(bed.case, bed.overrides, bed.folder, threads)
    if outcome["status"] == "stopped":
        raise StudyStopped(f"bed {bed.name} stopped before it settled")
    return str(Path(bed.folder) / "final_state.npz")


class StudyStopped(RuntimeError):
    """The study was asked to stop (its stop file) before this task finished."""


def run_task(run: RunSpec, threads: int, bed_state: str | None = None) -> dict:
    """One run of the study; never raises: a failure comes back with its cause."""
    started = time.perf_counter()
    overrides = dict(run.overrides)
    if bed_state is not None:
        overrides["particles.initial_state"] = bed_state
    try:
        outcome = _simulate(run.case, overrides, run.folder, threads, job_deadline())
    except Exception as exc:  # noqa: BLE001  (any failure of one run is reported, the others go on)
        from .io.run_log import log_tail
        return {"name": run.name, "family": run.family, "status": "failed", "error": f"{type(exc).__name__}: {exc}",
                "folder": run.folder, "t95": None, "simulated_seconds": 0.0, "point": run.point,
                "wall_seconds": time.perf_counter() - started, "log_tail": log_tail(run.folder)}
    summary = outcome["summary"]
    return {"name": run.name, "family": run.family, "status": outcome["status"], "t95": summary.get("t95"),
            "folder": run.folder, "simulated_seconds": summary["simulated_time"], "point": run.point,
            "pressure_drop_over_weight": summary.get("pressure_drop_over_weight"),
            "wall_seconds": time.perf_counter() - started,
            **({"started": outcome["started"], "worker": _worker_address()}
               if outcome["status"] == "paused" else {})}


def _retire(client, address: str, seconds: float = 10.0) -> bool:
    """Retire and close the worker at ``address`` (its job is at its walltime); tried again for up to
    ``seconds`` while Dask declines because a key released just before (the paused run's, its bed's) still
    lives only there. Returns whether it left; if it did not, ``PAUSED_RETURN_DELAY`` paces the run's
    returns to it until its lifetime ends it."""
    deadline = time.time() + seconds
    while True:
        try:
            if address in client.retire_workers(workers=[address], close_workers=True):
                return True
            if address not in client.scheduler_info().get("workers", {}):
                return True
        except Exception:  # noqa: BLE001  (already gone: its job ended)
            return True
        if time.time() >= deadline:
            return False
        time.sleep(0.25)


def _worker_address() -> str | None:
    """The Dask worker running this task (None outside one): a paused run names it, so that the study
    retires it (its job is at its end) before the run goes back into the queue."""
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):
        return None


# --------------------------------------------------------------------------- the scheduler side
def make_client(cluster: dict | None, scheduler: str | None, workers: int | None, threads: int):
    """A Dask client: on ``scheduler``, on a dask-jobqueue ``cluster`` table (a study's ``[cluster]``), or on
    a LocalCluster of ``workers`` processes (default: cores / threads). Returns ``(client, description)``."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:  # pragma: no cover - a dependency
        raise CaseError(["fvdem study needs Dask distributed: pip install 'dask[distributed]'"]) from None
    if scheduler:
        return Client(scheduler), scheduler
    cluster = cluster or {}
    problems: list[str] = []
    check_cluster(cluster, problems)  # a study's table was checked already; map_tasks' callers' is here
    if problems:
        raise CaseError(problems)
    options = {k: v for k, v in cluster.items() if k not in ("kind", "workers")}
    kind = cluster.get("kind", "local")
    count = workers or cluster.get("workers") or max(1, (os.cpu_count() or 1) // max(1, threads))
    if kind == "local":
        # Ctrl-C on a terminal signals the whole process group: the local workers ignore SIGINT (set
        # while they are spawned, and again by a plugin on any worker that replaces one), so that the
        # study's own handler stops the runs with checkpoints instead of the workers dying mid-run
        previous = signal.getsignal(signal.SIGINT) if threading.current_thread() is threading.main_thread() else None
        if previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            local = LocalCluster(n_workers=count, threads_per_worker=1, processes=True, dashboard_address=":0",
                                 **options)  # any free port: two studies side by side do not clash
        finally:
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
        client = Client(local)
        client.register_plugin(IgnoreInterrupt())
        return client, f"LocalCluster({count} workers x {threads} numba threads)"
    try:
        import dask_jobqueue
    except ImportError:
        raise CaseError([f"cluster.kind = {kind!r}: needs dask-jobqueue (pip install dask-jobqueue)"]) from None
    cluster_class = {"slurm": "SLURMCluster", "pbs": "PBSCluster", "sge": "SGECluster", "lsf": "LSFCluster"}[kind]
    try:
        jobs = getattr(dask_jobqueue, cluster_class)(**jobqueue_options(kind, options, threads))
    except (TypeError, ValueError) as exc:  # an option dask-jobqueue does not know
        raise CaseError([f"cluster: {exc} (the [cluster] table's keys are dask_jobqueue.{cluster_class}'s options)"]) from None
    # jobs while runs wait, none once they are done: a job that ends (its walltime, its worker's lifetime)
    # is replaced as long as runs are left, and idle ones are released to the shared queue. A target
    # duration of 1 ms asks for one job per waiting run (up to ``count``): Dask's default (5 s, with an
    # unknown task taken to last 0.5 s) would start one job for the first ten runs
    jobs.adapt(minimum_jobs=0, maximum_jobs=count, target_duration="1ms")
    return Client(jobs), f"{cluster_class}(up to {count} jobs)"


def jobqueue_options(kind: str, options: dict, threads: int) -> dict:
    """dask-jobqueue's options for a study's ``[cluster]`` table: one Dask worker process with one task
    slot per job (``cores = 1``, ``processes = 1``: one run at a time, its numba threads its own), and
    the job booking the run's ``threads`` CPUs where the scheduler has a separate option for it (SLURM
    ``job_cpu``, LSF ``ncpus``; on PBS and SGE book them with ``resource_spec``). The table has been
    checked (``check_cluster``: ``memory`` required, keys known to dask-jobqueue's classes)."""
    options = dict(options)
    margin = options.pop("stop_before_walltime", None)
    options.setdefault("cores", 1)
    options.setdefault("processes", 1)
    if kind == "slurm":
        options.setdefault("job_cpu", threads)
    elif kind == "lsf":
        options.setdefault("ncpus", threads)
    walltime = walltime_seconds(options["walltime"]) if "walltime" in options else None
    if walltime:
        # the job exports when it ends and the margin; a run pauses that long before (``job_deadline``) and
        # the worker retires halfway through the margin, so it takes no new run on its way out
        margin = _duration_seconds(margin) if margin is not None else min(DEFAULT_STOP_BEFORE_WALLTIME, walltime / 4)
        options["job_script_prologue"] = [*options.get("job_script_prologue", []),
                                          f"export {JOB_END_ENV}=$(( $(date +%s) + {walltime} ))",
                                          f"export {STOP_MARGIN_ENV}={margin:g}"]
        options["worker_extra_args"] = [*options.get("worker_extra_args", []),
                                        "--lifetime", f"{max(1.0, walltime - margin / 2):g}s"]
    return options


try:
    from distributed.diagnostics.plugin import WorkerPlugin
except ImportError:  # pragma: no cover - a dependency
    WorkerPlugin = object


class IgnoreInterrupt(WorkerPlugin):
    """A local worker ignores SIGINT (the terminal's Ctrl-C reaches the whole process group)."""

    name = "fvdem-ignore-sigint"

    def setup(self, worker):
        try:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        except ValueError:  # not the worker's main thread
            pass


def close_client(client) -> None:
    client.close()
    cluster = getattr(client, "cluster", None)
    if cluster is not None:
        cluster.close()


def progress_line(done: int, total: int, name: str, status: str, detail: str, started: float,
                  work_done: float | None = None, work_total: float | None = None, unit: str = "") -> str:
    """One line of a sweep's progress view: tasks done, the work done (e.g. simulated seconds) and an ETA
    from the rate so far."""
    elapsed = time.perf_counter() - started
    done_work, total_work = (done, total) if work_done is None else (work_done, work_total)
    eta = elapsed / done_work * (total_work - done_work) if done_work else math.nan
    work = f"{done_work:.4g} of {total_work:.4g}{unit} done, " if work_done is not None else ""
    return (f"[{done}/{total}] {name}: {status}" + (f" ({detail})" if detail else "")
            + f"; {work}{elapsed:.0f} s wall, ETA {eta:.0f} s")


def _guarded(function, item, threads):
    """A sweep task: ``function(item, threads)``, its failure returned with the cause instead of raised."""
    started = time.perf_counter()
    try:
        value = function(item, threads)
    except Exception as exc:  # noqa: BLE001  (one failed point is reported, the others go on)
        return {"status": "failed", "error": f"{type(exc).__name__}: {exc}", "value": None,
                "wall_seconds": time.perf_counter() - started}
    return {"status": "finished", "error": None, "value": value, "wall_seconds": time.perf_counter() - started}


def map_tasks(function, items, names, *, threads=1, scheduler=None, workers=None, cluster=None, log=print) -> list:
    """The engine under every sweep that is not a study of case files (the tools' fractions, variants
    and ramps): ``function(item, threads)`` for each item, each a task on the same Dask clients as
    ``fvdem study`` (``scheduler``, a dask-jobqueue ``cluster`` table, or a LocalCluster of ``workers``),
    one progress line per finished task. Returns, in the items' order, ``{"name", "status"
    ("finished" or "failed"), "value", "error", "wall_seconds"}``: a failure does not stop the others.
    ``function`` must be importable or picklable (a tool's module-level function is)."""
    from distributed import as_completed
    names = [str(n) for n in names]
    if len(set(names)) != len(names):
        raise ValueError("map_tasks: task names must be distinct")
    started = time.perf_counter()
    client, description = make_client(cluster, scheduler, workers, threads)
    log(f"{len(names)} tasks on {description}")
    results = {}
    try:
        futures = {client.submit(_guarded, function, item, threads, key=f"task-{name}", pure=False): name
                   for item, name in zip(items, names)}
        for done, future in enumerate(as_completed(list(futures)), 1):
            name = futures[future]
            result = dict(future.result(), name=name)
            results[name] = result
            log(progress_line(done, len(names), name, result["status"], result["error"] or "", started))
    finally:
        close_client(client)
    return [results[name] for name in names]


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
    return replace(study, runs=runs, beds=beds)


def request_stop(out) -> Path:
    """Ask the study running in ``out`` to stop: its runs checkpoint and end, queued runs do not start."""
    path = Path(out) / STOP_FILE
    path.write_text("stop requested\n")
    return path


# a replica's rank in the queue: every first replica before any second one, and so on (far more than a
# run's DEM steps, 2e7 for 20 s at 1e-6 s); the beds come before the runs of their replica
REPLICA_RANK = 10**10
BED_RANK = 10**12


def _priority(run: RunSpec) -> int:
    """First replicas first, then longest first: DEM steps left (duration minus what the folder holds,
    over the DEM step), less ``REPLICA_RANK`` per replica after the first. A campaign cut short has every
    point of the study once before it has any twice."""
    rank = -(run.replica - 1) * REPLICA_RANK
    try:
        dem_step = float(load_case(run.case, dict(run.overrides)).time.dem_step)
    except CaseError:
        return rank
    left = max(0.0, run.duration - _simulated_so_far(Path(run.folder)))
    return rank + int(round(left / dem_step))


def _bed_priority(bed: BedSpec) -> int:
    """A bed settles before the runs of its replica (``_priority``) but after those of the replica before:
    the first replicas' beds before everything, the own beds of second replicas once every first replica
    has started."""
    return BED_RANK if bed.replica == 1 else -(bed.replica - 1) * REPLICA_RANK + REPLICA_RANK // 2


class _StudyProgress:
    """The study's progress view: simulated seconds done over all runs (read from the run folders every
    ``poll`` seconds), runs done and the time left, as a tqdm bar on a terminal or a line every 2 % in a
    log (``fvdem.io.progress``); per-run lines go above it."""

    def __init__(self, study: Study, started: float, log):
        from .io.progress import progress_bar
        self.study, self.log = study, log
        self.total = sum(r.duration for r in study.runs)
        self.bar = progress_bar(self.total, self._simulated(), f"study {study.name} (simulated s)")
        if hasattr(self.bar, "step"):
            self.bar.step = 2.0
        self.is_tqdm = not hasattr(self.bar, "step")

    def _simulated(self) -> float:
        return sum(min(r.duration, _simulated_so_far(Path(r.folder), live=True)) for r in self.study.runs)

    def update(self, runs_done: int) -> None:
        now = self._simulated()
        self.bar.set_postfix_str(f"{runs_done}/{len(self.study.runs)} runs done", refresh=False)
        if now > self.bar.n:
            self.bar.update(now - self.bar.n)

    def message(self, line: str) -> None:
        if self.is_tqdm:
            self.bar.write(line, file=sys.stderr)
        else:
            self.log(line)

    def close(self) -> None:
        self.bar.close()


def run_study(study: Study, out, *, scheduler=None, workers=None, threads=1, log=print, poll: float = 30.0) -> dict:
    """Run every bed and run of ``study`` on Dask; returns the study's result (see ``fvdem study``).
    SIGINT/SIGTERM (main thread) or ``request_stop(out)`` stop it with every running run checkpointed.
    Progress: the run folders are read every ``poll`` seconds (``_StudyProgress``)."""
    from distributed import wait
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "study.toml").write_text(Path(study.path).read_text())
    (out / STOP_FILE).unlink(missing_ok=True)  # a stop request belongs to the invocation it stopped
    stop_requested = []

    def on_signal(signum, _frame):
        if not stop_requested:
            log(f"stopping (signal {signum}): each running run checkpoints at its next chunk; the same command "
                "continues the study")
        stop_requested.append(signum)
        request_stop(out)

    handlers = {}
    try:
        handlers = {sig: signal.signal(sig, on_signal) for sig in (signal.SIGINT, signal.SIGTERM)}
    except ValueError:  # not the main thread: request_stop(out) still stops the study
        pass
    started = time.perf_counter()
    client, description = make_client(study.cluster, scheduler, workers, threads)
    log(f"{description}; Dask dashboard at {getattr(client, 'dashboard_link', None) or 'none'}")
    tag = task_tag(study, out)
    try:
        beds = {b.name: client.submit(prepare_bed, b, threads, key=f"{tag}bed-{b.name}", pure=False,
                                      priority=_bed_priority(b)) for b in study.beds}

        def submit(run, key):
            return client.submit(run_task, run, threads, beds.get(run.bed) if run.bed else None, key=key, pure=False,
                                 priority=_priority(run))

        run_of, pending = {}, set()  # the futures live in ``pending`` only (a finished one is let go)
        for run in study.runs:
            future = submit(run, f"{tag}run-{run.name}")
            run_of[future.key] = run
            pending.add(future)
        attempts = {r.name: 1 for r in study.runs}
        stalls: dict[str, tuple] = {}  # run -> (paused attempts in a row without progress, time reached)

        def resubmit(run, result, future):
            """A run paused before its job's walltime goes back into the queue under a new key, however many
            jobs it takes; None after ``MAX_STALLS`` started attempts in a row without progress (or when
            the study is stopping)."""
            count, reached = stalls.get(run.name, (0, -1.0))
            if result.get("started", True):
                count = count + 1 if result["simulated_seconds"] <= reached else 0
            stalls[run.name] = (count, max(reached, result["simulated_seconds"]))
            if result.get("worker"):
                # the job is at its end: its worker takes no further run (retired before the resubmission,
                # or the scheduler could hand the run straight back to it), and adaptive scaling starts a
                # fresh job. Dask retires a worker only when no key lives on it alone, so the paused run's
                # result and its bed's state (now passed by value) are released first.
                if run.bed and not isinstance(beds[run.bed], str):
                    beds[run.bed] = beds[run.bed].result()
                client.cancel([future])
                _retire(client, result["worker"])
            if count >= MAX_STALLS or (out / STOP_FILE).exists():
                return None
            attempts[run.name] += 1
            bar.message(f"{run.name}: paused at t = {result['simulated_seconds']:.4g} s before its job's walltime; "
                        f"resubmitted (attempt {attempts[run.name]})")
            retry = submit(run, f"{tag}run-{run.name}-{attempts[run.name]}")
            run_of[retry.key] = run
            return retry

        total = sum(r.duration for r in study.runs)
        results, done = [], 0.0
        write_index(out, study, description=description)
        bar = _StudyProgress(study, started, log)
        while pending:
            try:
                finished, pending = wait(pending, timeout=poll, return_when="FIRST_COMPLETED")
            except TimeoutError:  # Dask's wait raises when nothing finished within the poll: show progress
                finished = set()
            for future in finished:
                try:
                    result = future.result()
                except Exception as exc:  # noqa: BLE001  (a bed failed or was stopped: its runs cannot start)
                    run = run_of[future.key]
                    name = run.name
                    stopped = isinstance(exc, StudyStopped) or (out / STOP_FILE).exists()
                    result = {"name": name, "family": run.family, "status": "stopped" if stopped else "failed",
                              "folder": run.folder, "t95": None, "simulated_seconds": 0.0, "point": run.point,
                              **({} if stopped else {"error": f"{type(exc).__name__}: {exc}"})}
                if result["status"] == "paused":
                    retry = resubmit(run_of[future.key], result, future)
                    if retry is not None:
                        pending.add(retry)
                        write_index(out, study, [*results, result], description)
                        continue
                    result = {**result, "status": "failed", "error": (
                        f"paused {MAX_STALLS} times in a row at t = {result['simulated_seconds']:.6g} s without "
                        "a step: its job's walltime less stop_before_walltime leaves no time for one chunk of "
                        "it; raise the cluster's walltime or lower stop_before_walltime")}
                results.append(result)
                done += result.get("simulated_seconds", 0.0) if result["status"] != "failed" else 0.0
                detail = result.get("error") or (f"t95 {result['t95']:.3g} s" if result.get("t95") is not None
                                                 else "t95 -")
                bar.message(progress_line(len(results), len(study.runs), result["name"], result["status"], detail,
                                          started, done, total, " simulated s"))
                write_index(out, study, results, description)
            bar.update(len(results))
        bar.close()
    finally:
        close_client(client)
        for sig, handler in handlers.items():
            signal.signal(sig, handler)
    index = write_index(out, study, results, description)
    summary = {"study": study.name, "scheduler": description, "runs": index["runs"],
               "wall_seconds": time.perf_counter() - started}
    if (out / STOP_FILE).exists():
        summary["stopped"] = True
    (out / "study.json").write_text(json.dumps(summary, indent=1) + "\n")
    return summary


def load_cluster(path) -> dict:
    """A cluster file (``fvdem study ... --cluster FILE``): the ``[cluster]`` table of a study file on
    its own, so the physics study file stays the same on a workstation and on any cluster. Its keys at
    the top level, or under ``[cluster]``; checked like a study's (``check_cluster``)."""
    path = Path(path)
    table = read_toml(path, "--cluster ")
    cluster = table["cluster"] if set(table) == {"cluster"} and isinstance(table["cluster"], dict) else table
    problems: list[str] = []
    check_cluster(cluster, problems)
    if problems:
        raise CaseError([f"{path}: {p}" for p in problems])
    return cluster


def task_tag(study: Study, out) -> str:
    """The prefix of a study's Dask task keys: its name and a digest of its folder, so that two studies
    (or one study in two folders) on one shared scheduler never share a task (Dask keeps the first task
    of a key and hands its result to the second: another study's bed, settled at other settings)."""
    import hashlib
    digest = hashlib.sha1(str(Path(out).resolve()).encode()).hexdigest()[:10]
    return f"{study.name}-{digest}-"


def _pending(run: RunSpec) -> dict:
    return {"name": run.name, "family": run.family, "status": "pending", "folder": run.folder, "t95": None,
            "point": run.point, "simulated_seconds": _simulated_so_far(Path(run.folder))}


def write_index(out, study: Study, results=(), description: str | None = None) -> dict:
    """``study.json``: every run of ``study`` with its latest result (``results``, else the one on
    record, else ``pending`` with the simulated seconds its folder holds), so that ``--report`` works
    while a study runs. Returns the index written."""
    out = Path(out)
    path = out / "study.json"
    record = {}
    if path.exists():
        try:
            record = json.loads(path.read_text())
        except (OSError, json.JSONDecodeError):
            record = {}
    latest = {r["name"]: r for r in record.get("runs", [])}
    latest.update({r["name"]: r for r in results})
    names = [r.name for r in study.runs]
    runs = ([{**(latest.get(r.name) or _pending(r)), "replica": r.replica} for r in study.runs]
            + [r for n, r in latest.items() if n not in names])
    index = {**{k: v for k, v in record.items() if k != "runs"}, "study": study.name,
             **({"scheduler": description} if description else {}), "runs": runs}
    path.write_text(json.dumps(index, indent=1) + "\n")
    return index


def _series(folder: Path):
    """A run's time series (``read_timeseries``), or None while it has none or only its header."""
    from .analysis.plots import read_timeseries
    if not (folder / "timeseries.csv").exists():
        return None
    try:
        series = read_timeseries(folder)
    except (IndexError, ValueError):  # a run that has written its header only
        return None
    return series if len(series.get("time", ())) else None


def _so_far(series) -> dict:
    """A run in progress from its time series: t95 (None if not yet mixed), simulated seconds, and the
    bed pressure drop over W/A and its fluctuation over the second half of what it holds."""
    import numpy as np
    from .analysis.mixing import mixing_time
    times = series["time"]
    out = {"simulated_time": float(times[-1]) if len(times) else 0.0,
           "t95": mixing_time(times, series["mixing_entropy"]) if "mixing_entropy" in series else None}
    if "pressure_drop_over_weight" in series and len(times) > 1:
        half = series["pressure_drop_over_weight"][times >= 0.5 * times[-1]]
        out["pressure_drop_over_weight"] = float(np.mean(half))
        out["pressure_drop_std_over_weight"] = float(np.std(half))
    return out


def _bed_surface(series):
    """The bed's height [m] as the table gives it: the mean over the second half of the time series of
    ``bed_top`` (the height below which 99 % of the particle tops lie), None without it. The summary's
    ``bed_height`` is a packed bed's (solid volume over area and core solids fraction): in a fluidized
    bed it exceeds the column (1.37 m in the 1.05 m column for AR-1 at 2.9 Umf). ``series``: ``_series``'s
    (None, or at least one row)."""
    import numpy as np
    if series is None or "bed_top" not in series:
        return None
    times = series["time"]
    return float(np.mean(series["bed_top"][times >= 0.5 * times[-1]]))


def _inlet_passes_umf(folder: Path) -> float | None:
    """When [s] a run's inlet velocity reaches the Umf its ``u_over_umf`` refers to: ``inlet_ramp / u_over_umf``
    for a linear ramp from 0 (0 for a full-speed start); None without a readable case or a U/Umf."""
    try:
        gas = load_case(folder / "case.toml").gas
    except CaseError:
        return None
    if not gas.u_over_umf:
        return None
    return gas.inlet_ramp / gas.u_over_umf if gas.u_over_umf >= 1.0 else None


def _pairs(runs, first, second) -> dict:
    """``{axes values: (run of family first, run of family second)}`` where both ran at those values."""
    by = {}
    for r in runs:
        by.setdefault(tuple(r.get("point", {}).values()), {})[r["family"]] = r
    return {point: (fam[first], fam[second]) for point, fam in by.items() if first in fam and second in fam}


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
    from .analysis.mixing import void_fraction_binarity
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
    from .analysis.plots import _pyplot, _save
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


def report(out) -> list:
    """The study's figures and table from its run folders: mixing entropy against time per family
    (Mema et al. (2020) Fig. 2), t95 against U/Umf (Fig. 4), AR-1 against AR-4 MP (Fig. 3) with their void
    fractions below 0.3 m (Fig. 7) and AR-4 MP drag only against drag + lift + torque (Fig. 9) at each
    velocity both ran, ``table.csv`` / ``table.json``, and ``findings.json`` (``check_findings``)."""
    from .analysis.plots import plot_mixing, plot_t95
    out = Path(out)
    result = json.loads((out / "study.json").read_text())
    for r in result["runs"]:  # an archive's folders are relative to it (fvdem study DIR --archive DEST)
        r["folder"] = str(out / r["folder"]) if not Path(r["folder"]).is_absolute() else r["folder"]
    runs = [r for r in result["runs"] if r["status"] != "failed" and (Path(r["folder"]) / "timeseries.csv").exists()]
    paths = []
    for family in sorted({r["family"] for r in runs}):
        paths.append(plot_mixing([Path(r["folder"]) for r in runs if r["family"] == family],
                                 out / f"mixing_{family}.png"))
    if runs:
        paths.append(plot_t95([Path(r["folder"]) for r in runs], out / "t95.png", names=[r["family"] for r in runs]))
    # Mema et al. (2020) Fig. 3 (AR-1 against AR-4 MP) and Fig. 9 (AR-4 MP drag only against drag + lift + torque)
    # at each velocity both families ran; Fig. 7 (void fractions below 0.3 m) of the same pairs
    for figure, (first, second) in (("fig3", ("ar1", "ar4_mp")), ("fig9", ("ar4_mp_drag", "ar4_mp"))):
        for point, pair in sorted(_pairs(runs, first, second).items()):
            tag = "_".join(f"{v:g}" for v in point)
            paths.append(plot_mixing([Path(r["folder"]) for r in pair], out / f"{figure}_mixing_{tag}.png"))
            if figure == "fig3":
                paths.append(plot_void_fractions(pair, out / f"fig7_void_fraction_{tag}.png"))
    rows = []
    for r in result["runs"]:
        summary = Path(r["folder"]) / "summary.json"
        data = json.loads(summary.read_text()) if summary.exists() else {}
        series = _series(Path(r["folder"]))
        if (not data or data.get("stopped_early")) and series is not None:
            # a run in progress: what its time series holds (the summary of an earlier stop is stale)
            data = _so_far(series)
            r = {**r, "t95": data["t95"]}
        record = void_fraction_record(r["folder"]) if r["status"] != "failed" else None
        binarity = None if record is None else record["binarity"]
        entropy = float(series["mixing_entropy"][-1]) if series is not None and "mixing_entropy" in series else None
        passes = _inlet_passes_umf(Path(r["folder"]))
        t95 = r.get("t95")
        rows.append({"name": r["name"], "family": r["family"], **r.get("point", {}), "status": r["status"],
                     "t95": t95, "inlet_passes_umf": passes,
                     "t95_from_inlet_at_umf": None if t95 is None or passes is None else t95 - passes,
                     "pressure_drop_over_weight": data.get("pressure_drop_over_weight"),
                     "pressure_drop_std_over_weight": (data["bed_pressure_drop_std_second_half"] / data["bed_weight_per_area"]
                                                       if "bed_pressure_drop_std_second_half" in data
                                                       else data.get("pressure_drop_std_over_weight")),
                     "bed_height": _bed_surface(series), "wall_seconds": data.get("wall_seconds"),
                     "simulated_seconds": data.get("simulated_time"),
                     "final_mixing_entropy": entropy,
                     "replica": r.get("replica") or int((re.search(r"_r(\d+)$", r["name"]) or [0, 1])[1]),
                     "void_fraction_binarity": binarity})
    (out / "table.json").write_text(json.dumps(rows, indent=1) + "\n")
    columns = list(dict.fromkeys(k for row in rows for k in row))
    lines = [",".join(columns)] + [",".join("" if row.get(c) is None else str(row.get(c)) for c in columns) for row in rows]
    (out / "table.csv").write_text("\n".join(lines) + "\n")
    findings = check_findings(rows)
    (out / "findings.json").write_text(json.dumps(findings, indent=1) + "\n")
    return paths + [out / "table.csv", out / "table.json", out / "findings.json"]


# --------------------------------------------------------------------------- archive (compact results)
ARCHIVED_COLUMNS = ("time", "mixing_entropy", "lacey_index", "pressure_drop_over_weight", "bed_pressure_drop",
                    "bed_top", "rms_speed", "max_overlap_over_diameter")
ARCHIVED_SUMMARY = ("case", "simulated_time", "steps", "settled", "stopped_early", "threads", "wall_seconds",
                    "cpu_seconds", "timings", "provenance", "t95", "pressure_drop_over_weight",
                    "bed_pressure_drop_std_second_half", "bed_weight_per_area", "bed_height", "mixing_cells",
                    "peak_memory_mb")


def archive(out, dest) -> list:
    """The compact results of a study folder's runs in ``dest`` (small enough to commit, e.g. under
    ``docs/data/``): per run its ``case.toml``, its time series thinned to ``ARCHIVED_COLUMNS`` (6
    significant digits), its summary's ``ARCHIVED_SUMMARY`` keys, its void-fraction record (histogram
    below 0.3 m, binarity) and its ``run.log``; plus the study's ``study.json`` (folders relative to
    ``dest``) and ``study.toml``, and the report made from them. No checkpoints, states or VTU files.
    ``fvdem study DEST --report`` rebuilds the report and findings from ``dest`` alone. A run already in
    ``dest`` is replaced only by one that holds more simulated time. Returns the files written."""
    out, dest = Path(out), Path(dest)
    index = json.loads((out / "study.json").read_text())
    dest.mkdir(parents=True, exist_ok=True)
    kept = json.loads((dest / "study.json").read_text()) if (dest / "study.json").exists() else {"runs": []}
    runs = {r["name"]: r for r in kept["runs"]}
    written = []
    for r in index["runs"]:
        folder = Path(r["folder"])
        series = _series(folder)
        if series is None:
            continue
        target = dest / "runs" / r["name"]
        held = _simulated_so_far(target, live=True) if target.exists() else -1.0
        if float(series["time"][-1]) <= held:
            continue  # what the archive holds is as far along (a later invocation lost nothing)
        target.mkdir(parents=True, exist_ok=True)
        columns = [c for c in ARCHIVED_COLUMNS if c in series]
        rows = zip(*(series[c] for c in columns))
        (target / "timeseries.csv").write_text(",".join(columns) + "\n" + "".join(
            ",".join(f"{v:.6g}" for v in row) + "\n" for row in rows))
        if (folder / "summary.json").exists():
            summary = json.loads((folder / "summary.json").read_text())
            summary = {k: summary[k] for k in ARCHIVED_SUMMARY if k in summary}
            if summary.get("stopped_early"):
                summary.update(_so_far(series))
            (target / "summary.json").write_text(json.dumps(summary, indent=1) + "\n")
        for name in ("case.toml", "run.log"):
            if (folder / name).exists():
                (target / name).write_text((folder / name).read_text())
        record = void_fraction_record(folder)
        if record is not None:
            (target / VOID_FRACTION).write_text(json.dumps(record) + "\n")
        runs[r["name"]] = {**r, "folder": f"runs/{r['name']}", "simulated_seconds": float(series["time"][-1])}
        written.append(target)
    (dest / "study.json").write_text(json.dumps({**{k: v for k, v in index.items() if k != "runs"},
                                                 "archived_from": str(out), "runs": list(runs.values())}, indent=1)
                                     + "\n")
    if (out / "study.toml").exists():
        (dest / "study.toml").write_text((out / "study.toml").read_text())
    return written + report(dest)


# Mema et al.'s findings (§5-§6) that a study's t95 table can check; each rule sees the runs by family
CLOSE = 0.10  # relative differences below this need replicas to be told from chaos
TERMINAL = 0.25  # a terminal t95 within this of the paper's "about" value holds
SETTINGS_TOLERANCE = 0.15  # t95 at the defaults within this of t95 at the paper's settings: no change


def _compare_binarity(rows) -> dict:
    """AR-1's void fractions below 0.3 m more binary than AR-4 MP's (Fig. 7), at every velocity both ran."""
    claim = "AR-1 void fractions more binary than AR-4 (Fig. 7)"
    by = {}
    for r in rows:
        if r["family"] in ("ar1", "ar4_mp") and r["status"] != "failed" and r.get("void_fraction_binarity") is not None:
            by.setdefault(r.get("gas.u_over_umf"), {}).setdefault(r["family"], []).append(r["void_fraction_binarity"])
    common = sorted(v for v, fam in by.items() if v is not None and len(fam) == 2)
    if not common:
        return {"finding": claim, "verdict": "open", "why": "no velocity where AR-1 and AR-4 MP both have gas snapshots"}
    values, close = {}, []
    for v in common:
        a, b = (sum(by[v][f]) / len(by[v][f]) for f in ("ar1", "ar4_mp"))
        values[f"{v:g}"] = {"ar1": a, "ar4_mp": b}
        if abs(a - b) < CLOSE * max(a, b) and min(len(by[v]["ar1"]), len(by[v]["ar4_mp"])) < 2:
            close.append(f"{v:g} Umf within {100 * CLOSE:.0f} % without replicas")
    rule = "binarity var / ((mean - packed)(1 - mean)) of the cells below 0.3 m, second half of the run"
    if close:
        return {"finding": claim, "verdict": "open", "why": "; ".join(close) + " (too noisy to tell)", "values": values,
                "rule": rule}
    holds = all(x["ar1"] > x["ar4_mp"] for x in values.values())
    return {"finding": claim, "verdict": "holds" if holds else "does not hold", "values": values, "rule": rule}


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
        if r["family"] == family and r["status"] != "failed" and "gas.u_over_umf" in r:
            out.setdefault(r["gas.u_over_umf"], []).append(r.get(key))
    return out


def _t95(rows, family):
    """``{U/Umf: [t95 or None, ...]}`` of the runs of a family (replicas listed together)."""
    return _by_velocity(rows, family, "t95")


def _compare(rows, faster, slower, velocities, claim):
    """``faster`` mixes sooner than ``slower`` at every velocity of ``velocities`` both ran."""
    a, b = _t95(rows, faster), _t95(rows, slower)
    common = sorted(v for v in set(a) & set(b) if velocities(v))
    if not common:
        return {"finding": claim, "verdict": "open", "why": f"no velocity where both {faster} and {slower} ran"}
    values, why, faster_at = {}, [], {}
    for v in common:
        if None in a[v] or None in b[v]:
            # an unmixed run's t95 lies beyond its end: a mixed run that mixed before the other's end
            # decides the comparison; otherwise show the entropy both reached
            ends = [[e or 0.0 for e in _by_velocity(rows, family, "simulated_seconds")[v]]
                    for family in (faster, slower)]
            ta = max(a[v]) if None not in a[v] else None
            tb = max(b[v]) if None not in b[v] else None
            if ta is not None and tb is None and ta < min(ends[1]):
                values[f"{v:g}"] = {faster: ta, slower: f"> {min(ends[1]):g} (not mixed by its end)"}
                faster_at[v] = True
                continue
            if tb is not None and ta is None and tb < min(ends[0]):
                values[f"{v:g}"] = {faster: f"> {min(ends[0]):g} (not mixed by its end)", slower: tb}
                return {"finding": claim, "verdict": "does not hold", "values": values,
                        "rule": "a run not mixed by its end mixes later than a run mixed before that time"}
            values[f"{v:g}"] = {"mixing_entropy_at_end": {family: _by_velocity(rows, family, "final_mixing_entropy")[v]
                                                          for family in (faster, slower)},
                                "end_time": {faster: ends[0], slower: ends[1]}}
            return {"finding": claim, "verdict": "open", "why": f"not mixed by the run's end at {v:g} Umf (too short)",
                    "values": values}
        ta, tb = sum(a[v]) / len(a[v]), sum(b[v]) / len(b[v])
        values[f"{v:g}"] = {faster: ta, slower: tb}
        faster_at[v] = ta < tb
        if abs(ta - tb) < CLOSE * max(ta, tb) and min(len(a[v]), len(b[v])) < 2:
            why.append(f"{v:g} Umf within {100 * CLOSE:.0f} % without replicas")
    if why:
        return {"finding": claim, "verdict": "open", "why": "; ".join(why) + " (too noisy to tell)", "values": values}
    holds = all(faster_at.values())
    return {"finding": claim, "verdict": "holds" if holds else "does not hold", "values": values}


def check_findings(rows) -> list:
    """Each finding of Mema et al. (2020) (§5-§6), with fvdem's numbers and one word: holds, does not hold, or
    open (and why: runs missing, too short to mix, or differences within the noise without replicas).
    From the t95 table: AR-4 against AR-1 up to 2 Umf, lift and torque, SP against MP, the terminal t95
    and its change above 2.3 Umf; from the gas snapshots: AR-1's void fractions more binary than AR-4's
    (``void_fraction_binarity``, Fig. 7); and whether fvdem's defaults change the mixing (a family
    ``ar1_paper`` at the paper's settings beside ``ar1``)."""
    findings = [
        _compare(rows, "ar4_mp", "ar1", lambda v: v <= 2.0, "AR-4 (MP) mixes faster than AR-1 up to 2 Umf"),
        _compare(rows, "ar4_mp", "ar4_mp_drag", lambda v: True, "lift and torque shorten AR-4 mixing"),
    ]
    sp, mp = _t95(rows, "ar4_sp"), _t95(rows, "ar4_mp")
    common = [v for v in sorted(set(sp) & set(mp)) if None not in sp[v] + mp[v]]
    claim = "single- against multi-particle closures: only a slight effect on AR-4 mixing"
    if not common:
        findings.append({"finding": claim, "verdict": "open", "why": "no velocity where SP and MP both mixed"})
    else:
        gaps = {f"{v:g}": abs(sum(sp[v]) / len(sp[v]) - sum(mp[v]) / len(mp[v])) / (sum(mp[v]) / len(mp[v]))
                for v in common}
        findings.append({"finding": claim, "verdict": "holds" if max(gaps.values()) < 0.2 else "does not hold",
                         "values": gaps, "rule": "t95 within 20 %"})
    for family, paper in (("ar1", 2.6), ("ar4_mp", 2.3)):
        t = _t95(rows, family)
        high = sorted(v for v in t if v >= 2.3)
        claim = f"terminal t95 of {family} about {paper} s (paper)"
        mixed = [v for v in high if None not in t[v]]
        if not high:
            findings.append({"finding": claim, "verdict": "open", "why": "no velocity at or above 2.3 Umf"})
        elif not mixed:
            findings.append({"finding": claim, "verdict": "open", "why": "not mixed by the run's end (too short)"})
        else:
            means = {f"{v:g}": sum(t[v]) / len(t[v]) for v in mixed}
            terminal = sum(means.values()) / len(means)
            findings.append({"finding": claim, "verdict": "holds" if abs(terminal / paper - 1) < TERMINAL else "does not hold",
                             "values": means, "rule": f"mean t95 at or above 2.3 Umf within {100 * TERMINAL:.0f} % of the paper"})
        claim = f"{family}: little change of t95 above about 2.3 Umf"
        if len(mixed) < 2:
            findings.append({"finding": claim, "verdict": "open",
                             "why": "fewer than two mixed velocities at or above 2.3 Umf"})
        else:
            means = {f"{v:g}": sum(t[v]) / len(t[v]) for v in mixed}
            spread = (max(means.values()) - min(means.values())) / max(means.values())
            findings.append({"finding": claim, "verdict": "holds" if spread < 0.2 else "does not hold",
                             "values": means, "rule": "spread below 20 %"})
    findings.append(_compare_binarity(rows))
    findings.append(_defaults_against_paper_settings(rows))
    return findings
