"""Folder locks: one process at a time writes a run folder or runs a study folder.

Two ``fvdem run`` on one folder, or a second ``fvdem study`` started on a folder a study is running in (a
second terminal, a restarted campaign script), would write the same time series and checkpoints, and a
second start of a run with no checkpoint would even clear the folder under the first. Each writer holds an
advisory lock on ``LOCK_FILE`` inside its folder (``flock``; over NFS the kernel maps it to a POSIX lock, so
it holds between the nodes of a cluster too), taken before it touches anything and released by the kernel
whatever way the process ends (SIGKILL, a lost node's lease): a lock is never stale. The file also says who
holds it (process, host, since when, the command), for the refusal's message and ``fvdem study --status``.

Where ``fcntl`` does not exist (Windows), or the file system has no locks (NFS mounted ``nolock``: ENOLCK),
folders go unlocked.
"""
from __future__ import annotations

import contextlib
import datetime
import json
import os
import socket
import sys
import time
from pathlib import Path

from ..errors import OutputError

try:
    import fcntl
except ImportError:  # pragma: no cover  (Windows: no advisory locks, folders unlocked)
    fcntl = None

LOCK_FILE = ".fvdem.lock"  # in a run or study folder; not a result (an empty folder may hold it)

# s: how long a writer retries a held lock before it refuses; a probe (``holder``) holds a free lock for a few
# microseconds, so only a real writer outlasts this
RETRY_SECONDS = 0.5


class FolderInUse(OutputError):
    """A folder another process is writing (``holder``: what its lock file says of it)."""

    def __init__(self, folder, holder: dict, what: str):
        self.folder, self.holder = Path(folder), holder
        study = _study_of(self.folder, holder)
        stop = f"fvdem study {study} --stop, or " if study is not None else ""
        super().__init__(f"{what} {folder} is in use by {describe_holder(holder)}; wait for it to end or stop it "
                         f"({stop}SIGINT to process {holder.get('pid', '?')})")


def _study_of(folder: Path, record: dict) -> Path | None:
    """The study folder whose study holds ``folder`` (the study folder itself, or ``OUT/runs/<run>`` while a
    study runs in ``OUT``), or None."""
    if record.get("kind") == "study":
        return folder
    above = folder.parent.parent
    return above if (holder(above) or {}).get("kind") == "study" else None


def describe_holder(holder: dict) -> str:
    """``fvdem study ... (process 1234 on host since 2026-12-04T00:20:48+00:00)`` from a lock file's record."""
    where = ", ".join(x for x in (f"process {holder['pid']}" if holder.get("pid") else "",
                                  f"on {holder['host']}" if holder.get("host") else "",
                                  f"since {holder['since']}" if holder.get("since") else "") if x)
    return f"{holder.get('command') or 'another fvdem process'}" + (f" ({where})" if where else "")


# the folders this process holds locked (resolved path -> how many ``FolderLock`` hold it): a study's command
# line takes its folder's lock before it moves superseded folders, and ``run_study`` takes it again
_HELD: dict[str, int] = {}


class FolderLock:
    """The lock of one folder (created if missing). ``acquire`` takes it or raises ``FolderInUse``; ``release``
    gives it back; a context manager does both. ``kind`` ("run", "study") and ``details`` go into the lock
    file beside the process, host, time and command line. A process that holds a folder's lock may take it
    again (it is released when the last taker releases it)."""

    def __init__(self, folder, kind: str = "run", details: dict | None = None):
        self.folder, self.kind, self.details = Path(folder), kind, dict(details or {})
        self._file = None
        self._nested = False
        self._created = False

    @property
    def held(self) -> bool:
        return self._file is not None or self._nested

    def acquire(self, retry: float = RETRY_SECONDS) -> FolderLock:
        if self.held or fcntl is None:
            return self
        key = str(self.folder.resolve())
        if _HELD.get(key):
            _HELD[key] += 1
            self._nested = True
            return self
        try:
            self._created = not self.folder.exists()
            self.folder.mkdir(parents=True, exist_ok=True)
            handle = open(self.folder / LOCK_FILE, "a+")
        except OSError as exc:
            raise OutputError(f"{self.kind} folder {self.folder}: {exc.strerror or exc}") from None
        deadline = time.monotonic() + retry
        while True:
            try:
                fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
                break
            except BlockingIOError:
                if time.monotonic() >= deadline:
                    holder = _read(handle)
                    handle.close()
                    raise FolderInUse(self.folder, holder, f"{self.kind} folder") from None
                time.sleep(0.05)
            except OSError:  # a file system without locks (ENOLCK: NFS mounted nolock): the folder goes unlocked
                handle.close()
                return self
        handle.seek(0)
        handle.truncate()
        handle.write(json.dumps({"kind": self.kind, "pid": os.getpid(), "host": socket.gethostname(),
                                 "since": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                                 "command": _command(), **self.details}) + "\n")
        handle.flush()
        self._file = handle
        _HELD[key] = 1
        return self

    def release(self) -> None:
        key = str(self.folder.resolve())
        if self._nested:
            if _HELD.get(key):
                _HELD[key] -= 1
            self._nested = False
        elif self._file is not None:
            _HELD.pop(key, None)
            try:
                if self._created and [p.name for p in self.folder.iterdir()] == [LOCK_FILE]:
                    # a folder made for a writer that wrote nothing (a refused --resume, a bad case): not left
                    (self.folder / LOCK_FILE).unlink()
                    self.folder.rmdir()
                fcntl.flock(self._file.fileno(), fcntl.LOCK_UN)
            except OSError:
                pass
            finally:
                self._file.close()
                self._file = None

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *_) -> None:
        self.release()


def holder(folder) -> dict | None:
    """Who holds ``folder``'s lock now (its lock file's record, ``{}`` if unreadable), or None if nobody does
    (no lock file, or a free lock: a probe takes it for a few microseconds and gives it back)."""
    path = Path(folder) / LOCK_FILE
    if fcntl is None or not path.exists():
        return None
    try:
        handle = open(path, "a+")
    except OSError:
        return None
    with handle:
        try:
            fcntl.flock(handle.fileno(), fcntl.LOCK_SH | fcntl.LOCK_NB)
        except BlockingIOError:
            return _read(handle)
        except OSError:  # no locks on this file system: nobody can be seen
            return None
        fcntl.flock(handle.fileno(), fcntl.LOCK_UN)
        return None


def _read(handle) -> dict:
    try:
        handle.seek(0)
        return json.loads(handle.read() or "{}")
    except (OSError, ValueError):
        return {}


def _command() -> str:
    """This process's command line as typed (``fvdem study ...``, a worker's ``python -m ...``)."""
    name = Path(sys.argv[0]).name if sys.argv and sys.argv[0] else "python"
    line = " ".join([name, *sys.argv[1:]])
    return line if len(line) <= 300 else line[:297] + "..."


def folder_lock(folder, details: dict | None = None):
    """A run folder's ``FolderLock`` (``kind`` "run"), or a no-op context for a run without a folder (None)."""
    return contextlib.nullcontext() if folder is None else FolderLock(folder, "run", details)
