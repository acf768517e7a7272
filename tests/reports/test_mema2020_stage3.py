"""Stage 3's study file composed from the decisions (docs/bed-dynamics.md, "Stage 3"; fvdem.reports.mema2020.stage3,
tools/stage3_study.py), checked by expanding it with the study engine beside stage 2's: a changed shape runs every
stage-2 point of its base families, two replicas a point, at the new settings, its beds settled at theirs; an
unchanged shape's runs are stage 2's to the name, case and bed (so that --adopt counts them); the confirmation study
runs each factor's two levels three times at the new contact settings; the Umf rule at its 5 % bound."""
import json
import os
import subprocess
import sys
import tomllib
from collections import Counter

import pytest
import tomli_w

from fvdem.reports.mema2020.stage3 import (CONFIRM_REPLICAS, compose_stage3, confirmation_study, shape_of_case,
                                           umf_reference)
from fvdem.study import load_study
from paths import ROOT, TOOLS

STAGE2 = ROOT / "studies" / "mema2020_stage2.toml"
CONTACT = {"contact.normal_stiffness": 3200.0, "time.dem_step": 2.5e-5, "gas.cfd_step": 5.0e-4}


def _expand(tmp_path, table: dict, name: str):
    """The study a table makes, written beside a link to the repository's cases (its case paths are ../cases/)."""
    studies = tmp_path / "studies"
    studies.mkdir(exist_ok=True)
    if not (tmp_path / "cases").exists():
        os.symlink(ROOT / "cases", tmp_path / "cases")
    path = studies / f"{name}.toml"
    path.write_text(tomli_w.dumps(table))
    return load_study(path, tmp_path / "out" / name)


def _runs(study, shape):
    return {r.name: r for r in study.runs if shape_of_case(r.case) == shape}


@pytest.fixture(scope="module")
def stage2(tmp_path_factory):
    return tomllib.loads(STAGE2.read_text()), load_study(STAGE2, tmp_path_factory.mktemp("stage2"))


def test_a_changed_shape_runs_every_point_twice_at_the_new_settings_and_the_other_keeps_stage_2s_runs(
        tmp_path, stage2):
    table, old = stage2
    bed = {"contact.normal_stiffness": 2.0e4, "time.dem_step": 1.0e-5, "contact.friction": 0.0}
    new = _expand(tmp_path, compose_stage3(table, {"AR-1": {"set": {**CONTACT, "gas.inlet_ramp": 0.0}, "bed": bed}}),
                  "stage3")
    assert new.name == "mema2020_stage3"
    # AR-4: the same runs, to the name, physics, bed, duration and priority
    keep = lambda runs: {n: (r.physics, r.bed, r.duration, r.priority, r.overrides) for n, r in runs.items()}
    assert keep(_runs(new, "AR-4 MP")) == keep(_runs(old, "AR-4 MP")) and _runs(old, "AR-4 MP")
    # AR-1: stage 2's points of its base families (no replica series), two replicas each, at the new settings
    ar1, before = _runs(new, "AR-1"), _runs(old, "AR-1")
    point = lambda r: (r.family, r.point.get("gas.u_over_umf"))
    assert {point(r) for r in ar1.values()} == {point(r) for r in before.values()
                                               if not r.family.endswith(("_t95", "_expansion"))}
    assert set(Counter(point(r) for r in ar1.values()).values()) == {2}
    assert {r.family for r in ar1.values()} == {"ar1", "ar1_tall"}
    for r in ar1.values():
        assert {k: r.overrides[k] for k in CONTACT} == CONTACT and r.overrides["gas.inlet_ramp"] == 0.0
        assert r.duration == next(b.duration for b in before.values() if point(b) == point(r))
    beds = {b.name: b for b in new.beds}
    for name in {r.bed for r in ar1.values()}:
        assert {k: beds[name].overrides[k] for k in bed} == bed  # its beds settle at theirs, with the preparation
    assert {b.name for b in new.beds if "ar1" in b.name} == {r.bed for r in ar1.values()}  # no unused bed
    # beds of their own names: no stage-2 run of a changed shape passes for a stage-3 one (--adopt)
    assert not {r.bed for r in ar1.values()} & {b.name for b in old.beds}


