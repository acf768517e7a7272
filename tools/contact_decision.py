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
and the verdict; under ``candidates``, per shape each candidate's verdict and the ``choice``. ``--plot FILE.png``
draws each setting's mixing entropy against time at that velocity (mean and SD band over its ended runs, a run that
ended mixed held at its last value, as the window entropy counts it), one panel per shape."""
from __future__ import annotations

import argparse
import csv
import json
import shutil
import tempfile
from pathlib import Path

import numpy as np

from fvdem.analysis.plots import pyplot, save_figure
from fvdem.study import report
from fvdem.study.records import RunState, folder_case, state_of
from fvdem.reports.mema2020.families import T95_ONLY
from fvdem.reports.mema2020.readings import CANDIDATE, SHAPES, contact_candidates, contact_settings

ROOT = Path(__file__).resolve().parents[1]
ARCHIVES = tuple(ROOT / "docs" / "data" / name for name in ("mema2020", "contact_paper", "contact_candidates"))


def study_archives(given, defaults, parser, option: str = "--archives") -> list:
    """The archives a tool reads: those given, else the ``defaults`` that exist; any without a ``study.json`` is
    refused (exit 2) with the option that named it."""
    archives = list(given) if given else [a for a in defaults if (a / "study.json").exists()]
    missing = [str(a) for a in archives if not (a / "study.json").exists()]
    if missing:
        parser.exit(2, f"{option}: {', '.join(missing)}: not a study archive (no study.json)\n")
    return archives


def report_json(archive: Path, names: list, rebuild: bool = True) -> list:
    """The JSON files ``names`` of an archive's report (rebuilt in a scratch copy, else as committed), each parsed,
    None where the report has no such file."""
    def read(folder: Path) -> list:
        return [json.loads((folder / name).read_text()) if (folder / name).is_file() else None for name in names]
    if not rebuild:
        return read(archive)
    with tempfile.TemporaryDirectory() as scratch:
        copy = Path(scratch) / archive.name
        shutil.copytree(archive, copy)
        report(copy)
        return read(copy)


def planned_rows(archive: Path, rows: list) -> list:
    """An archive's table rows of the runs it plans, each with its ``gas.u_over_umf`` (``with_velocity``)."""
    if rows is None:
        raise FileNotFoundError(archive / "table.json")
    return [with_velocity(archive, r) for r in rows if r["status"] != "not planned"]


def table_rows(archive: Path, rebuild: bool = True) -> list:
    """The table rows of an archive (its report rebuilt in a scratch copy, else its committed table), the runs it
    plans, each with its ``gas.u_over_umf`` (``with_velocity``)."""
    return planned_rows(archive, report_json(archive, ["table.json"], rebuild)[0])


def with_velocity(archive: Path, row: dict) -> dict:
    """``row`` with ``gas.u_over_umf``: a study's table has a column only for the keys it sweeps, so a family at
    its case's own velocity (``studies/contact_paper.toml``) takes it from the run's archived case.toml; a run
    not begun (no case.toml) has none."""
    case = None if "gas.u_over_umf" in row else folder_case(archive / "runs" / row["name"])
    return row if case is None else {**row, "gas.u_over_umf": case.gas.u_over_umf}


TIMES = np.arange(0.0, 8.0 + 1e-9, 0.05)  # [s] the curves' common grid: the window entropy's 8 s


def entropy_curve(run: Path) -> np.ndarray | None:
    """A run's mixing entropy on ``TIMES`` from its archived timeseries.csv, held at its last value past its end
    (a run that ended mixed stays mixed); None without one."""
    path = run / "timeseries.csv"
    if not path.is_file():
        return None
    with path.open() as f:
        rows = [(float(r["time"]), float(r["mixing_entropy"])) for r in csv.DictReader(f) if r.get("mixing_entropy")]
    if not rows:
        return None
    t, s = np.array(rows).T
    return np.interp(TIMES, t, s)  # np.interp holds the end values beyond the last sample


