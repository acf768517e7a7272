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

from fvdem.reports.mema2020.plan import EXPANSION_SECONDS, plan_points, plan_tables
from fvdem.reports.mema2020.stage3 import (ROUND_HOURS, addable_series, compose_stage3, narrow_exclude, round_tables,
                                           round_toml, series_tables, study_toml)
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


def _finding(kind: str, family: str, v: float, replicas: int, now: int, cost) -> dict:
    """An open finding whose plan asks ``replicas`` of ``family`` at ``v`` in all (``now`` so far)."""
    return {"finding": f"{kind} finding", "verdict": "open", "plans": [{"kind": kind, "core_hours": None, "runs": [
        {"family": family, "u_over_umf": v, "replicas": replicas, "now": now, "cpu_seconds": cost}]}]}


def _row(name: str, family: str, v: float, cpu: float, seconds: float, status: str = "finished") -> dict:
    return {"name": name, "family": family, "gas.u_over_umf": v, "status": status, "cpu_seconds": cpu,
            "simulated_seconds": seconds}


def test_a_series_without_runs_is_priced_at_its_base_familys_whole_runs():
    """Stage 3, rule 3: a series the study may add (``addable``) but has no run of at a point is priced at its base
    family's whole runs there (an expansion run at its 5 s share, a t95 run at a whole run's cost), and an
    expansion plan whose replicas are whole runs (no series there) at a whole run's cost; a series' own runs price
    it where it has some."""
    rows = [_row("ar4_mp_r1", "ar4_mp", 1.6, 8000.0, 20.0), _row("ar4_mp_r2", "ar4_mp", 1.6, 6000.0, 20.0),
            _row("ar4_mp_r3", "ar4_mp", 1.7, 5000.0, 16.0)]
    assert EXPANSION_SECONDS == 5.0
    findings = [_finding("expansion", "ar4_mp", 1.6, 6, 2, None), _finding("t95", "ar4_mp", 1.6, 5, 2, 7000.0)]
    tables, _, _ = plan_tables(rows, findings, ["ar4_mp_expansion", "ar4_mp_t95"])
    assert tables[("ar4_mp_expansion", 1.6)]["cost"] == pytest.approx(5.0 * 350.0)
    assert tables[("ar4_mp_t95", 1.6)]["cost"] == pytest.approx(7000.0)
    assert {k: t["from"] for k, t in tables.items()} == {("ar4_mp_expansion", 1.6): 0, ("ar4_mp_t95", 1.6): 0}
    # without the series (not addable, none in the study): whole runs, priced as whole runs
    tables, _, _ = plan_tables(rows, [_finding("expansion", "ar4_mp", 1.7, 3, 1, None)])
    assert tables[("ar4_mp", 1.7)]["cost"] == 5000.0
    # the series' own ended runs price it
    own = rows + [_row("ar4_mp_expansion_r1", "ar4_mp_expansion", 1.6, 1500.0, 5.0)]
    tables, _, _ = plan_tables(own, [_finding("expansion", "ar4_mp", 1.6, 6, 3, 1500.0)], ["ar4_mp_expansion"])
    assert tables[("ar4_mp_expansion", 1.6)]["cost"] == 1500.0 and tables[("ar4_mp_expansion", 1.6)]["from"] == 1


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
    path.write_text("# stage 3\n" + study_toml(stage3))
    return root, path, stage2, stage3


def test_a_round_brings_a_changed_shapes_replica_series_back_at_its_points_alone(composed, tmp_path):
    root, path, stage2, stage3 = composed
    assert addable_series(stage2, stage3) == ["ar1_expansion", "ar1_t95", "ar1_tall_t95"]  # AR-4 unchanged: none
    entry = lambda family, v, now, n: {"family": family, "u_over_umf": v, "from": now, "replicas": n,
                                       "more": n - now, "core_hours": 1.0, "why": [f"a finding asks {family}"]}
    # two series sharing stage 2's bed ar1_t95 in one round; a t95 series where its base runs 16 s (1.7 Umf)
    chosen = [entry("ar1_t95", 2.0, 0, 6), entry("ar1_t95", 1.7, 0, 4), entry("ar1_tall_t95", 2.9, 0, 3),
              entry("ar1", 1.6, 2, 3)]
    text = path.read_text() + round_toml(chosen, stage2, stage3, 1, ["round one"])
    trial = path.with_name("round.toml")
    trial.write_text(text)
    before = load_study(path, tmp_path / "before")
    after = load_study(trial, tmp_path / "after")
    count = lambda study: Counter((r.family, r.point["gas.u_over_umf"]) for r in study.runs)
    added = count(after) - count(before)
    assert added == Counter({("ar1_t95", 2.0): 6, ("ar1_t95", 1.7): 4, ("ar1_tall_t95", 2.9): 3, ("ar1", 1.6): 1})
    assert not count(before) - count(after)  # nothing lost
    runs = {r.name: r for r in after.runs}
    beds = {b.name: b for b in after.beds}
    base = {(r.family, r.point["gas.u_over_umf"]): r for r in after.runs}
    for r in after.runs:
        if not (r.family.startswith("ar1") and r.family.endswith("_t95")):
            continue
        twin = base[(r.family[:-4], r.point["gas.u_over_umf"])]  # the base family's run at its point
        # the base family's new settings and run length, the series' own stop, beds of its own seeds renamed
        assert {k: r.overrides[k] for k in CONTACT} == CONTACT and r.overrides["gas.inlet_ramp"] == 0.0
        assert r.overrides["time.stop_after_mixed"] == 0.0 and r.overrides["gas.umf"] == twin.overrides["gas.umf"]
        assert r.duration == twin.duration and r.priority == -1
        assert r.bed.startswith("ar1_t95_stage3") and {k: beds[r.bed].overrides[k] for k in BED} == BED
        seed = beds[r.bed].overrides["particles.insertion.seed"]  # stage 2's series seeds: from 201
        assert seed >= 201 and seed != beds[twin.bed].overrides.get("particles.insertion.seed")
        if r.family == "ar1_tall_t95":
            assert r.overrides["domain.upper"] == [0.15, 0.15, 2.1]
    assert {r.duration for r in after.runs if r.family == "ar1_t95" and r.point["gas.u_over_umf"] == 1.7} == {16.0}
    assert {n for n in runs if n.startswith("ar4")} == {r.name for r in before.runs if r.name.startswith("ar4")}
    # the expansion series: its own 5 s decides, after its base family's [[durations]]
    tables = series_tables(stage2, stage3, "ar1_expansion", [1.6])
    assert tables["durations"][-1] == {"family": "ar1_expansion", "duration": 5.0}
    assert tables["exclude"] == [1.7, 2.0, 2.3, 2.6, 2.9]
    # a later round narrows the exclusion a round wrote; one written otherwise is not the rounds' to change
    narrowed = narrow_exclude(text, "ar1_t95", [2.3])
    assert narrowed.count('"gas.u_over_umf" = [1.6, 2.6, 2.9]') == 1
    assert narrow_exclude(text, "ar1_tall", [1.6]) is None


