"""Stage 3's study file from the decisions (issue 66, docs/bed-dynamics.md, "Stage 3"): the contact settings' choice
per shape (``readings.contact_candidates`` on the archives of the paper's study, ``contact_paper`` and
``contact_candidates``), the screenings' changes (``decisions.screening_decision``), their confirmation at new
contact settings where those change too (``decisions.confirmation``), and the velocity reference of the Umf rule
(``stage3.umf_reference``), composed into ``studies/mema2020_stage3.toml`` by ``stage3.compose_stage3``.

    python tools/stage3_study.py --umf AR-1=1.62 AR-4=1.80
    python tools/stage3_study.py --umf AR-1=1.62 AR-4=1.80 --confirmations docs/data/confirm_ar1 --json

Until every decision is taken it writes nothing but says what waits. Where a shape's contact settings change and its
screening changes factors, the confirmation study comes first: it is written once to
``studies/confirm_<design>.toml`` (``--confirm-dir``) for ``fvdem study`` to run, and its archive read with
``--confirmations``; where a factor's confirmation asks more runs, the tool says to what to raise its replicas.
``--umf SHAPE=VALUE``: fvdem's Umf with the preferred bed (``tools/validate_umf.py``), AR-4 for the AR-4 bed (MP
closures). A stage-3 file that exists is never overwritten (exit 2). ``--quick`` reads the archives' committed tables and records as they are (else each
report is rebuilt in a scratch copy). The last line is one JSON object: ``ready``, ``waiting``, per shape what was
decided, and the files written."""
from __future__ import annotations

import argparse
import json
import tomllib
from pathlib import Path

from contact_decision import ARCHIVES as CONTACT_ARCHIVES, study_archives, table_rows  # tools/, beside this script
from screening_decision import ARCHIVES as SCREENING_ARCHIVES, screening_record
from fvdem.analysis.plots import read_timeseries
from fvdem.case import load_case
from fvdem.reports.mema2020.decisions import SCREENINGS, confirmation, screening_decision
from fvdem.reports.mema2020.readings import SHAPES, contact_candidates
from fvdem.reports.mema2020.stage3 import (CONFIRM_REPLICAS, CONTACT_KEYS, EXPERIMENT_UMF, compose_stage3,
                                           confirmation_study, shape_of_case, study_toml, umf_reference)
from fvdem.study.records import RunState, folder_case, state_of
from fvdem.study.screening import response_value

ROOT = Path(__file__).resolve().parents[1]
STAGE2 = ROOT / "studies" / "mema2020_stage2.toml"
OUT = ROOT / "studies" / "mema2020_stage3.toml"
UMF_NAMES = {"AR-1": "AR-1", "AR-4": "AR-4 MP", "AR-4 MP": "AR-4 MP"}


def case_value(case, key: str):
    section, name = key.split(".")
    return getattr(getattr(case, section), name)


def contact_of(archives: list, family: str) -> dict | None:
    """The contact settings (``CONTACT_KEYS``) a family's ended runs ran at, from an archived case.toml."""
    for archive in archives:
        for run in sorted((archive / "runs").glob(f"{family}_*")):
            case = folder_case(run)
            if case is not None and (run / "summary.json").is_file():
                return {key: case_value(case, key) for key in CONTACT_KEYS}
    return None


BED_CONTACT = ("contact.normal_stiffness", "time.dem_step")  # what settles a bed (it has no gas step)


def bed_contact(stage2: dict, path: Path, shape: str) -> dict:
    """The contact settings a shape's beds settle at in stage 3: their own case's (the paper's), as the beds of the
    runs that decided the contact settings settled (``studies/contact_paper.toml`` and ``contact_candidates.toml``
    set no contact keys), named whatever stage 2's settings set."""
    bed = next(b for b in stage2["beds"].values() if shape_of_case(b["case"]) == shape)
    case = load_case(path.parent / bed["case"])
    return {key: case_value(case, key) for key in BED_CONTACT}


