"""The screenings, decided (issue 66, item 2): which model choices the paper does not fix change for the re-run of
the paper's study, from the committed archives of ``studies/screening_ar1.toml`` and ``studies/screening_ar4.toml``,
by the rule ``fvdem.reports.mema2020.decisions.screening_decision`` (docs/bed-dynamics.md, "The screening", rules
1-4, fixed before the screenings' runs).

    python tools/screening_decision.py --archives docs/data/screening_ar1 docs/data/screening_ar4 --json

Each archive's screening report is rebuilt in a scratch copy first (``fvdem study COPY --report``); ``--quick``
reads the archives' committed ``screening.json`` as it is. Without ``--archives``, the committed archives of both
screenings that exist. Prints, per shape, each factor's main effect on the primary response with its 95 % interval
and its decision ("change", "keep", "cause", "add replicas", "fold-over first", "waits for the early signs"), and the
told two-factor chains; until every planned run holds the responses the reading is provisional and changes nothing.
The last line is one JSON object: per shape the decision record (``factors``, ``chains``, ``changes``: the high
levels' settings the study moves to, ``decided``)."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from contact_decision import report_json, study_archives  # tools/, beside this script
from fvdem.reports.mema2020.decisions import screening_decision
from fvdem.study.screening import SCREENING_FILE

ROOT = Path(__file__).resolve().parents[1]
ARCHIVES = tuple(ROOT / "docs" / "data" / name for name in ("screening_ar1", "screening_ar4"))


def screening_record(archive: Path, rebuild: bool = True) -> dict | None:
    """An archive's screening record (its report rebuilt in a scratch copy, else its committed one); None where
    the archive holds none (not a designed study, or no report yet)."""
    return report_json(archive, [SCREENING_FILE], rebuild)[0]


def _interval(entry: dict) -> str:
    low, high = entry["interval"]
    return "no interval" if low is None else f"[{low:+.3f}, {high:+.3f}]"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--archives", nargs="+", type=Path,
                        help="screening archives (fvdem study DIR --archive; default: the committed "
                             "docs/data/screening_ar1 and screening_ar4, those that exist)")
    parser.add_argument("--quick", action="store_true", help="read the archives' committed screening.json")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    args = parser.parse_args(argv)
    archives = study_archives(args.archives, ARCHIVES, parser)
    out = {}
    for archive in archives:
        record = screening_record(archive, rebuild=not args.quick)
        if record is None:
            parser.exit(2, f"--archives: {archive}: no screening report (a study without a [design] table?)\n")
        try:
            decision = screening_decision(record)
        except ValueError as exc:
            parser.exit(2, f"--archives: {archive}: {exc}\n")
        out[decision["shape"]] = decision
        if args.json:
            continue
        print(f"{decision['shape']} ({archive.name}), on {decision['primary']}:")
        if "waiting" in decision:
            print(f"  not yet: {decision['waiting']} (the reading below is provisional)")
        for factor, entry in decision["factors"].items():
            why = entry.get("why") or ", ".join(entry.get("chains", [])) or entry.get("paper_fixes") or ""
            print(f"  {factor:8s} {entry['estimate']:+.3f} {_interval(entry):18s} {entry['decision']}"
                  + (f" ({why})" if why and entry["decision"] != "keep" else ""))
        for chain in decision["chains"]:
            print(f"  told chain {chain['chain']}: {chain['estimate']:+.3f} {_interval(chain)}")
        print(f"  changes: {decision['changes'] or 'none'}{'' if decision['decided'] else ' (not decided yet)'}")
    print(json.dumps({"screenings": out}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
