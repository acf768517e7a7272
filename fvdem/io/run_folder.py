"""A run's output folder: created without replacing results, resumed only with the same physics, and
the writers that fill it (VTU/PVD snapshots, checkpoint, final state, summary).

Files: ``case.toml`` (the resolved case), ``timeseries.csv``, ``particles.pvd`` / ``gas.pvd`` with
their ``*.vtu``, ``checkpoint.npz`` (replaced atomically), ``final_state.npz`` and ``summary.json``.
"""
from __future__ import annotations

import functools
import json
import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..case import Case, to_toml
from ..errors import OutputError  # noqa: F401  (re-exported: fvdem.io.run_folder.OutputError)
from .checkpoint import save_checkpoint
from .vtk import write_gas_vtu, write_particles_vtu, write_pvd
from .locks import LOCK_FILE

CHECKPOINT = "checkpoint.npz"
FINAL_STATE = "final_state.npz"

# keys a resumed run may change: when it ends, what it writes and how it runs; all else is its physics
# (the pressure preconditioner changes how the pressure correction reaches its tolerance, not the tolerance;
# the corrector tolerance moves only the intermediate PISO correctors, the fields by ~1e-8 relative, while the
# last corrector keeps linear_tolerance)
RESUME_SAFE = ("name", "description", "time.end", "time.stop_when_settled", "time.settled_speed", "time.min_time",
               "time.stop_after_mixed",
               "output.", "run.", "gas.pressure_preconditioner", "gas.corrector_tolerance")