def confirmed(archives: list, shape: str, decision: dict) -> dict:
    """Per factor of ``decision['changes']`` its confirmation from the confirmation archives' ended runs."""
    primary = SCREENINGS[shape]["primary"]
    design = SCREENINGS[shape]["design"]
    values = {}
    for archive in archives:
        for row in json.loads((archive / "table.json").read_text()):
            if state_of(row["status"]) is not RunState.ENDED:
                continue
            folder = archive / "runs" / row["name"]
            series = read_timeseries(folder) if (folder / "timeseries.csv").is_file() else None
            value, _ = response_value(primary, row, series, False)
            if value is not None:
                values.setdefault(row["family"], []).append(value)
    return {factor: confirmation(values.get(f"{design}_base", []), values.get(f"{design}_{factor}", []),
                                 decision["factors"][factor]) for factor in decision["changes"]}


def _write(path: Path, text: str, written: list, parser) -> None:
    if path.exists() and path.read_text() != text:
        parser.exit(2, f"{path}: exists (never overwritten); move it aside to write it again\n")
    path.write_text(text)
    written.append(str(path))


def _header(lines: list) -> str:
    return "".join(f"# {line}\n" if line else "#\n" for line in lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--umf", nargs="+", metavar="SHAPE=VALUE", default=[],
                        help="fvdem's Umf [m/s] with the preferred bed per shape (AR-1, AR-4), tools/validate_umf.py")
    parser.add_argument("--contact-archives", nargs="+", type=Path, help="archives of the paper's study, "
                        "contact_paper and contact_candidates (default: the committed ones that exist)")
    parser.add_argument("--screenings", nargs="+", type=Path, help="screening archives (default: the committed "
                        "docs/data/screening_ar1 and screening_ar4 that exist)")
    parser.add_argument("--confirmations", nargs="+", type=Path, default=[],
                        help="archives of the confirmation studies (studies/confirm_<design>.toml)")
    parser.add_argument("--stage2", type=Path, default=STAGE2, help="stage 2's study file")
    parser.add_argument("--out", type=Path, default=OUT, help="stage 3's study file to write")
    parser.add_argument("--confirm-dir", type=Path, default=ROOT / "studies", help="where confirmation studies go")
    parser.add_argument("--quick", action="store_true", help="read the archives' committed tables and records")
    parser.add_argument("--json", action="store_true", help="print only the JSON object")
    args = parser.parse_args(argv)
    umf = {}
    for item in args.umf:
        shape, _, value = item.partition("=")
        try:
            umf[UMF_NAMES[shape]] = float(value)
        except (KeyError, ValueError):
            parser.exit(2, f"--umf {item}: SHAPE=VALUE with SHAPE one of AR-1, AR-4 and VALUE in m/s "
                           "(e.g. AR-1=1.62)\n")
    contact_archives = study_archives(args.contact_archives, CONTACT_ARCHIVES, parser, "--contact-archives")
    screenings = study_archives(args.screenings, SCREENING_ARCHIVES, parser, "--screenings")
    study_archives(args.confirmations, (), parser, "--confirmations")
    stage2 = tomllib.loads(args.stage2.read_text())
    rows = [r for a in contact_archives for r in table_rows(a, rebuild=not args.quick)]
    candidates = contact_candidates(rows)["shapes"]
    decisions = {}
    for archive in screenings:
        record = screening_record(archive, rebuild=not args.quick)
        if record is not None:
            decision = screening_decision(record)
            decisions[decision["shape"]] = (decision, tomllib.loads((archive / "study.toml").read_text()))
    waiting, out, changes, written, notes = [], {}, {}, [], []
    for shape in SHAPES:
        entry = out.setdefault(shape, {})
        choice = candidates[shape]["choice"]
        entry["contact_choice"] = choice
        contact = {}
        if choice is None:
            waiting.append(f"{shape}: the contact settings (tools/contact_decision.py: not decided yet)")
        elif choice != "defaults":
            contact = contact_of(contact_archives, choice) or {}
            if not contact:
                waiting.append(f"{shape}: no ended run of {choice} to read its contact settings from")
            contact = {k: v for k, v in contact.items() if stage2["settings"].get(k) != v}
        entry["contact"] = contact
        if shape not in decisions:
            waiting.append(f"{shape}: its screening's archive")
            continue
        decision, screening_table = decisions[shape]
        entry["screening"] = {f: e["decision"] for f, e in decision["factors"].items()}
        if not decision["decided"]:
            waiting.append(f"{shape}: its screening ({decision.get('waiting') or 'factors wait for replicas'})")
            continue
        factors = dict(decision["changes"])
        settle = bed_contact(stage2, args.stage2, shape) if contact else {}
        if contact and factors:  # confirmed at the new contact settings first
            verdicts = confirmed(args.confirmations, shape, decision) if args.confirmations else {}
            entry["confirmation"] = verdicts
            if not verdicts or any(v["verdict"] in ("open", "add runs") for v in verdicts.values()):
                study = confirmation_study(screening_table, list(factors), contact, settle)
                path = args.confirm_dir / f"{study['name']}.toml"
                if not path.exists():  # once: more runs are its replicas raised, the runs so far kept
                    path.write_text(_header([f"{shape}: the screening's changes confirmed at the new contact "
                                             "settings (docs/bed-dynamics.md, Stage 3, rule 1), written by "
                                             "tools/stage3_study.py", f"  fvdem study {path.name} --out "
                                             f"~/fvdem-runs/{study['name']} --workers 1"]) + study_toml(study))
                    written.append(str(path))
                more = [f for f, v in verdicts.items() if v["verdict"] == "add runs"]
                most = max((max(v["runs"]) for v in verdicts.values()), default=0)
                waiting.append(f"{shape}: the confirmation of {', '.join(factors)} ({path}"
                               + (f"; {', '.join(more)} within the interval of mattering: raise its replicas to "
                                  f"{most + CONFIRM_REPLICAS} and run it again" if more else "") + ")")
                continue
            factors = {f: factors[f] for f, v in verdicts.items() if v["verdict"] == "confirms"}
        run_set, bed_set = dict(contact), dict(settle)
        for factor, level in factors.items():
            level = dict(level)
            bed = level.pop("bed", None)
            if bed is not None:  # a bed preparation: the screening's bed less its replica seed
                bed_set.update({k: v for k, v in screening_table["beds"][bed].get("set", {}).items()
                                if k != "particles.insertion.seed"})
            run_set.update(level)
        entry["factors"] = factors
        if shape not in umf:
            waiting.append(f"{shape}: fvdem's Umf with the preferred bed (--umf; tools/validate_umf.py)")
            continue
        entry["umf"] = umf_reference(shape, umf[shape])
        if entry["umf"]["umf"] is not None:
            run_set["gas.umf"] = entry["umf"]["umf"]
        changes[shape] = {"set": run_set, "bed": bed_set}
        notes.append(f"{shape}: contact {choice} {contact or '(unchanged)'}; factors {list(factors) or 'none'}; Umf "
                     f"{umf[shape]:g} m/s against the experiment's {EXPERIMENT_UMF[shape]:g} "
                     f"({100 * entry['umf']['relative']:+.1f} %): "
                     + ("the paper's velocity definition" if entry["umf"]["umf"] else "fvdem's own Umf kept"))
    if not waiting:
        study = compose_stage3(stage2, changes)
        _write(args.out, _header(["Stage 3 of Mema et al.'s study (issue 66): stage 2's points at the decided "
                                  "settings, composed by tools/stage3_study.py (docs/bed-dynamics.md, Stage 3)", *notes,
                                  f"  fvdem study {args.out.name} --out ~/fvdem-runs/mema2020_stage3 --workers 2 "
                                  "--adopt docs/data/mema2020"]) + study_toml(study), written, parser)
    result = {"ready": not waiting, "waiting": waiting, "shapes": out, "written": written}
    if not args.json:
        for line in waiting:
            print(f"waits: {line}")
        for path in written:
            print(f"wrote {path}")
    print(json.dumps(result, default=str))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
