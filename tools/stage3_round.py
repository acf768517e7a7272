"""A round of stage 3's replicas (issue 66, docs/bed-dynamics.md, "Stage 3", rule 3): from the archive of stage 3's
study, every table of its plan (the replicas that would decide its open findings, ``plan.toml``) whose added replicas
cost at most 20 core-hours at its point's runs so far, cheapest first, appended to the study file as one round.

    python tools/stage3_round.py docs/data/mema2020_stage3
    python tools/stage3_round.py docs/data/mema2020_stage3 --dry-run --json

A changed shape starts without stage 2's replica series (``<family>_t95``, ``<family>_expansion``): a round that asks
one brings it back from stage 2's file, with stage 3's changes to its base family and beds, at the round's points
alone; its first replicas are priced at the base family's runs (a t95 run at a whole run's cost, an expansion run at
its 5 s share of one). A table whose cost is unknown (no run of its point has ended) or above the limit is left out
and said so; a finding it alone would decide stays open. The round is appended; the one thing of the file it changes
is a series' own ``[[exclude]]`` that an earlier round wrote, narrowed where a later round asks the series at
another velocity. The file is refused (exit 2, nothing written) unless the study engine expands it with every run
it planned before and each table's replicas. The archive must hold every run the file plans (archived after the
last round), else the tool waits: a plan that does not see a round's runs would ask them again. A table the file
already plans is not added again. The last line is one JSON object: ``round``, ``chosen``,
``left``, ``written``, and ``waiting``: what it needs that is not there yet (stage 3's file or archive; then it
writes nothing and exits 0). ``--quick`` reads the archive's committed table and findings (else its report is
rebuilt in a scratch copy).
"""
from __future__ import annotations

import argparse
import json
import tempfile
import tomllib
from collections import Counter
from pathlib import Path

from contact_decision import planned_rows, report_json, study_archives  # tools/, beside this script
from fvdem.reports.mema2020.families import row_ended
from fvdem.reports.mema2020.plan import plan_tables
from fvdem.reports.mema2020.stage3 import (ROUND_HOURS, ROUND_MARK, addable_series, narrow_exclude, round_tables,
                                           round_toml)
from fvdem.errors import CaseError
from fvdem.study.sweep import study_from_table

ROOT = Path(__file__).resolve().parents[1]
STAGE2 = ROOT / "studies" / "mema2020_stage2.toml"
STUDY = ROOT / "studies" / "mema2020_stage3.toml"
ARCHIVE = ROOT / "docs" / "data" / "mema2020_stage3"


def report_records(archive: Path, rebuild: bool = True) -> tuple[list, list]:
    """An archive's table rows of the runs it plans (each with its ``gas.u_over_umf``) and its findings, from its
    report rebuilt in a scratch copy, else from its committed files."""
    rows, findings = report_json(archive, ["table.json", "findings.json"], rebuild)
    return planned_rows(archive, rows), findings


def planned(text: str, path: Path, scratch: Path) -> tuple[Counter, set]:
    """How many runs a study file's ``text`` (at ``path``: its case paths are relative to it) plans per (family,
    U/Umf), as the study engine expands it, and their names."""
    study = study_from_table(tomllib.loads(text), path, scratch)
    return Counter((r.family, r.point.get("gas.u_over_umf")) for r in study.runs), {r.name for r in study.runs}


