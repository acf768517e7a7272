"""What made a run: the fvdem version, the git commit of the source (when it is a git checkout), the
date, the host and its processor, the thread count and the versions of the libraries that compute (numpy, numba, FiPy).
``summary.json`` holds it under ``provenance``; the run's ``case.toml`` and ``run.log`` start with it.
"""
from __future__ import annotations

import datetime
import functools
import os
import platform
import subprocess
import sys
from pathlib import Path

from .version import __version__


@functools.lru_cache(maxsize=1)
def source_commit() -> str | None:
    """The git commit of fvdem's source tree (``<hash>`` or ``<hash>-dirty``), or None when fvdem is not
    run from a git checkout (an installed wheel) or git is missing."""
    source = Path(__file__).resolve().parent.parent
    if not (source / ".git").exists():
        return None
    try:
        commit = subprocess.run(["git", "-C", str(source), "rev-parse", "HEAD"], capture_output=True, text=True,
                                timeout=10)
        if commit.returncode != 0:
            return None
        dirty = subprocess.run(["git", "-C", str(source), "status", "--porcelain", "--untracked-files=no", "--",
                                "fvdem"], capture_output=True, text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return commit.stdout.strip() + ("-dirty" if dirty.returncode == 0 and dirty.stdout.strip() else "")


@functools.lru_cache(maxsize=1)
def library_versions() -> dict:
    import numba
    import numpy
    try:
        from importlib.metadata import version
        fipy = version("fipy")
    except Exception:  # noqa: BLE001  (metadata missing: an unusual install)
        fipy = None
    return {"python": platform.python_version(), "numpy": numpy.__version__, "numba": numba.__version__,
            "fipy": fipy}


@functools.lru_cache(maxsize=1)
def cpu_model(cpuinfo: str = "/proc/cpuinfo") -> str | None:
    """The processor a run's CPU seconds were spent on, e.g. ``AMD EPYC (family 26, model 2), 2 CPUs``: the
    first processor's ``model name``, ``cpu family`` and ``model`` from Linux's ``cpuinfo`` (a virtual machine's
    model name often leaves the generation out: the family tells Zen 1 (23) from Zen 5 (26)), and the CPUs this
    process may use; ``platform.processor()`` elsewhere. None when nothing says. The same run costs 2-3 times
    more CPU seconds on one machine than another (docs/studies.md), so a cost figure needs it beside it."""
    fields = {}
    try:
        for line in Path(cpuinfo).read_text(errors="replace").splitlines():
            if not line.strip():
                if fields:
                    break  # the first processor's block is enough
                continue
            key, _, value = line.partition(":")
            fields.setdefault(key.strip(), value.strip())
    except OSError:
        pass
    name = fields.get("model name") or platform.processor() or None
    if name is None:
        return None
    if fields.get("cpu family") and fields.get("model"):
        name += f" (family {fields['cpu family']}, model {fields['model']})"
    try:
        cpus = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cpus = os.cpu_count()
    return name + (f", {cpus} CPUs" if cpus else "")


# the processor of a run whose summary does not name one (made before fvdem recorded it, 2026-12-06)
UNRECORDED_CPU = "not recorded"


def processor_of(summary: dict) -> str:
    """The processor a run's ``summary.json`` says its CPU seconds were spent on (``provenance.cpu``), or
    ``UNRECORDED_CPU``."""
    return (summary.get("provenance") or {}).get("cpu") or UNRECORDED_CPU


def provenance(threads: int | None = None) -> dict:
    """``{"fvdem", "commit", "date" (UTC, ISO 8601), "host", "cpu" (``cpu_model``), "threads", "python",
    "numpy", "numba", "fipy", "command"}`` of this process now."""
    return {"fvdem": __version__, "commit": source_commit(),
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "host": platform.node(), "cpu": cpu_model(), "threads": threads, **library_versions(),
            "command": " ".join(Path(sys.argv[0]).name if i == 0 else a for i, a in enumerate(sys.argv)) or None}


def peak_memory_mb() -> float:
    """This process's peak resident memory so far [MB] (a study worker's: its largest run's)."""
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def describe(record: dict) -> str:
    """One line: ``fvdem 0.2.0 (commit abc123), 2026-12-02T20:00:00+00:00 on host (AMD EPYC (family 26, model 2),
    2 CPUs), 2 thread(s); numba ...`` (a record written before fvdem recorded the processor has no brackets)."""
    commit = f" (commit {record['commit']})" if record.get("commit") else ""
    cpu = f" ({record['cpu']})" if record.get("cpu") else ""
    threads = f", {record['threads']} thread(s)" if record.get("threads") is not None else ""
    return (f"fvdem {record['fvdem']}{commit}, {record['date']} on {record['host']}{cpu}{threads}; "
            f"python {record['python']}, numpy {record['numpy']}, numba {record['numba']}, FiPy {record['fipy']}")
