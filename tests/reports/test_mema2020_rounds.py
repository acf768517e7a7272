"""Stage 3's rounds of replicas (docs/bed-dynamics.md, "Stage 3", rule 3; ``stage3.round_tables``, ``round_toml``,
``tools/stage3_round.py``): every plan table whose added replicas cost at most 20 core-hours, cheapest first; a
changed shape's replica series brought back from stage 2 at the new settings; priced at the base family's runs."""
from __future__ import annotations

import json
import os
import sys
import tomllib
from collections import Counter

import pytest
import tomli_w

from fvdem.reports.mema2020.plan import plan_points, plan_tables
from fvdem.reports.mema2020.rules import EXPANSION_SECONDS, replica_cost
from fvdem.reports.mema2020.stage3 import (ROUND_HOURS, addable_series, compose_stage3, round_tables, round_toml,
                                           series_tables)
from fvdem.study import load_study
from paths import ROOT, TOOLS

STAGE2 = ROOT / "studies" / "mema2020_stage2.toml"
CONTACT = {"contact.normal_stiffness": 3200.0, "time.dem_step": 2.5e-5, "gas.cfd_step": 5.0e-4}
BED = {"contact.normal_stiffness": 2.0e4, "time.dem_step": 1.0e-5, "contact.friction": 0.0}


def test_the_plan_as_data_writes_the_archived_plan_toml_unchanged():
    """``plan_points`` is ``plan_tables`` written out: the committed stage-2 archive's plan.toml, byte for byte."""
    archive = ROOT / "docs" / "data" / "mema2020"
    rows = [r for r in json.loads((archive / "table.json").read_text()) if r["status"] != "not planned"]
    findings = json.loads((archive / "findings.json").read_text())
    assert plan_points(rows, findings, "mema2020_stage2") == (archive / "plan.toml").read_text()
    tables, _, _ = plan_tables(rows, findings)
    assert len(tables) == (archive / "plan.toml").read_text().count("\n[[points]]\n")


def test_a_round_takes_each_table_up_to_20_core_hours_cheapest_first():
    hour = 3600.0
    tables = {("a", 2.0): {"from": 2, "replicas": 5, "cost": 2 * hour, "why": ["x"]},  # 3 more: 6 core-hours
              ("b", 2.0): {"from": 2, "replicas": 4, "cost": 0.5 * hour, "why": ["y"]},  # 1 core-hour
              ("c", 1.6): {"from": 3, "replicas": 13, "cost": 2 * hour, "why": ["z"]},  # 20: at the limit, in
              ("d", 1.7): {"from": 2, "replicas": 13, "cost": 2 * hour, "why": ["w"]},  # 22: stays open
              ("e", 2.9): {"from": 0, "replicas": 4, "cost": None, "why": ["v"]}}  # unpriced
    chosen, left = round_tables(tables)
    assert ROUND_HOURS == 20.0
    assert [(e["family"], e["core_hours"]) for e in chosen] == [("b", 1.0), ("a", 6.0), ("c", 20.0)]
    assert {e["family"]: e["left"] for e in left} == {
        "d": "22 core-hours, more than a round's 20", "e": "no run of its point has ended: its cost is unknown"}


def test_a_series_without_runs_is_priced_at_its_base_familys_whole_runs():
    """An expansion run at its 5 s share of a whole run (CPU seconds per simulated second times 5 s); a series'
    own ended runs where it has some; a t95 run at a whole run's cost where no run was cut at t95."""
    rows = [{"family": "ar4_mp", "gas.u_over_umf": 1.6, "status": "finished", "cpu_seconds": 8000.0,
             "simulated_seconds": 20.0},
            {"family": "ar4_mp", "gas.u_over_umf": 1.6, "status": "finished", "cpu_seconds": 6000.0,
             "simulated_seconds": 20.0}]
    assert EXPANSION_SECONDS == 5.0
    assert replica_cost(rows, "ar4_mp", 1.6, "ar4_mp_expansion") == pytest.approx(5.0 * 350.0)
    assert replica_cost(rows, "ar4_mp", 1.6) == pytest.approx(7000.0)
    assert replica_cost(rows, "ar4_mp", 1.7, "ar4_mp_expansion") is None  # no run there at all
    own = rows + [{"family": "ar4_mp", "column": "ar4_mp_expansion", "gas.u_over_umf": 1.6, "status": "finished",
                   "cpu_seconds": 1500.0, "simulated_seconds": 5.0}]
    assert replica_cost(own, "ar4_mp", 1.6, "ar4_mp_expansion") == 1500.0


@pytest.fixture(scope="module")
def composed(tmp_path_factory):
    """Stage 3 with AR-1 changed (new contact settings and a full-speed start, its beds settled frictionless at the
    paper's contacts), AR-4 as stage 2, written beside a link to the repository's cases."""
    root = tmp_path_factory.mktemp("stage3")
    (root / "studies").mkdir()
    os.symlink(ROOT / "cases", root / "cases")
    stage2 = tomllib.loads(STAGE2.read_text())
    stage3 = compose_stage3(stage2, {"AR-1": {"set": {**CONTACT, "gas.inlet_ramp": 0.0}, "bed": BED}})
    path = root / "studies" / "mema2020_stage3.toml"
    path.write_text("# stage 3\n" + tomli_w.dumps(stage3))
    return root, path, stage2, stage3