def waits(waiting: list, quiet: bool) -> int:
    """Says what the round waits for (each line unless ``quiet``, then the JSON object) and writes nothing: 0."""
    if not quiet:
        for line in waiting:
            print(f"waits: {line}")
    print(json.dumps({"round": None, "waiting": waiting, "chosen": [], "left": [], "written": []}))
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("archive", type=Path, nargs="?",
                        help="stage 3's study archive (fvdem study DIR --archive; default: the committed "
                             "docs/data/mema2020_stage3 where it exists)")
    parser.add_argument("--study", type=Path, help="stage 3's study file, appended to (default: "
                        "studies/mema2020_stage3.toml)")
    parser.add_argument("--stage2", type=Path, default=STAGE2, help="stage 2's study file (its replica series)")
    parser.add_argument("--hours", type=float, default=ROUND_HOURS,
                        help="a table's most core-hours to join the round (the rule's 20)")
    parser.add_argument("--quick", action="store_true", help="read the archive's committed table and findings")
    parser.add_argument("--dry-run", action="store_true", help="say what the round would append, write nothing")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    args = parser.parse_args(argv)
    if not args.hours > 0:
        parser.exit(2, f"--hours {args.hours:g}: a positive number of core-hours\n")
    archives = study_archives([args.archive] if args.archive else None, (ARCHIVE,), parser, "archive")
    if args.study is not None and not args.study.is_file():
        parser.exit(2, f"--study {args.study}: no such study file (compose it first: tools/stage3_study.py)\n")
    args.study = args.study or STUDY
    waiting = ([] if args.study.is_file() else [f"{args.study}: stage 3's study file (tools/stage3_study.py)"]) + (
        [] if archives else [f"{ARCHIVE}: stage 3's archive (fvdem study ... --archive)"])
    if waiting:
        return waits(waiting, args.json)
    archive = archives[0]
    if not (archive / "table.json").exists() and args.quick:
        parser.exit(2, f"archive: {archive}: no table.json (its report not written; leave out --quick)\n")
    text = args.study.read_text()
    stage3, stage2 = tomllib.loads(text), tomllib.loads(args.stage2.read_text())
    rows, findings = report_records(archive, rebuild=not args.quick)
    with tempfile.TemporaryDirectory() as scratch:
        before, names = planned(text, args.study, Path(scratch) / "before")
        behind = names - {r["name"] for r in rows}
        if behind:  # its plan would not see the runs the file's last round added: they would be asked again
            return waits([f"{archive}: archived before the study file's last round ({len(behind)} of its runs not "
                          "in the archive's table): archive the study again (fvdem study DIR --archive)"], args.json)
        tables, _, _ = plan_tables(rows, findings, addable_series(stage2, stage3))
        chosen, left = round_tables(tables, args.hours)
        chosen = [e for e in chosen if before[(e["family"], e["u_over_umf"])] < e["replicas"]]
        number = text.count(f"\n{ROUND_MARK}") + 1
        ended = sum(row_ended(r) for r in rows)
        said = [f"tools/stage3_round.py from {archive.name} ({ended} of {len(rows)} runs ended): every table of its "
                f"plan whose added replicas cost at most {args.hours:g} core-hours, cheapest first "
                f"(docs/bed-dynamics.md, Stage 3, rule 3): {len(chosen)} table{'' if len(chosen) == 1 else 's'}, "
                f"about {sum(e['core_hours'] for e in chosen):.3g} core-hours"]
        said += [f"left: {e['more']} more of {e['family']} at {e['u_over_umf']:g} Umf ({e['left']})" for e in left]
        written = []
        if chosen and not args.dry_run:
            new = text
            for e in chosen:  # a series an earlier round brought back, asked at a velocity it excluded
                if e["family"] in stage3["families"] and before[(e["family"], e["u_over_umf"])] == 0:
                    new = narrow_exclude(new, e["family"], [e["u_over_umf"]]) or new
            new = new.rstrip("\n") + "\n" + round_toml(chosen, stage2, stage3, number, said)
            try:
                after, _ = planned(new, args.study, Path(scratch) / "after")
            except (CaseError, tomllib.TOMLDecodeError) as exc:
                parser.exit(2, f"--study {args.study}: the round would make a file the study engine refuses "
                               f"({exc}); nothing written\n")
            lost = [key for key, n in before.items() if after[key] < n]
            short = [f"{e['family']} at {e['u_over_umf']:g} Umf ({after[(e['family'], e['u_over_umf'])]} of "
                     f"{e['replicas']}: an [[exclude]] no round wrote drops it; remove that velocity from it, no "
                     "run is lost)" for e in chosen if after[(e["family"], e["u_over_umf"])] < e["replicas"]]
            if lost or short:
                parser.exit(2, f"--study {args.study}: the round would "
                               + (f"drop runs of {lost}" if lost else f"not plan {'; '.join(short)}")
                               + "; nothing written\n")
            args.study.write_text(new)
            written.append(str(args.study))
    result = {"round": number, "waiting": [], "chosen": chosen, "left": left, "written": written}
    if not args.json:
        for line in said:
            print(line)
        for e in chosen:
            print(f"  {e['family']} at {e['u_over_umf']:g} Umf: {e['from']} -> {e['replicas']} replicas, about "
                  f"{e['core_hours']:.3g} core-hours")
        print(f"appended round {number} to {args.study}" if written else "nothing written")
    print(json.dumps(result, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
