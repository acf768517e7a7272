"""A study folder's bed and run folders against the study as it now stands. A folder started under another
definition (a family's setting changed in the study file since) would be resumed into a refusal, or, at its
end, skipped and reported as a run of the new definition; ``changed_folders`` names each such folder with the
keys that differ before anything runs, and ``supersede`` (``fvdem study --supersede``) moves them aside to
``OUT/superseded/``, so that their runs start again under the new case. A run taken out of the study file
after it began (a replica or point removed) keeps its folder and its entry in the index, flagged not planned
(``write_index``); ``unplanned_folders`` names those that have not ended, and ``--supersede`` moves them aside
too. Nothing is deleted."""
from __future__ import annotations

import json
import shutil
from datetime import datetime, timezone
from pathlib import Path

from ..case import load_case
from ..io.run_folder import physics_changes, physics_fingerprint
from .records import RunState, classify_run, entry_folder
from .specs import BED_STATE, BedSpec

SUPERSEDED = "superseded"  # in a study folder or its archive: folders of an older definition of a run


def folder_physics(folder) -> str | None:
    """The ``physics_fingerprint`` of a run or bed folder's ``case.toml`` (None without one)."""
    path = Path(folder) / "case.toml"
    return physics_fingerprint(path.read_text(), BED_STATE) if path.exists() else None


def changed_folders(study) -> list:
    """``(spec, changes)`` for each bed and run of ``study`` whose folder was started with other physics than the
    study now sets (``changes``: the keys, before -> now); a run whose bed is listed is listed as well (it would
    start from another state), with "its bed <name> changed" where its own case did not."""
    changed = []
    for spec in (*study.beds, *study.runs):
        held = folder_physics(spec.folder)
        if held is not None and held != spec.physics:
            keys = physics_changes(load_case(spec.case, dict(spec.overrides)), spec.folder, also_safe=BED_STATE)
            changed.append((spec, keys))
    beds = {spec.name for spec, _ in changed if isinstance(spec, BedSpec)}
    listed = {spec.name for spec, _ in changed}
    changed += [(run, f"its bed {run.bed} changed") for run in study.runs
                if run.bed in beds and run.name not in listed and Path(run.folder, "case.toml").exists()]
    return changed


def unplanned_folders(study, out) -> list:
    """``(name, folder)`` of each run ``out/study.json`` lists that ``study`` no longer plans (neither among its
    runs nor those ``--only`` left out), whose folder holds something and which has not ended (an ended run is a
    result: it stays). The runner never starts these; ``supersede`` (with ``keys`` None) moves them aside."""
    index_path = Path(out) / "study.json"
    if not index_path.exists():
        return []
    index = json.loads(index_path.read_text())
    planned = {r.name for r in (*study.runs, *study.left_out)}
    found = []
    for entry in index.get("runs", []):
        folder = entry_folder(out, entry) if entry.get("folder") else None
        if entry["name"] in planned or folder is None or not folder.is_dir():
            continue
        state = classify_run(folder, {**entry, "planned": False})
        if state not in (RunState.ENDED, RunState.RUNNING):
            found.append((entry["name"], str(folder)))
    return found


def supersede(out, moves, by: str) -> list:
    """Move each ``(name, folder, keys)`` of ``moves`` to ``out/superseded/<name>`` (``<name>-2``, ... if taken),
    with a ``SUPERSEDED.txt`` saying when, why (``keys``: what changed; None: the study file no longer lists the
    run) and by what (``by``: the code's provenance); their records leave ``out/study.json``, so that the study
    lists them pending (or not at all, where it no longer plans them). Returns the new places."""
    out = Path(out)
    moved = []
    for name, folder, keys in moves:
        dest = _free(out / SUPERSEDED / name)
        dest.parent.mkdir(parents=True, exist_ok=True)
        shutil.move(folder, dest)
        why = (f"the study file no longer lists run {name} and it had not ended; the study does not run it"
               if keys is None else
               f"the study now sets other physics for run {name} ({keys}); the study runs it again under its new case")
        (dest / "SUPERSEDED.txt").write_text(
            f"{folder} moved here on {datetime.now(timezone.utc).isoformat(timespec='seconds')} by {by}: {why}\n")
        moved.append(dest)
    index = out / "study.json"
    if moved and index.exists():
        names = {name for name, _, _ in moves}
        record = json.loads(index.read_text())
        record["runs"] = [r for r in record.get("runs", []) if r.get("name") not in names]
        index.write_text(json.dumps(record, indent=1) + "\n")
    return moved


def _free(path: Path) -> Path:
    """``path``, or ``path-2``, ``path-3``, ... whichever does not exist yet."""
    k = 1
    candidate = path
    while candidate.exists():
        k += 1
        candidate = path.with_name(f"{path.name}-{k}")
    return candidate
