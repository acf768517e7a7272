"""The outputs every case in ``cases/`` writes, shrunk to seconds of work: ``timeseries.csv``'s columns
and ``summary.json``'s keys (nested tables as ``table.key``).

``python tests/output_keys.py`` records them in ``tests/data/output_keys.json``;
``tests/regression/test_output_keys.py`` compares a fresh run against that record, so a restructuring that loses
or renames an output fails. Record again only for an intended change (and say so in CHANGELOG.md).
"""
from __future__ import annotations

import json
import sys
import tomllib
from pathlib import Path

from paths import DATA, ROOT

RECORD = DATA / "output_keys.json"
CASES = sorted(p.stem for p in (ROOT / "cases").glob("*.toml"))
SAMPLES = 24  # timeseries rows: more than the 20 a suspension summary needs


def shrunk_table(name: str) -> dict:
    """The case's table with few particles (inserted, not loaded), and a few dozen output samples."""
    table = tomllib.loads((ROOT / "cases" / f"{name}.toml").read_text())
    particles = table.setdefault("particles", {})
    particles.pop("initial_state", None)
    if not table.get("suspension", {}).get("enabled", False) and particles.get("count", 1000) > 0:
        particles["count"] = 120
    return table


def case_of(name: str):
    from fvdem.case import case_from_dict
    case = case_from_dict(shrunk_table(name), str(ROOT / "cases" / f"{name}.toml"))
    coupled_or_gas = case.gas.enabled and (case.particles.count == 0 or case.coupling.enabled
                                             or case.particles.fixed)
    step = case.gas.cfd_step if coupled_or_gas else case.time.dem_step
    overrides = {"time.end": SAMPLES * step, "output.timeseries_interval": step,
                 "output.snapshot_interval": 8 * step, "output.checkpoint_interval": 8 * step,
                 "output.progress": False, "time.stop_when_settled": False}
    return case_from_dict(shrunk_table(name), str(ROOT / "cases" / f"{name}.toml"), overrides)


def flat_keys(table: dict, prefix: str = "") -> list:
    keys = []
    for key, value in table.items():
        keys.append(prefix + key)
        if isinstance(value, dict):
            keys += flat_keys(value, f"{prefix}{key}.")
    return keys


def outputs(name: str, out: Path) -> dict:
    import fvdem
    fvdem.Simulation(case_of(name), out, threads=1).run()
    header = (out / "timeseries.csv").read_text().splitlines()[0]
    return {"timeseries": header.split(","), "summary": flat_keys(json.loads((out / "summary.json").read_text()))}


def main() -> int:
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        record = {name: outputs(name, Path(tmp) / name) for name in CASES}
    RECORD.write_text(json.dumps(record, indent=1) + "\n")
    print(RECORD)
    return 0


if __name__ == "__main__":
    sys.exit(main())