def test_with_nothing_changed_stage_3_is_stage_2s_study(tmp_path, stage2):
    table, old = stage2
    new = _expand(tmp_path, compose_stage3(table, {"AR-1": {"set": {}, "bed": {}}}), "same")
    assert {n: (r.physics, r.bed) for n, r in _runs(new, "AR-1").items()} == {
        n: (r.physics, r.bed) for n, r in _runs(old, "AR-1").items()}
    with pytest.raises(ValueError, match="the shapes are AR-1, AR-4 MP"):
        compose_stage3(table, {"AR-2": {"set": CONTACT}})


def test_the_confirmation_study_runs_the_base_and_each_factors_high_level_three_times_at_the_new_contacts(
        tmp_path):
    screening = tomllib.loads((ROOT / "studies" / "screening_ar1.toml").read_text())
    settle = {"contact.normal_stiffness": 2.0e4, "time.dem_step": 1.0e-5}
    study = _expand(tmp_path, confirmation_study(screening, ["start", "packing"], CONTACT, settle), "confirm_ar1")
    assert study.name == "confirm_ar1"
    assert Counter(r.family for r in study.runs) == {f"ar1_{f}": CONFIRM_REPLICAS for f in ("base", "start", "packing")}
    for r in study.runs:
        assert {k: r.overrides[k] for k in CONTACT} == CONTACT and r.overrides["gas.umf"] == 1.914
        assert r.overrides["gas.inlet_ramp"] == (0.0 if r.family == "ar1_start" else 1.0)
        assert r.bed.startswith("ar1_dense" if r.family == "ar1_packing" else "ar1")
        assert r.overrides.get("contact.rolling_friction", 0.46) == 0.46  # the others at their study setting
    for b in study.beds:  # settled as stage 3's beds, not at the runs' contacts
        assert {k: b.overrides[k] for k in settle} == settle
    with pytest.raises(ValueError, match="factor 'lift': not one of ar1's"):
        confirmation_study(screening, ["lift"], CONTACT, settle)


@pytest.mark.parametrize("shape, measured, umf", [("AR-1", 1.65, 1.58), ("AR-1", 1.67, None), ("AR-4 MP", 1.615, 1.7),
                                                   ("AR-4 MP", 1.90, None)])
def test_the_umf_rule_returns_to_the_papers_definition_within_5_percent(shape, measured, umf):
    assert umf_reference(shape, measured)["umf"] == umf