def plot_curves(tables: dict, velocity: float, path: Path) -> Path:
    """Each setting's entropy against time at ``velocity`` per shape (the defaults' replicas, the paper's settings,
    each candidate): the mean over its ended runs and a band of one SD, the run count in the legend; ``tables``:
    each archive's table rows (``table_rows``)."""
    plt = pyplot()
    fig, axes = plt.subplots(1, len(SHAPES), figsize=(5.5 * len(SHAPES), 4.0), squeeze=False)
    rows = [r for table in tables.values() for r in table]
    where = {r["name"]: archive for archive, table in tables.items() for r in table}
    for ax, (shape, (defaults, paper)) in zip(axes[0], SHAPES.items()):
        families = {defaults: "defaults", paper: "paper's settings"}
        families.update({f: f.split(CANDIDATE, 1)[1] for f in sorted({r["family"] for r in rows})
                         if f.startswith(defaults + CANDIDATE)})
        for family, label in families.items():
            runs = [r for r in rows if r["family"] in (family, family + T95_ONLY)
                    and r.get("gas.u_over_umf") == velocity and state_of(r["status"]) is RunState.ENDED]
            curves = [c for c in (entropy_curve(where[r["name"]] / "runs" / r["name"]) for r in runs
                                  if r["name"] in where) if c is not None]
            if not curves:
                continue
            mean, sd = np.mean(curves, axis=0), np.std(curves, axis=0, ddof=1) if len(curves) > 1 else 0.0 * TIMES
            line, = ax.plot(TIMES, mean, label=f"{label} ({len(curves)} runs)")
            ax.fill_between(TIMES, mean - sd, mean + sd, color=line.get_color(), alpha=0.2, lw=0)
        ax.axhline(0.95, color="0.5", lw=0.8, ls=":")
        ax.set(title=f"{shape} at {velocity:g} Umf", xlabel="time [s]", ylabel="mixing entropy", ylim=(0.0, 1.02))
        ax.legend(fontsize=8, loc="lower right")
    return save_figure(fig, path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--archives", nargs="+", type=Path,
                        help="study archives (fvdem study DIR --archive) holding the settings' runs (default: the "
                             "committed docs/data/mema2020, contact_paper and contact_candidates, those that exist)")
    parser.add_argument("--quick", action="store_true", help="read the archives' committed tables, no rebuild")
    parser.add_argument("--velocity", type=float, default=2.0, help="U/Umf of the comparison (default 2.0)")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    parser.add_argument("--plot", type=Path, metavar="FILE.png",
                        help="draw each setting's mixing entropy against time (mean, SD band) to this PNG")
    args = parser.parse_args(argv)
    archives = study_archives(args.archives, ARCHIVES, parser)
    if args.plot is not None and (args.plot.suffix != ".png" or not args.plot.parent.is_dir()):
        parser.exit(2, f"--plot {args.plot}: give a .png file in an existing folder\n")
    tables = {archive: table_rows(archive, rebuild=not args.quick) for archive in archives}
    rows = [r for table in tables.values() for r in table]
    result = contact_settings(rows, args.velocity)
    result["candidates"] = contact_candidates(rows, args.velocity)
    if not args.json:
        for shape, entry in result["shapes"].items():
            print(f"{shape}: {entry['verdict']}" + (f" ({entry['why']})" if entry.get("why") else "")
                  + f"; t95 {entry['t95']['paper']} (paper's settings) against {entry['t95']['defaults']} "
                  f"(defaults), {entry['t95']['order']}")
            chosen = result["candidates"]["shapes"][shape]
            for family, c in chosen["candidates"].items():
                print(f"  {family}: {c['verdict']}; t95 {c['t95']['candidate']} ({c['t95']['runs']} runs), "
                      f"{c['cost']} CPU s per simulated s")
            print(f"  the defaults move to: {chosen['choice'] or 'not decided yet'}")
    if args.plot is not None:
        plot_curves(tables, args.velocity, args.plot)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
