"""Where a study's runs go: the ``[cluster]`` table (or ``--cluster FILE``) checked, the Dask client made
on it (a LocalCluster, a running scheduler, or a dask-jobqueue cluster of batch jobs), and what a run
inside a batch job knows of its walltime (``job_deadline``)."""
from __future__ import annotations

import os
import re
import signal
import threading
from pathlib import Path

from ..errors import CaseError
from .checks import did_you_mean, problem, read_toml


CLUSTER_KINDS = ("local", "slurm", "pbs", "sge", "lsf")


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
        problem(problems, "cluster.kind", kind, f"one of {', '.join(CLUSTER_KINDS)}")
        return
    allowed = cluster_keys(kind)
    for key in sorted(set(cluster) - allowed, key=str):
        problem(problems, f"cluster.{key}", cluster[key], f"unknown key for kind = {kind!r}"
                 f"{did_you_mean(key, allowed)}; allowed: {', '.join(sorted(allowed))}")
    for key, (kind_of, what, ok) in CLUSTER_TYPES.items():
        if key in cluster and key in allowed:
            value = cluster[key]
            if not isinstance(value, kind_of) or isinstance(value, bool) or not ok(value):
                problem(problems, f"cluster.{key}", value, what)
    if kind != "local" and "memory" not in cluster:
        problems.append(f"cluster.memory: missing; a {kind} job needs the memory it books, e.g. memory = \"4GB\" "
                        "(a run of the shipped fluidized beds needs about 1 GB: docs/studies.md, \"What a run costs\")")


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


def until_epoch(text, now: float | None = None) -> float | None:
    """The epoch seconds a study's ``--until`` names: ``"+<duration>"`` from ``now`` (``_duration_seconds``'s
    forms: ``"+90m"``, ``"+2h"``, ``"+1:30:00"``), a clock time ``"HH:MM"`` or ``"HH:MM:SS"`` (local, its next
    occurrence after ``now``) or an ISO date and time (``"2026-12-05T04:45"``, local unless it has an offset);
    None if it is none of these, or names a moment not after ``now``."""
    import re
    import time
    from datetime import datetime, timedelta
    now = time.time() if now is None else now
    if not isinstance(text, str) or not text.strip():
        return None
    text = text.strip()
    if text.startswith("+"):
        seconds = _duration_seconds(text[1:])
        return now + seconds if seconds else None
    clock = re.fullmatch(r"(\d{1,2}):(\d{2})(?::(\d{2}))?", text)
    if clock:
        hour, minute, second = int(clock[1]), int(clock[2]), int(clock[3] or 0)
        if hour > 23 or minute > 59 or second > 59:
            return None
        today = datetime.fromtimestamp(now).astimezone()
        moment = today.replace(hour=hour, minute=minute, second=second, microsecond=0)
        if moment.timestamp() <= now:
            moment += timedelta(days=1)
        return moment.timestamp()
    try:
        moment = datetime.fromisoformat(text)
    except ValueError:
        return None
    moment = moment if moment.tzinfo else moment.astimezone()  # a naive time is local
    return moment.timestamp() if moment.timestamp() > now else None


# a run inside a batch job pauses this long before the job's walltime unless the cluster table says
# (stop_before_walltime): the current chunk, the checkpoint and the worker's shutdown must fit in it
DEFAULT_STOP_BEFORE_WALLTIME = 300.0


JOB_END_ENV, STOP_MARGIN_ENV = "FVDEM_JOB_END", "FVDEM_STOP_MARGIN"


def job_deadline(environ=None) -> float | None:
    """When a run in this process must have paused (epoch seconds): the job's end less the margin, both
    exported by the job script's prologue (``jobqueue_options``); None outside such a job."""
    environ = os.environ if environ is None else environ
    try:
        return float(environ[JOB_END_ENV]) - float(environ.get(STOP_MARGIN_ENV, DEFAULT_STOP_BEFORE_WALLTIME))
    except (KeyError, ValueError):
        return None


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


# Dask's own monitoring at its defaults costs a study of CPU-bound runs about a tenth of a core (the event loop's
# tick every 20 ms, the system monitor every 0.5 s, each worker's statistical profiler sampling its running
# task every 10 ms; a GIL monitor where gilknocker is installed): measured with two workers holding sleeping
# tasks, 4.8-6.2 % of a core in the client's process and 3.6-5.0 % in each worker, against 1.5-1.7 % and
# 0.7 % with these (``tools/bench_study_overhead.py``, docs/benchmarks.md). The dashboard stays; its
# profile page and system plots go quiet. Where the user's Dask configuration (YAML, DASK_* variable) sets one
# of these keys to other than Dask's default, the user's value is kept (``quiet_dask``).
QUIET_DASK = {"distributed.admin.tick.interval": "1s", "distributed.admin.system-monitor.interval": "5s",
              "distributed.admin.system-monitor.gil.enabled": False, "distributed.worker.profile.enabled": False}


def quiet_dask() -> dict:
    """The settings of ``QUIET_DASK`` whose keys the Dask configuration in force leaves at Dask's defaults and
    no ``DASK_*`` environment variable sets (``DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=True`` keeps the
    workers' profiler, even though True is Dask's default)."""
    import dask
    import distributed  # noqa: F401  (registers its configuration's defaults, which the keys below are)
    defaults = dask.config.merge(*dask.config.defaults)
    quiet = {}
    for key, value in QUIET_DASK.items():
        default = dask.config.get(key, default=None, config=defaults)
        if default is not None and dask.config.get(key, default=None) == default and _env_name(key) not in os.environ:
            quiet[key] = value
    return quiet


def _env_name(key: str) -> str:
    """A Dask configuration key as its ``DASK_*`` environment variable (``a.b-c.d`` -> ``DASK_A__B_C__D``)."""
    return "DASK_" + "__".join(part.replace("-", "_").upper() for part in key.split("."))


def worker_count(cluster: dict | None, workers: int | None, threads: int) -> int:
    """How many workers (LocalCluster processes, or dask-jobqueue jobs at most) a client made by ``make_client``
    has: ``--workers``, else the ``[cluster]`` table's ``workers``, else the cores over the run's threads."""
    return workers or (cluster or {}).get("workers") or max(1, (os.cpu_count() or 1) // max(1, threads))


def make_client(cluster: dict | None, scheduler: str | None, workers: int | None, threads: int):
    """A Dask client: on ``scheduler``, on a dask-jobqueue ``cluster`` table (a study's ``[cluster]``), or on
    a LocalCluster of ``workers`` processes (default: cores / threads). Returns ``(client, description)``."""
    try:
        import dask
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
    count = worker_count(cluster, workers, threads)
    if kind == "local":
        # Ctrl-C on a terminal signals the whole process group: the local workers ignore SIGINT (set
        # while they are spawned, and again by a plugin on any worker that replaces one), so that the
        # study's own handler stops the runs with checkpoints instead of the workers dying mid-run
        previous = signal.getsignal(signal.SIGINT) if threading.current_thread() is threading.main_thread() else None
        if previous is not None:
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            with dask.config.set(quiet_dask()):  # the scheduler reads it now, each nanny keeps a copy for its worker
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
        job_options = jobqueue_options(kind, options, threads)  # before the scheduler's settings below
        with dask.config.set(quiet_dask()):  # its scheduler, in this process
            jobs = getattr(dask_jobqueue, cluster_class)(**job_options)
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
    # the workers start on the nodes from the job script: Dask's monitoring is quieted there by its variables
    options["job_script_prologue"] = [*options.get("job_script_prologue", []),
                                      *(f"export {_env_name(k)}={v}" for k, v in quiet_dask().items())]
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
