"""What made a run: the fvdem version, the git commit of the source (when it is a git checkout), the
date, the host, the thread count and the versions of the libraries that compute (numpy, numba, FiPy).
``summary.json`` holds it under ``provenance``; the run's ``case.toml`` and ``run.log`` start with it.
"""
from __future__ import annotations

import datetime
import functools
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


def provenance(threads: int | None = None) -> dict:
    """``{"fvdem", "commit", "date" (UTC, ISO 8601), "host", "threads", "python", "numpy", "numba", "fipy",
    "command"}`` of this process now."""
    return {"fvdem": __version__, "commit": source_commit(),
            "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "host": platform.node(), "threads": threads, **library_versions(),
            "command": " ".join(Path(sys.argv[0]).name if i == 0 else a for i, a in enumerate(sys.argv)) or None}


def peak_memory_mb() -> float:
    """This process's peak resident memory so far [MB] (a study worker's: its largest run's)."""
    import resource
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def describe(record: dict) -> str:
    """One line: ``fvdem 0.2.0 (commit abc123), 2026-12-02T20:00:00+00:00 on host, 2 thread(s); numba ...``."""
    commit = f" (commit {record['commit']})" if record.get("commit") else ""
    threads = f", {record['threads']} thread(s)" if record.get("threads") is not None else ""
    return (f"fvdem {record['fvdem']}{commit}, {record['date']} on {record['host']}{threads}; "
            f"python {record['python']}, numpy {record['numpy']}, numba {record['numba']}, FiPy {record['fipy']}")
