"""One study family against another, column by column: each side's mean, SD and runs, and their difference with
its 95 % interval (Welch's t), from committed study archives (``fvdem study DIR --archive``): a variant of a model
against the replicas of its baseline, the way the stochastic force's bed runs are reported against the defaults'
(docs/validation-suspension.md, "In the gas-fluidized bed").

    python tools/compare_families.py          # that comparison: docs/data/stochastic_bed against docs/data/mema2020
    python tools/compare_families.py --variant docs/data/contact_paper:ar1_paper \\
        --baseline docs/data/mema2020:ar1,ar1_t95 --velocity 2.0 --columns t95 mixing_entropy_at_4

Each side is ``ARCHIVE:FAMILY[,FAMILY...]``; a run counts where it has ended (``RunState.ENDED``) and has the column; ``--velocity``
keeps a family's runs at that U/Umf (a family at its case's own velocity takes it from the run's archived
case.toml). A run not mixed by its end has no t95 and is left out of the t95 row, which says how many were. The
archives' committed tables are read as they are. The last line is one JSON object."""
from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

from scipy import stats

from contact_decision import with_velocity  # tools/, beside this script
from fvdem.study.records import RunState, state_of


ROOT = Path(__file__).resolve().parents[1]
DEFAULT = {"variant": str(ROOT / "docs" / "data" / "stochastic_bed") + ":ar1_force",
           "baseline": str(ROOT / "docs" / "data" / "mema2020") + ":ar1,ar1_t95", "velocity": 2.0,
           "columns": ["t95", "mixing_entropy_at_2", "mixing_entropy_at_4", "mixing_entropy_at_6",
                       "mixing_entropy_window", "dense_bed_expansion", "pressure_drop_std_over_weight", "overlap_p99"]}


def side_rows(spec: str, velocity=None) -> tuple:
    """``(label, rows)`` of ``ARCHIVE:FAMILY[,FAMILY...]``: the table rows of those families' ended runs (at
    ``velocity`` where given)."""
    if ":" not in spec:
        raise ValueError(f"{spec!r}: give ARCHIVE:FAMILY[,FAMILY...]")
    archive, families = spec.rsplit(":", 1)
    archive = Path(archive)
    if not (archive / "table.json").exists():
        raise ValueError(f"{archive}: not a study archive (no table.json)")
    names = families.split(",")
    rows = [r for r in json.loads((archive / "table.json").read_text())
            if r["family"] in names and state_of(r["status"]) == RunState.ENDED]
    if velocity is not None:
        rows = [r for r in rows if with_velocity(archive, r).get("gas.u_over_umf") == velocity]
    return f"{archive.name}:{families}", rows


def difference(a: list, b: list) -> dict:
    """Means, SDs and counts of ``a`` and ``b``, and ``mean(a) - mean(b)`` with its 95 % interval by Welch's t
    (None where a side has fewer than two values)."""
    out = {"variant": _summary(a), "baseline": _summary(b), "difference": None, "interval": None}
    if len(a) < 2 or len(b) < 2:
        if a and b:
            out["difference"] = out["variant"]["mean"] - out["baseline"]["mean"]
        return out
    va, vb = stats.tvar(a) / len(a), stats.tvar(b) / len(b)
    dof = (va + vb) ** 2 / (va ** 2 / (len(a) - 1) + vb ** 2 / (len(b) - 1)) if va + vb > 0 else float("inf")
    half = stats.t.ppf(0.975, dof) * math.sqrt(va + vb)
    d = out["variant"]["mean"] - out["baseline"]["mean"]
    out.update(difference=d, interval=[d - half, d + half])
    return out


def _summary(values: list) -> dict:
    n = len(values)
    return {"runs": n, "mean": sum(values) / n if n else None,
            "sd": math.sqrt(stats.tvar(values)) if n > 1 else None}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--variant", metavar="ARCHIVE:FAMILY[,FAMILY...]",
                        help=f"default: the stochastic force's bed runs, {DEFAULT['variant']}")
    parser.add_argument("--baseline", metavar="ARCHIVE:FAMILY[,FAMILY...]",
                        help=f"default: the defaults' replicas at 2.0 Umf, {DEFAULT['baseline']}")
    parser.add_argument("--velocity", type=float, help="keep the runs at this U/Umf (default with the default sides: 2.0)")
    parser.add_argument("--columns", nargs="+", help="table.json columns to compare (default: " +
                        " ".join(DEFAULT["columns"]) + ")")
    parser.add_argument("--quick", action="store_true", help="the same (the committed tables are read as they are; "
                                                             "nothing runs)")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    args = parser.parse_args(argv)
    if args.variant is None and args.baseline is None:
        args.variant, args.baseline = DEFAULT["variant"], DEFAULT["baseline"]
        args.velocity = DEFAULT["velocity"] if args.velocity is None else args.velocity
    if args.variant is None or args.baseline is None:
        parser.exit(2, "compare_families: give both --variant and --baseline, or neither (the default comparison)\n")
    args.columns = args.columns or DEFAULT["columns"]
    try:
        (label_a, rows_a), (label_b, rows_b) = (side_rows(s, args.velocity) for s in (args.variant, args.baseline))
    except ValueError as err:
        parser.exit(2, f"compare_families: {err}\n")
    unknown = [c for c in args.columns if rows_a + rows_b and not any(c in r for r in rows_a + rows_b)]
    if unknown:
        parser.exit(2, f"compare_families: --columns: {', '.join(unknown)}: not in either table\n")
    result = {"variant": label_a, "baseline": label_b, "velocity": args.velocity, "columns": {}}
    for column in args.columns:
        a = [r[column] for r in rows_a if r.get(column) is not None]
        b = [r[column] for r in rows_b if r.get(column) is not None]
        entry = difference(a, b)
        entry["left_out"] = [len(rows_a) - len(a), len(rows_b) - len(b)]
        result["columns"][column] = entry
        v, w = entry["variant"], entry["baseline"]

        def text(s):
            return "-" if s["mean"] is None else f"{s['mean']:.4g}" + (f" ± {s['sd']:.2g}" if s["sd"] else "") + \
                f" ({s['runs']})"
        interval = "" if entry["interval"] is None else " [{:+.3g}, {:+.3g}]".format(*entry["interval"])
        change = "" if entry["difference"] is None else f"; difference {entry['difference']:+.3g}{interval}"
        missing = "" if not any(entry["left_out"]) else f"; without a value: {entry['left_out'][0]} and {entry['left_out'][1]} run(s)"
        if not args.json:
            print(f"{column}: {text(v)} against {text(w)}{change}{missing}")
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