def test_a_round_brings_a_changed_shapes_replica_series_back_at_its_points_alone(composed, tmp_path):
    root, path, stage2, stage3 = composed
    assert addable_series(stage2, stage3) == ["ar1_expansion", "ar1_t95", "ar1_tall_t95"]
    chosen = [{"family": "ar1_t95", "u_over_umf": 2.0, "from": 0, "replicas": 6, "more": 6, "core_hours": 3.0,
               "why": ["a finding: 8 of ar1 at 2 Umf in all (now 2)"]},
              {"family": "ar1", "u_over_umf": 1.6, "from": 2, "replicas": 3, "more": 1, "core_hours": 1.5,
               "why": ["another: 3 of ar1 at 1.6 Umf in all (now 2)"]}]
    text = path.read_text() + round_toml(chosen, stage2, stage3, 1, ["round one"])
    trial = path.with_name("round.toml")
    trial.write_text(text)
    before = load_study(path, tmp_path / "before")
    after = load_study(trial, tmp_path / "after")
    count = lambda study: Counter((r.family, r.point["gas.u_over_umf"]) for r in study.runs)
    added = count(after) - count(before)
    assert added == Counter({("ar1_t95", 2.0): 6, ("ar1", 1.6): 1})  # nothing else, nothing lost
    assert not count(before) - count(after)
    runs = {r.name: r for r in after.runs}
    beds = {b.name: b for b in after.beds}
    series = [r for r in after.runs if r.family == "ar1_t95"]
    base = next(r for r in after.runs if r.family == "ar1" and r.point["gas.u_over_umf"] == 2.0)
    for r in series:  # the base family's new settings, the series' own stop, beds of its own seeds renamed
        assert {k: r.overrides[k] for k in CONTACT} == CONTACT and r.overrides["gas.inlet_ramp"] == 0.0
        assert r.overrides["time.stop_after_mixed"] == 0.0 and r.overrides["gas.umf"] == base.overrides["gas.umf"]
        assert r.bed.startswith("ar1_t95_stage3") and r.duration == base.duration and r.priority == -1
        assert {k: beds[r.bed].overrides[k] for k in BED} == BED
        seed = beds[r.bed].overrides["particles.insertion.seed"]  # stage 2's series seeds: from 201
        assert seed >= 201 and seed != beds[base.bed].overrides.get("particles.insertion.seed")
    assert {n for n in runs if n.startswith("ar4")} == {r.name for r in before.runs if r.name.startswith("ar4")}
    # the expansion series keeps stage 2's 5 s ([[durations]]); the tall t95 series its 2.1 m column
    tables = series_tables(stage2, stage3, "ar1_expansion", [1.6])
    assert tables["durations"] == [{"family": "ar1_expansion", "duration": 5.0}]
    assert tables["exclude"] == [{"family": "ar1_expansion", "gas.u_over_umf": [1.7, 2.0, 2.3, 2.6, 2.9]}]
    tall = series_tables(stage2, stage3, "ar1_tall_t95", [2.9])["families"]["ar1_tall_t95"]
    assert tall["set"]["domain.upper"] == [0.15, 0.15, 2.1] and tall["set"]["contact.normal_stiffness"] == 3200.0


def test_the_round_tool_appends_once_and_refuses_a_round_an_exclude_would_drop(composed, tmp_path, monkeypatch,
                                                                               capsys):
    root, path, stage2, stage3 = composed
    study = tmp_path / "studies" / "stage3.toml"
    study.parent.mkdir()
    (tmp_path / "cases").symlink_to(ROOT / "cases")
    study.write_text(path.read_text())
    archive = tmp_path / "archive"
    archive.mkdir()
    (archive / "study.json").write_text("{}")
    sys.path.insert(0, str(TOOLS))
    import stage3_round as tool
    hour = 3600.0
    tables = {("ar1_t95", 2.0): {"from": 0, "replicas": 6, "cost": hour, "why": ["t95 finding"]},
              ("ar1", 1.7): {"from": 2, "replicas": 30, "cost": hour, "why": ["costly finding"]}}
    monkeypatch.setattr(tool, "report_records", lambda archive, rebuild: ([], []))
    monkeypatch.setattr(tool, "plan_tables", lambda rows, findings, addable: (dict(tables), [], []))
    args = [str(archive), "--study", str(study), "--stage2", str(STAGE2), "--json"]
    assert tool.main(args) == 0
    said = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert said["round"] == 1 and [e["family"] for e in said["chosen"]] == ["ar1_t95"]
    assert [e["family"] for e in said["left"]] == ["ar1"] and "28 core-hours" in said["left"][0]["left"]
    text = study.read_text()
    assert text.startswith(path.read_text()) and "# stage 3, round 1\n" in text
    assert Counter(r.family for r in load_study(study, tmp_path / "out").runs)["ar1_t95"] == 6
    # a second call before the archive holds the round's runs adds nothing
    assert tool.main(args) == 0
    assert study.read_text() == text and json.loads(capsys.readouterr().out.strip().splitlines()[-1])["written"] == []
    # a later round asking the series at a velocity its first round excluded: refused, nothing written
    tables[("ar1_t95", 2.9)] = {"from": 0, "replicas": 4, "cost": hour, "why": ["later"]}
    with pytest.raises(SystemExit) as refused:
        tool.main(args)
    assert refused.value.code == 2 and "[[exclude]]" in capsys.readouterr().err
    assert study.read_text() == text