def _archived(study, done=()) -> list:
    """The rows an archive of ``study`` (a loaded study) would hold: every run it plans, those of ``done``'s
    (family, U/Umf) ended at 3600 CPU s over 8 simulated s, the others pending."""
    return [{"name": r.name, "family": r.family, "gas.u_over_umf": r.point["gas.u_over_umf"],
             **({"status": "finished", "cpu_seconds": 3600.0, "simulated_seconds": 8.0}
                if (r.family, r.point["gas.u_over_umf"]) in done else {"status": "pending"})} for r in study.runs]


def test_the_round_tool_appends_a_round_once_and_waits_for_its_archive(composed, tmp_path, monkeypatch, capsys):
    """The tool on the findings' plans as data: a t95 plan for AR-1 at 2.0 Umf brings ``ar1_t95`` back; called
    again on the same archive it waits (the archive lacks the round's runs), and on the archive taken after the
    round it adds nothing (the round's runs are on their way); a later plan at 2.3 narrows the series' exclusion."""
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
    done = {("ar1", 2.0), ("ar1", 2.3), ("ar1", 1.7)}
    findings = [_finding("t95", "ar1", 2.0, 8, 2, 3600.0), _finding("whole", "ar1", 1.7, 30, 2, 3600.0)]
    records = {"rows": _archived(load_study(study, tmp_path / "a"), done), "findings": findings}
    monkeypatch.setattr(tool, "report_records", lambda archive, rebuild: (records["rows"], records["findings"]))
    args = [str(archive), "--study", str(study), "--stage2", str(STAGE2), "--json"]
    last = lambda: json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert tool.main(args) == 0
    said = last()
    assert said["round"] == 1 and [(e["family"], e["from"], e["replicas"]) for e in said["chosen"]] == [
        ("ar1_t95", 0, 6)]
    assert said["chosen"][0]["core_hours"] == pytest.approx(6.0)  # priced at ar1's whole runs there
    assert [e["family"] for e in said["left"]] == ["ar1"] and "28 core-hours" in said["left"][0]["left"]
    text = study.read_text()
    assert text.startswith(path.read_text()) and "# stage 3, round 1\n" in text
    planned = Counter((r.family, r.point["gas.u_over_umf"]) for r in load_study(study, tmp_path / "b").runs)
    assert planned[("ar1_t95", 2.0)] == 6 and sum(n for (f, _), n in planned.items() if f == "ar1_t95") == 6
    # the same archive again: it lacks the round's runs, so the tool waits and writes nothing
    assert tool.main(args) == 0
    said = last()
    assert said["written"] == [] and "archive the study again" in said["waiting"][0] and study.read_text() == text
    # archived after the round: the six are on their way, nothing to add
    records["rows"] = _archived(load_study(study, tmp_path / "c"), done)
    assert tool.main(args) == 0
    assert last()["chosen"] == [] and study.read_text() == text
    # a later plan asks the series at 2.3, where round 1 excluded it: the exclusion narrowed, the runs added
    records["findings"] = [_finding("t95", "ar1", 2.3, 6, 2, 3600.0)]
    assert tool.main(args) == 0
    said = last()
    assert said["round"] == 2 and [(e["family"], e["u_over_umf"]) for e in said["chosen"]] == [("ar1_t95", 2.3)]
    after = Counter((r.family, r.point["gas.u_over_umf"]) for r in load_study(study, tmp_path / "d").runs)
    assert after - planned == Counter({("ar1_t95", 2.3): 4}) and not planned - after