@dataclass
class Schedule:
    """A writer's schedule: every ``every`` loop steps."""

    every: int  # loop steps

    def due(self, step: int) -> bool:
        return step % self.every == 0

    def next_after(self, step: int) -> int:
        return (step // self.every + 1) * self.every


@dataclass
class RunState:
    """What the writers carry over a run (saved in checkpoints)."""
    snapshots: dict = field(default_factory=dict)  # collection -> [(time, file)]
    histories: dict = field(default_factory=dict)  # observable name -> its history
    wall_seconds: float = 0.0
    cpu_seconds: float = 0.0
    ended: str = ""  # why the run ended before its end time: a scene's end test ("settled", "mixed"), else ""
    timings: dict = field(default_factory=dict)  # phase -> seconds (fvdem.timing)

    @classmethod
    def from_checkpoint(cls, meta: dict, histories: dict) -> "RunState":
        """The state saved in a checkpoint; ``histories``: the scene's empty ones, for any it lacks."""
        meta = upgrade_writer_state(meta)
        return cls(snapshots=meta.pop("snapshots", {}), histories={**histories, **meta.pop("histories", {})}, **meta)


def prepare_output(out_dir, overwrite: bool = False, resume: bool = False) -> Path:
    """Create the output folder; never replace results unless ``overwrite`` (the folder's lock file,
    ``fvdem.io.locks``, is not a result: it stays)."""
    out = Path(out_dir)
    try:
        if resume:
            if not (out / CHECKPOINT).exists():
                raise OutputError(f"--resume: {out} holds no {CHECKPOINT} to resume from")
            return out
        held = [p for p in out.iterdir() if p.name != LOCK_FILE] if out.exists() else []
        if held:
            if not overwrite:
                raise OutputError(f"output folder {out} exists and is not empty; pass --overwrite to replace it "
                                  "or --resume to continue its run")
            for path in held:  # the folder's lock (its writer's, this process's) stays
                shutil.rmtree(path) if path.is_dir() and not path.is_symlink() else path.unlink()
        out.mkdir(parents=True, exist_ok=True)
        return out
    except OSError as exc:
        raise OutputError(f"output folder {out}: {exc.strerror or exc}"
                          + (f" ({exc.filename})" if exc.filename and str(exc.filename) != str(out) else "")) from None


def open_output(out_dir, case: Case, overwrite: bool = False, resume: bool = False) -> Path:
    """``prepare_output``, and a folder to resume checked against ``case`` (``check_resumable``)."""
    out = prepare_output(out_dir, overwrite, resume)
    if resume:
        check_resumable(case, out)
    return out


def guarded_write(write, args, time: float, out: Path) -> None:
    """Run a writer of a run at ``time`` [s] into ``out``; a full disk or an unwritable folder stops the run with
    ``OutputError`` (the checkpoint is replaced atomically, so the last complete one stays intact)."""
    try:
        write(*args)
    except OSError as exc:
        where = f" ({exc.filename})" if getattr(exc, "filename", None) else ""
        raise OutputError(
            f"writing the output failed at t = {time:.6g} s{where}: {exc.strerror or exc}; the last "
            f"complete checkpoint in {out} is intact: free space or fix the folder's permissions, then "
            "continue with --resume") from None


def check_resumable(case: Case, out: Path) -> None:
    """Refuse to resume ``out`` with a case whose physics differs from the one it was started with
    (its ``case.toml``), naming every key that differs; end time, output and run settings may change."""
    changed = physics_changes(case, out)
    if changed:
        raise OutputError(f"--resume: the case differs from the one {out} was started with in {changed}. A resumed "
                          "run continues the same physics; change only time.end, output.*, run.*, "
                          "gas.pressure_preconditioner or gas.corrector_tolerance, or start a new run folder")


def physics_changes(case: Case, out: Path, also_safe=()) -> str:
    """The keys (with their values before and now) in which ``case`` differs from the ``case.toml`` of run folder
    ``out`` beyond ``RESUME_SAFE`` and ``also_safe``; "" where they agree or ``out`` has no case.toml."""
    import tomllib
    path = Path(out) / "case.toml"
    if not path.exists():
        return ""
    try:
        before = path.read_text()
        return case_text_changes(before, to_toml(case), also_safe)
    except (OSError, tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise OutputError(f"{path} cannot be read ({exc}); it records the case the run was started with")


def case_text_changes(before: str, now: str, also_safe=()) -> str:
    """The physics keys (``physics_items``) in which two case files' texts differ, with their values before and
    now ("key: before -> now; ..."); "" where they agree."""
    before, now = physics_items(before, also_safe), physics_items(now, also_safe)
    changed = [key for key in sorted(set(before) | set(now)) if before.get(key) != now.get(key)]
    return "; ".join(f"{k}: {before.get(k, '(unset)')!r} -> {now.get(k, '(unset)')!r}" for k in changed)


def physics_items(toml_text: str, also_safe=()) -> dict:
    """A case file's physics: its keys (dotted, flattened) and values beyond ``RESUME_SAFE`` and ``also_safe``
    (a key, or a prefix ending in "."): what a resumed run keeps. A key the file lacks is taken at its default:
    a ``case.toml`` written by an older fvdem, before the key existed, ran as its default runs (a default
    changed since shows: the older file holds the old value)."""
    import tomllib
    flat = {**_default_case_items(), **_flatten(tomllib.loads(toml_text))}
    return {key: value for key, value in flat.items()
            if not any(key == safe or (safe.endswith(".") and key.startswith(safe))
                       for safe in (*RESUME_SAFE, *also_safe))}


@functools.lru_cache(maxsize=1)
def _default_case_items() -> dict:
    """Every key of the default case (``Case()``) with its value, flattened (read-only: shared)."""
    import tomllib
    return _flatten(tomllib.loads(to_toml(Case())))


def physics_fingerprint(toml_text: str, also_safe=()) -> str:
    """A short hash of ``physics_items``: equal for two case files exactly when their physics agree (a study
    records it per run, so that its archive can tell a run of an older definition)."""
    import hashlib
    items = json.dumps(sorted(physics_items(toml_text, also_safe).items()), default=repr)
    return hashlib.sha256(items.encode()).hexdigest()[:16]


def _flatten(table, prefix=""):
    flat = {}
    for key, value in table.items():
        if isinstance(value, dict):
            flat.update(_flatten(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat


def write_snapshot(out: Path, model, entries: dict) -> None:
    """VTU snapshots of the particles and the gas, listed in ``particles.pvd`` / ``gas.pvd``;
    ``entries`` holds the (time, file) rows of each collection (kept in the checkpoint)."""
    if model.dem is not None:
        rows = entries.setdefault("particles", [])
        name = f"particles_{len(rows):05d}.vtu"
        write_particles_vtu(out / name, model.particles)
        rows.append((model.time, name))
        write_pvd(out / "particles.pvd", rows)
    if model.gas is not None:
        rows = entries.setdefault("gas", [])
        name = f"gas_{len(rows):05d}.vtu"
        write_gas_vtu(out / name, model.gas)
        rows.append((model.time, name))
        write_pvd(out / "gas.pvd", rows)


def write_checkpoint(out: Path, model, meta: dict) -> None:
    save_checkpoint(out / CHECKPOINT, model.state(), meta)


def write_text_atomic(path, text: str) -> None:
    """``path``'s text replaced at once (a temporary file renamed over it): a reader polling it while it is
    written (``fvdem study --status``, a study's progress, ``--report`` while a study runs) sees the old
    text or the new, never half of one."""
    path = Path(path)
    tmp = path.with_name(path.name + f".{os.getpid()}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def write_final(out: Path, particles, summary: dict) -> None:
    """``final_state.npz`` (the particles in id order, written atomically) and ``summary.json``."""
    if particles is not None:
        order = np.argsort(particles.ids, kind="stable")
        tmp = out / (FINAL_STATE + ".tmp")
        with open(tmp, "wb") as fh:
            np.savez(fh, **{k: v[order] for k, v in particles.as_dict().items()})
        os.replace(tmp, out / FINAL_STATE)
    write_text_atomic(out / "summary.json", json.dumps(summary, indent=2) + "\n")


# checkpoints written before the scenes (up to b38a3bd) kept each history under its own key
_FORMER = {"pvd_entries": ("snapshots", "particles"), "gas_pvd_entries": ("snapshots", "gas"),
           "pressure_history": ("histories", "bed_pressure"), "mixing_history": ("histories", "mixing")}


def upgrade_writer_state(meta: dict) -> dict:
    """A checkpoint's writer state in today's form (``snapshots`` and ``histories`` by name)."""
    meta = dict(meta)
    tables = {"snapshots": dict(meta.pop("snapshots", {})), "histories": dict(meta.pop("histories", {}))}
    for old, (table, name) in _FORMER.items():
        if old in meta:
            tables[table][name] = meta.pop(old)
    if "settled" in meta:  # before the scenes' end tests (0.2.0): a bed at rest was the only early end
        meta["ended"] = "settled" if meta.pop("settled") else ""
    samples, orientations = meta.pop("suspension_history", None), meta.pop("orientation_history", [])
    if samples:
        tables["histories"]["suspension"] = {"samples": samples, "orientations": orientations}
    return {**meta, **tables}
