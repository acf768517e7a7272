"""The contact settings, decided (issue 66, item 3): fvdem's defaults against Mema et al.'s own contact stiffness
and steps, per shape at 2.0 Umf, from the committed archives of the paper's study (the defaults' replicas) and of
``studies/contact_paper.toml`` (the paper's settings), by the rule ``fvdem.reports.mema2020.readings.contact_settings``
(fixed before the runs it judges); and where they differ, the cheaper candidates of
``studies/contact_candidates.toml`` against both, and the settings the defaults move to, by
``readings.contact_candidates`` (fixed before its runs).

    python tools/contact_decision.py --archives docs/data/mema2020 docs/data/contact_paper \
        docs/data/contact_candidates --json

Each archive's report is rebuilt in a scratch copy first (its table with the entropy columns); ``--quick`` reads
the archives' committed tables as they are. Without ``--archives``, the committed archives of both studies that
exist. The last line is one JSON object: per shape, each measure's means at both settings, their runs and order,
and the verdict; under ``candidates``, per shape each candidate's verdict and the ``choice``."""
from __future__ import annotations

import argparse
import json
import shutil
import tempfile
from pathlib import Path

from fvdem.study import report
from fvdem.study.records import folder_case
from fvdem.reports.mema2020.readings import contact_candidates, contact_settings

ROOT = Path(__file__).resolve().parents[1]
ARCHIVES = tuple(ROOT / "docs" / "data" / name for name in ("mema2020", "contact_paper", "contact_candidates"))


def table_rows(archive: Path, rebuild: bool = True) -> list:
    """The table rows of an archive (its report rebuilt in a scratch copy, else its committed table), the runs it
    plans, each with its ``gas.u_over_umf`` (``with_velocity``)."""
    if not rebuild:
        rows = json.loads((archive / "table.json").read_text())
    else:
        with tempfile.TemporaryDirectory() as scratch:
            copy = Path(scratch) / archive.name
            shutil.copytree(archive, copy)
            report(copy)
            rows = json.loads((copy / "table.json").read_text())
    return [with_velocity(archive, r) for r in rows if r["status"] != "not planned"]


def with_velocity(archive: Path, row: dict) -> dict:
    """``row`` with ``gas.u_over_umf``: a study's table has a column only for the keys it sweeps, so a family at
    its case's own velocity (``studies/contact_paper.toml``) takes it from the run's archived case.toml; a run
    not begun (no case.toml) has none."""
    case = None if "gas.u_over_umf" in row else folder_case(archive / "runs" / row["name"])
    return row if case is None else {**row, "gas.u_over_umf": case.gas.u_over_umf}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--archives", nargs="+", type=Path,
                        help="study archives (fvdem study DIR --archive) holding the settings' runs (default: the "
                             "committed docs/data/mema2020, contact_paper and contact_candidates, those that exist)")
    parser.add_argument("--quick", action="store_true", help="read the archives' committed tables, no rebuild")
    parser.add_argument("--velocity", type=float, default=2.0, help="U/Umf of the comparison (default 2.0)")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    args = parser.parse_args(argv)
    archives = args.archives or [a for a in ARCHIVES if (a / "study.json").exists()]
    missing = [str(a) for a in archives if not (a / "study.json").exists()]
    if missing:
        parser.exit(2, f"--archives: {', '.join(missing)}: not a study archive (no study.json)\n")
    rows = [r for archive in archives for r in table_rows(archive, rebuild=not args.quick)]
    result = contact_settings(rows, args.velocity)
    result["candidates"] = contact_candidates(rows, args.velocity)
    if not args.json:
        for shape, entry in result["shapes"].items():
            print(f"{shape}: {entry['verdict']}; t95 {entry['t95']['paper']} (paper's settings) against "
                  f"{entry['t95']['defaults']} (defaults), {entry['t95']['order']}")
            chosen = result["candidates"]["shapes"][shape]
            for family, c in chosen["candidates"].items():
                print(f"  {family}: {c['verdict']}; t95 {c['t95']['candidate']} ({c['t95']['runs']} runs), "
                      f"{c['cost']} CPU s per simulated s")
            print(f"  the defaults move to: {chosen['choice'] or 'not decided yet'}")
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