def test_the_tool_writes_nothing_until_every_decision_is_taken_and_says_what_waits(tmp_path):
    result = subprocess.run([sys.executable, str(TOOLS / "stage3_study.py"), "--quick", "--json", "--out",
                             str(tmp_path / "stage3.toml"), "--confirm-dir", str(tmp_path), "--umf", "AR-1=1.9"],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    out = json.loads(result.stdout.strip().splitlines()[-1])
    assert not out["ready"]  # AR-4's Umf is not given, whatever the campaign has decided
    assert any(w.startswith("AR-4 MP: ") for w in out["waiting"])
    assert all(w.split(":")[0] in ("AR-1", "AR-4 MP") for w in out["waiting"])
    assert not (tmp_path / "stage3.toml").exists()
    bad = subprocess.run([sys.executable, str(TOOLS / "stage3_study.py"), "--quick", "--umf", "AR-2=1.9"],
                         capture_output=True, text=True, timeout=300)
    assert bad.returncode == 2 and "--umf AR-2=1.9: SHAPE=VALUE" in bad.stderr and "Traceback" not in bad.stderr


def test_the_tool_writes_the_confirmation_first_and_stage_3_once_it_confirms(tmp_path, monkeypatch, stage2, capsys):
    """The decisions stand in (AR-1: the 3200 N/m candidate and a full-speed start; AR-4 MP: its defaults and no
    change): the tool writes the confirmation study; with a confirmation archive that confirms, stage 3, which the
    study engine expands with AR-1's runs at the new settings and the experiment's Umf (1.62 m/s is within 5 % of
    1.58), and AR-4's as stage 2's (1.90 m/s is not within 5 % of 1.7: fvdem's own Umf kept)."""
    sys.path.insert(0, str(TOOLS))
    import stage3_study as tool
    choices = {"AR-1": {"choice": "ar1_candidate_k3200"}, "AR-4 MP": {"choice": "defaults"}}
    monkeypatch.setattr(tool, "table_rows", lambda archive, rebuild: [])
    monkeypatch.setattr(tool, "contact_candidates", lambda rows: {"shapes": choices})
    monkeypatch.setattr(tool, "contact_of", lambda archives, family: dict(CONTACT))
    start = {"estimate": 0.1, "decision": "change"}
    decided = {"AR-1": {"shape": "AR-1", "decided": True, "changes": {"start": {"gas.inlet_ramp": 0.0}},
                        "factors": {"start": start}},
               "AR-4 MP": {"shape": "AR-4 MP", "decided": True, "changes": {}, "factors": {}}}
    monkeypatch.setattr(tool, "screening_record", lambda archive, rebuild: {"shape": archive.name})
    monkeypatch.setattr(tool, "screening_decision", lambda record: decided[record["shape"]])
    archives = {}
    for shape, name in (("AR-1", "screening_ar1"), ("AR-4 MP", "screening_ar4")):
        archives[shape] = tmp_path / shape
        archives[shape].mkdir()
        (archives[shape] / "study.json").write_text("{}")
        (archives[shape] / "study.toml").write_text((ROOT / "studies" / f"{name}.toml").read_text())
    (tmp_path / "studies").mkdir()
    os.symlink(ROOT / "cases", tmp_path / "cases")
    args = ["--quick", "--json", "--screenings", str(archives["AR-1"]), str(archives["AR-4 MP"]),
            "--contact-archives", str(archives["AR-1"]), "--umf", "AR-1=1.62", "AR-4=1.90",
            "--out", str(tmp_path / "studies" / "stage3.toml"), "--confirm-dir", str(tmp_path / "studies")]
    assert tool.main(args) == 0
    confirm = tmp_path / "studies" / "confirm_ar1.toml"
    assert confirm.exists() and not (tmp_path / "studies" / "stage3.toml").exists()
    study = load_study(confirm, tmp_path / "out" / "confirm")
    assert {r.family for r in study.runs} == {"ar1_base", "ar1_start"}
    def archive(name, base, high):
        done = tmp_path / name
        (done / "runs").mkdir(parents=True)
        (done / "study.json").write_text("{}")
        rows = []
        for family, entropy in (("ar1_base", base), ("ar1_start", high)):
            for k, value in enumerate(entropy, 1):
                run = f"{family}_r{k}"
                rows.append({"name": run, "family": family, "status": "finished", "simulated_seconds": 7.0,
                             "duration": 7.0})
                (done / "runs" / run).mkdir()
                (done / "runs" / run / "timeseries.csv").write_text(f"time,mixing_entropy\n0.0,0.0\n3.0,{value}\n"
                                                                    "7.0,0.99\n")
        (done / "table.json").write_text(json.dumps(rows))
        return done
    # within its interval of mattering: more runs, the study file kept as it is
    text = confirm.read_text()
    unsure = archive("unsure", (0.60, 0.66, 0.55), (0.64, 0.70, 0.61))
    capsys.readouterr()
    assert tool.main([*args, "--confirmations", str(unsure)]) == 0
    said = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert any("start within the interval of mattering: raise its replicas to 6" in w for w in said["waiting"])
    assert confirm.read_text() == text and not (tmp_path / "studies" / "stage3.toml").exists()
    # the full-speed start mixes the bed faster at 3 s in 3 runs of 3
    done = archive("confirm_archive", (0.60, 0.62, 0.58), (0.75, 0.78, 0.73))
    assert tool.main([*args, "--confirmations", str(done)]) == 0
    new = load_study(tmp_path / "studies" / "stage3.toml", tmp_path / "out" / "stage3")
    _, old = stage2
    for r in _runs(new, "AR-1").values():
        assert r.overrides["gas.inlet_ramp"] == 0.0 and r.overrides["gas.umf"] == 1.58
        assert {k: r.overrides[k] for k in CONTACT} == CONTACT
    assert {b.overrides["contact.normal_stiffness"] for b in new.beds if "ar1" in b.name} == {2.0e4}
    assert {n: r.physics for n, r in _runs(new, "AR-4 MP").items()} == {
        n: r.physics for n, r in _runs(old, "AR-4 MP").items()}
    assert "--adopt docs/data/mema2020" in (tmp_path / "studies" / "stage3.toml").read_text()
    # never overwritten: another decision refuses to replace the file
    monkeypatch.setattr(tool, "contact_of", lambda archives, family: {**CONTACT, "contact.normal_stiffness": 5e3})
    with pytest.raises(SystemExit) as refused:
        tool.main([*args, "--confirmations", str(done)])
    assert refused.value.code == 2
