"""Two study archives' findings side by side, old and new verdicts: the paper's study at stage 2 against its re-run
at the decided settings (stage 3), or any study's archive against a later one.

    python tools/compare_findings.py        # the paper's study: stage 2 against stage 3 (its archive once committed)
    python tools/compare_findings.py docs/data/mema2020 docs/data/mema2020_stage3 --labels "stage 2" "stage 3"
    python tools/compare_findings.py docs/data/mema2020.json NEW --out findings_side_by_side.md

Each side is a study archive or folder (its ``findings.json``, written by ``fvdem study --report``) or a results file
(``fvdem study --results``: its ``findings``). Findings are matched by their claim's words; a finding on one side
only shows "-" on the other. Prints a Markdown table (finding, which set of rules reads it, each side's verdict,
whether it changed) and, last, one JSON object (``--json``: that alone); ``--out`` also writes the table to a file.
Without the two sides: docs/data/mema2020 against docs/data/mema2020_stage3, or, until stage 3's archive is
committed, against the stage-2 results file (nothing changes: a check that the files read)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

DATA = Path(__file__).resolve().parents[1] / "docs" / "data"
STAGE3 = DATA / "mema2020_stage3"
DEFAULT = (DATA / "mema2020", STAGE3 if (STAGE3 / "findings.json").exists() else DATA / "mema2020.json")


def findings_of(path: Path) -> list:
    """The findings of an archive or study folder (``findings.json``) or of a results file (its ``findings``)."""
    source = path / "findings.json" if path.is_dir() else path
    if not source.is_file():
        raise ValueError(f"{path}: no findings.json there (write it with `fvdem study {path} --report`)"
                         if path.is_dir() else f"{path}: no such file or study folder")
    try:
        data = json.loads(source.read_text())
    except json.JSONDecodeError as error:
        raise ValueError(f"{source}: not JSON ({error.msg}, line {error.lineno})") from None
    findings = data.get("findings") if isinstance(data, dict) else data
    if not isinstance(findings, list) or not all(isinstance(f, dict) and "finding" in f and "verdict" in f
                                                 for f in findings):
        raise ValueError(f"{source}: holds no findings (a list of {{'finding', 'verdict', ...}})")
    return findings


def side_by_side(old: list, new: list) -> list:
    """One row per finding, in the old side's order then the new side's own: ``finding``, ``readings`` ("first" or
    "second" set of rules), ``old`` and ``new`` verdicts (None where a side lacks it), ``changed``."""
    def readings(f):
        return f.get("readings", "first")
    before = {f["finding"]: f for f in old}
    after = {f["finding"]: f for f in new}
    claims = list(before) + [c for c in after if c not in before]
    rows = []
    for claim in claims:
        a, b = before.get(claim), after.get(claim)
        rows.append({"finding": claim, "readings": readings(a or b), "old": a and a["verdict"],
                     "new": b and b["verdict"], "changed": bool(a and b and a["verdict"] != b["verdict"])})
    return rows


def table(rows: list, labels: tuple) -> str:
    """The rows as a Markdown table, with a line counting each side's verdicts."""
    lines = [f"| finding | rules | {labels[0]} | {labels[1]} | changed |", "|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['finding']} | {r['readings']} | {r['old'] or '-'} | {r['new'] or '-'} | "
                     f"{'yes' if r['changed'] else ''} |")
    for key, label in zip(("old", "new"), labels):
        verdicts = [r[key] for r in rows if r[key]]
        counts = ", ".join(f"{verdicts.count(v)} {v}" for v in ("holds", "does not hold", "open") if v in verdicts)
        lines.append(f"\n{label}: {len(verdicts)} findings: {counts or 'none'}.")
    changed = sum(r["changed"] for r in rows)
    lines.append(f"Changed: {changed} of {sum(bool(r['old'] and r['new']) for r in rows)} on both sides.")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", type=Path, nargs="?", default=DEFAULT[0],
                        help=f"archive, study folder or results file: the earlier verdicts (default {DEFAULT[0]})")
    parser.add_argument("new", type=Path, nargs="?", default=DEFAULT[1],
                        help=f"the same for the later verdicts (default {DEFAULT[1]})")
    parser.add_argument("--labels", nargs=2, metavar=("OLD", "NEW"),
                        help="the two columns' names (default: old, new; stage 2, stage 3 for the default sides)")
    parser.add_argument("--out", type=Path, help="also write the Markdown table here")
    parser.add_argument("--quick", action="store_true", help="the same (committed files are read; nothing runs)")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    args = parser.parse_args(argv)
    args.labels = args.labels or (("stage 2", "stage 3") if (args.old, args.new) == DEFAULT else ("old", "new"))
    try:
        rows = side_by_side(findings_of(args.old), findings_of(args.new))
    except ValueError as error:
        parser.exit(2, f"compare_findings.py: {error}\n")
    text = table(rows, tuple(args.labels))
    if not args.json:
        print(text)
    if args.out:
        if args.out.exists():
            parser.exit(2, f"compare_findings.py: --out {args.out}: exists (results are never overwritten; name "
                           "another file)\n")
        args.out.write_text(text)
    print(json.dumps({"labels": list(args.labels), "rows": rows}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
