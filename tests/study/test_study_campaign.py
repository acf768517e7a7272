"""The study engine on the paper's campaign (studies/mema2020_*.toml and its archives under docs/data/): a study
file of 163 runs in tiers, replicas and families of their own as the engine expands, ranks, queues and fits them
to a deadline, folders of an older definition named, and an archived study's table rebuilt by the generic report.
The engine's own tests run a synthetic study (test_study_engine.py)."""
import json
from dataclasses import replace
from pathlib import Path

import pytest

from fvdem.study import load_study, write_index
from fvdem.study.runner import _priority

from study_runs import ROOT


def test_the_papers_study_and_its_subset_are_the_runs_the_issue_names(tmp_path):
    full = load_study(ROOT / "studies" / "mema2020.toml", tmp_path)
    assert len(full.runs) == 22 and full.duration == 20.0
    families = {f: sorted(r.point["gas.u_over_umf"] for r in full.runs if r.family == f) for f in
                ("ar1", "ar4_mp", "ar4_sp", "ar4_mp_drag")}
    assert families["ar1"] == families["ar4_mp"] == families["ar4_sp"] == [1.6, 1.7, 2.0, 2.3, 2.6, 2.9]
    assert families["ar4_mp_drag"] == [1.6, 1.7, 2.0, 2.9]
    subset = load_study(ROOT / "studies" / "mema2020_subset.toml", tmp_path)
    assert sorted(r.name for r in subset.runs) == ["ar1_paper_u_over_umf2.9", "ar1_u_over_umf2", "ar1_u_over_umf2.9",
                                                   "ar4_mp_drag_u_over_umf2", "ar4_mp_u_over_umf2",
                                                   "ar4_mp_u_over_umf2.9"]
    defaults = [r for r in subset.runs if r.family != "ar1_paper"]
    assert subset.duration >= 6 and all(r.duration == subset.duration for r in defaults)
    assert all(r.overrides["contact.normal_stiffness"] == 800.0 for r in defaults)
    # one point repeated at the paper's own settings, from a bed settled at them
    paper = next(r for r in subset.runs if r.family == "ar1_paper")
    assert paper.overrides["contact.normal_stiffness"] == 2.0e4 and paper.overrides["time.dem_step"] == 1e-5
    assert paper.overrides["time.end"] == paper.duration == 4.5 and paper.bed == "ar1_paper"
    bed = next(b for b in subset.beds if b.name == "ar1_paper")
    assert bed.overrides["contact.normal_stiffness"] == 2.0e4 and bed.overrides["time.dem_step"] == 1e-5
    assert all(r.overrides["gas.inlet_ramp"] == 1.0 for r in full.runs + subset.runs)


def test_every_first_replica_starts_before_any_second_one_and_its_bed_between(tmp_path):
    """A campaign cut short has every point of the study once: the first replicas' runs outrank all second
    replicas' (whatever their length), a second replica's own bed settles after the first replicas have
    started and before the runs that need it."""
    from fvdem.study.runner import _bed_priority
    study = load_study(ROOT / "studies" / "mema2020_stage2.toml", tmp_path)
    # 22 points, two replicas each, but one of AR-4 SP at 2.6 and 2.9 Umf (their pinned rods cap the entropy) and
    # of AR-4 MP at 2.9 in the paper's 1.05 m column; AR-4 MP and SP at 2.9, SP at 2.3 and 2.6 and MP drag only at
    # 2.9 in a 2.1 m column, two replicas each (MP drag only there alone), and AR-1 at 2.6 and 2.9 there too
    # and, for the bed expansion at 1.6 and 1.7 Umf alone, AR-1 and AR-4 MP cut short after its window (5 s) from
    # beds of their own: two replicas of AR-1, four of AR-4 MP (the campaign's spreads: 0.01-0.09 and 0.45-0.66),
    # at 1.7 eleven of each, at 2.0 three of AR-4 MP; and the findings' plans at least
    # cost: at 1.6 Umf AR-4 MP to three and MP drag only to four (at priority 1), AR-4 MP cut short to six, at 2.0
    # AR-4 MP to three and drag only to five, AR-4 MP and MP drag only at 2.9 in the tall column, AR-1 at 2.3 and at
    # 2.9 in the tall column to three; then, a
    # tranche at priority -1 for the differences at 2.0 and 2.9 Umf, runs that end when they mix from beds of their
    # own (seeds from 201): at 2.0 eight of AR-1, six of AR-4 MP and four of drag only, at 2.9 in the tall column
    # six, four and four; and a second, the open findings' plan once the first had ended (at 2.0 44, 13 and 17, at
    # 2.9 16, 5 and 7), trimmed once one of them was decided: at 2.0 24, 10 and 10, at 2.9 10, 5 and 7
    assert len(study.runs) == 163 and {r.replica for r in study.runs} == set(range(1, 25))
    cut = {(r.family, r.point["gas.u_over_umf"]): [] for r in study.runs if r.family.endswith("_t95")}
    for r in study.runs:
        if r.family.endswith("_t95"):
            cut[(r.family, r.point["gas.u_over_umf"])].append((r.replica, r.bed, r.priority, r.duration,
                                                               r.overrides["time.stop_after_mixed"]))
    assert cut == {(f"ar{f}", v): [(k, f"ar{f[0]}_t95" + (f"_r{k}" if k > 1 else ""), -1, 8.0, 0.0)
                                   for k in range(1, n + 1)]
                   for f, v, n in (("1_t95", 2.0, 24), ("4_mp_t95", 2.0, 10), ("4_mp_drag_t95", 2.0, 10),
                                   ("1_tall_t95", 2.9, 10), ("4_mp_tall_t95", 2.9, 5), ("4_mp_drag_tall_t95", 2.9, 7))}
    assert {r.name for r in study.runs if r.priority == 1} == {
        f"ar4_mp{drag}_u_over_umf1.6_r{k}" for drag in ("", "_drag") for k in range(1, 4 + (drag != ""))}
    assert {r.priority for r in study.runs if not r.family.endswith("_t95") and r.priority != 1} == {0}
    listed = {e["name"]: e["stop_after_mixed"] for e in write_index(tmp_path, study)["runs"]}  # for --status
    assert listed["ar1_t95_u_over_umf2_r1"] == 0.0 and listed["ar1_u_over_umf2_r1"] == 2.0
    assert {r.overrides["domain.upper"][2] for r in study.runs if r.family.endswith("tall_t95")} == {2.1}
    seeds = {b.name: b.overrides.get("particles.insertion.seed") for b in study.beds if "_t95" in b.name}
    assert seeds == {**{f"ar1_t95{f'_r{k}' if k > 1 else ''}": 200 + k for k in range(1, 25)},
                     **{f"ar4_t95{f'_r{k}' if k > 1 else ''}": 200 + k for k in range(1, 11)}}
    study = replace(study, runs=tuple(r for r in study.runs if not r.family.endswith("_t95")),
                    beds=tuple(b for b in study.beds if "_t95" not in b.name))
    short = {r.name: (r.duration, r.bed) for r in study.runs if "expansion" in r.name}
    assert short == {f"ar{f}_expansion_u_over_umf{v:g}_r{k}": (5.0, f"ar{f[0]}_expansion" + (f"_r{k}" if k > 1 else ""))
                     for f, n in (("1", {1.6: 2, 1.7: 11}), ("4_mp", {1.6: 6, 1.7: 11, 2.0: 3})) for v in n
                     for k in range(1, n[v] + 1)}
    assert sorted((r.name, r.bed) for r in study.runs if r.replica > 2 and "expansion" not in r.name) == sorted(
        [(f"ar4_mp{drag}_u_over_umf{v}_r{k}", f"ar4_r{k}")
         for (drag, v), last in {("", "1.6"): 3, ("_drag", "1.6"): 4, ("", "2"): 3, ("_drag", "2"): 5}.items()
         for k in range(3, last + 1)]
        + [("ar4_mp_tall_u_over_umf2.9_r3", "ar4_r3"), ("ar4_mp_drag_tall_u_over_umf2.9_r3", "ar4_r3"),
           ("ar1_u_over_umf2.3_r3", "ar1_r3"),
           ("ar1_tall_u_over_umf2.9_r3", "ar1_r3")])
    assert {r.name for r in study.runs if "tall" in r.name} == {
        f"ar{point}_r{k}" for point in ("4_mp_tall_u_over_umf2.9", "4_mp_drag_tall_u_over_umf2.9",
                                        "4_sp_tall_u_over_umf2.3", "4_sp_tall_u_over_umf2.6",
                                        "4_sp_tall_u_over_umf2.9",
                                        "1_tall_u_over_umf2.6", "1_tall_u_over_umf2.9") for k in (1, 2)} | {
        "ar4_mp_tall_u_over_umf2.9_r3", "ar4_mp_drag_tall_u_over_umf2.9_r3", "ar1_tall_u_over_umf2.9_r3"}
    first = [_priority(r) for r in study.runs if r.replica == 1]
    second = [_priority(r) for r in study.runs if r.replica == 2]
    third = [_priority(r) for r in study.runs if r.replica == 3]
    assert min(first) > max(second) and min(second) > max(third)
    assert max(first) == 20.0 / 5e-5  # then longest first within a replica (the [[durations]] points: 20 s)
    beds = {b.name: _bed_priority(b) for b in study.beds}
    assert set(beds) == {"ar1", "ar4", "ar1_r2", "ar4_r2", "ar1_r3", "ar4_r3", "ar4_r4", "ar4_r5", "ar1_expansion",
                         "ar4_expansion",
                         *(f"ar1_expansion_r{k}" for k in range(2, 12)), *(f"ar4_expansion_r{k}" for k in range(2, 12))}
    # insertion seeds from 101: no expansion run starts from a bed a full run starts from
    seeds = {b.name: b.overrides.get("particles.insertion.seed") for b in study.beds}
    assert {seeds[b] for b in seeds if "expansion" in b} == set(range(101, 112)) and seeds["ar4_expansion_r4"] == 104
    assert seeds["ar1_expansion_r11"] == 111 and seeds["ar4_expansion_r11"] == 111
    assert seeds["ar4_r3"] == seeds["ar1_r3"] == 3 and seeds["ar4_r4"] == 4 and seeds["ar4_r5"] == 5
    assert min(beds["ar1"], beds["ar4"]) > max(first)
    assert min(first) > beds["ar1_r2"] == beds["ar4_r2"] > max(second) and max(second) > beds["ar4_r3"] > max(third)


def test_runs_with_more_dem_steps_left_start_first(tmp_path):
    study = load_study(ROOT / "studies" / "mema2020_subset.toml", tmp_path)
    priority = {r.name: _priority(r) for r in study.runs}
    # 4.5 s at the paper's 1e-5 s DEM step is more steps than 6 s at the defaults' 5e-5 s
    assert priority["ar1_paper_u_over_umf2.9"] == pytest.approx(4.5 / 1e-5, rel=1e-6)
    assert priority["ar1_u_over_umf2"] == pytest.approx(6.0 / 5e-5, rel=1e-6)


def test_runs_in_progress_go_before_every_run_not_started(tmp_path):
    """A campaign stopped and continued finishes what it began: a run with simulated time in its folder (not at
    its end) outranks every run not started, whatever its replica, and the nearest its end goes first; the
    beds still come first."""
    from fvdem.study.runner import BED_RANK
    study = load_study(ROOT / "studies" / "mema2020_stage2.toml", tmp_path)
    by_name = {r.name: r for r in study.runs}
    fresh = max(_priority(r) for r in study.runs)
    for name, so_far in (("ar1_u_over_umf2_r2", 1.0), ("ar4_mp_u_over_umf1.6_r2", 15.0)):
        folder = Path(by_name[name].folder)
        folder.mkdir(parents=True)
        (folder / "summary.json").write_text(json.dumps({"simulated_time": so_far, "stopped_early": True}))
    near, far = _priority(by_name["ar4_mp_u_over_umf1.6_r2"]), _priority(by_name["ar1_u_over_umf2_r2"])
    assert BED_RANK > near > far > fresh  # 5 s left before 7 s left, both before any first replica not started
    # a run at its end is not in progress
    (Path(by_name["ar1_u_over_umf2_r2"].folder) / "summary.json").write_text(json.dumps({"simulated_time": 8.0}))
    assert _priority(by_name["ar1_u_over_umf2_r2"]) < fresh


def test_the_queue_hands_on_runs_one_free_slot_at_a_time_in_the_order_of_their_folders_now(tmp_path):
    """Dask orders tasks by priority only on one worker, so the study holds its runs back and hands on as
    many as there are free slots, the first by ``_priority`` as read from the run folders at that moment: a run
    that has begun since the queue was made goes before every run not started."""
    from fvdem.study.runner import _Queue
    study = load_study(ROOT / "studies" / "mema2020_stage2.toml", tmp_path)
    queue = _Queue(study.runs, 2)
    ended, first = queue.take(0)
    # the study file's priority 1 (AR-4 MP and drag only at 1.6 Umf) first, first replicas before second ones
    assert ended == [] and [r.name for r in first] == ["ar4_mp_u_over_umf1.6_r1", "ar4_mp_drag_u_over_umf1.6_r1"]
    assert queue.take(2) == ([], []) and len(queue) == 161
    late = next(r for r in study.runs if r.name == "ar4_sp_u_over_umf2.3_r2")
    Path(late.folder).mkdir(parents=True)
    (Path(late.folder) / "summary.json").write_text(json.dumps({"simulated_time": 0.5, "stopped_early": True}))
    assert [r.name for r in queue.take(1)[1]] == ["ar4_sp_u_over_umf2.3_r2"]  # begun elsewhere: in progress now
    done = next(r for r in study.runs if r.name == "ar1_u_over_umf2.9_r1")  # at its end: handed on at once
    Path(done.folder).mkdir(parents=True)
    (Path(done.folder) / "summary.json").write_text(json.dumps({"simulated_time": 8.0}))
    ended, taken = queue.take(2)
    assert [r.name for r in ended] == ["ar1_u_over_umf2.9_r1"] and taken == [] and len(queue) == 159
    sizes = iter([3, 1])
    live = _Queue(study.runs[:5], lambda: next(sizes))  # a running cluster's threads, read at each take
    assert len(live.take(0)[1]) == 3
    assert live.take(3) == ([], [])  # the cluster is down to one thread: nothing more until runs end
    assert len(live.drain()) == 2 and len(live) == 0


def test_with_a_deadline_the_runs_expected_to_end_by_it_start_first(tmp_path, monkeypatch):
    """``until``: a freed slot goes first to the runs expected to end before the deadline (their expected
    simulated seconds left at their family's CPU seconds per simulated second, ``study_status``), in
    ``_priority`` order among themselves, then the others; a slot is not left idle."""
    import shutil
    import time

    import fvdem.provenance
    # read on a processor none of the archive's runs ran on: the rates as measured (on one of theirs the status
    # scales them to it: tests/unit/test_locks.py)
    monkeypatch.setattr(fvdem.provenance, "cpu_model", lambda: "a processor of its own")

    from fvdem.study.runner import _Queue, _bed_wall, _expected_wall, _fitting
    from fvdem.study.status import study_status
    archive = tmp_path / "archive"
    shutil.copytree(ROOT / "docs" / "data" / "mema2020", archive)
    short, long = "ar1_u_over_umf2_r2", "ar4_mp_u_over_umf1.6_r2"  # two ended runs, made not started again
    for name in (short, long):
        shutil.rmtree(archive / "runs" / name)
    status = study_status(archive)
    wall = _expected_wall(archive, 2)
    for r in status["runs"]:  # each run's expected wall time: its expected seconds left at its family's rate
        family = status["families"][r["family"]]
        if family["cpu_per_simulated_second"] is not None:
            assert wall[r["name"]] == pytest.approx(r["expected_left"] * family["cpu_per_simulated_second"] / 2)
        else:  # none measured: its kin's pooled rate (a "_t95" family's base, and its cut-short kin where measured)
            rates = [status["families"][k]["cpu_per_simulated_second"] for k in family["rate_from"]]
            assert (r["expected_left"] * min(rates) / 2 * (1 - 1e-9) <= wall[r["name"]]
                    <= r["expected_left"] * max(rates) / 2 * (1 + 1e-9))
    assert 0 < wall[short] < wall[long]  # AR-1 to where its first replica ended (8 s), AR-4 MP to 20 s
    left = {name: seconds for name, seconds in wall.items() if seconds > 0}
    cut = (wall[short] + wall[long]) / 2
    study = load_study(ROOT / "studies" / "mema2020_stage2.toml", archive)
    fitting = _fitting(archive, study.runs, time.time() + cut, 2)
    names = {r.name for r in study.runs}
    assert {n for n, w in wall.items() if w <= cut - 5.0} & names <= fitting <= {n for n, w in wall.items() if w <= cut}
    assert short in fitting and long not in fitting
    # a run whose bed has not settled yet waits for it too: the settled beds' CPU seconds of its case file (of
    # every settled bed where none of its case has), over the threads; nothing added where none has settled
    bed_of = {r.name: r.bed for r in study.runs}
    beds = {b.name: b for b in study.beds}
    assert bed_of[short] == "ar1_r2" and bed_of[long] == "ar4_r2"
    assert _fitting(archive, study.runs, time.time() + wall[short] + 30.0, 2, study.beds) >= {short}
    for name, cpu in (("ar1", 80.0), ("ar1_expansion", 60.0), ("ar4", 180.0)):
        folder = Path(beds[name].folder)
        folder.mkdir(parents=True)
        (folder / "final_state.npz").write_bytes(b"")
        (folder / "summary.json").write_text(json.dumps({"cpu_seconds": cpu, "simulated_time": 0.4}))
    stopped = Path(beds["ar4_r3"].folder)  # a bed stopped early has not settled: it waits too, and is no measure
    stopped.mkdir(parents=True)
    (stopped / "final_state.npz").write_bytes(b"")
    (stopped / "summary.json").write_text(json.dumps({"cpu_seconds": 9.0, "stopped_early": True}))
    settle = _bed_wall(study.beds, study_status(archive)["beds"], 2)
    assert settle["ar1_r2"] == pytest.approx(70.0 / 2) and settle["ar4_r2"] == pytest.approx(180.0 / 2)
    assert settle["ar4_r3"] == pytest.approx(90.0) and "ar4" not in settle and "ar1" not in settle
    assert settle["ar4_expansion"] == pytest.approx(90.0)  # bed_ar4.toml's settled bed
    assert short not in _fitting(archive, study.runs, time.time() + wall[short] + 30.0, 2, study.beds)
    assert short in _fitting(archive, study.runs, time.time() + wall[short] + 40.0, 2, study.beds)
    shortest = min((n for n in left if n in names), key=left.get)
    # within one tier (the study file's priority 1, and the top tier a run in progress joins, set aside: priorities
    # rank above the deadline, test_a_lower_priority_tranche_starts_only_once_the_runs_queued_before_it_have_started)
    flat = [replace(r, priority=0) for r in study.runs if r.name in left]
    queue = _Queue(flat, 1, fits=lambda runs: {shortest})
    assert [r.name for r in queue.take(0)[1]] == [shortest]  # before every run in progress or longer
    plain = _Queue(flat, 1)
    nothing = _Queue(flat, 1, fits=lambda runs: set())
    assert [r.name for r in nothing.take(0)[1]] == [r.name for r in plain.take(0)[1]]  # none fits: as without


def test_folders_started_under_another_definition_are_named_with_the_keys_that_differ(tmp_path):
    """A study file changed since its runs began (a family's setting): each folder whose case.toml holds other
    physics than the study now sets is listed with the keys (before -> now); a run whose bed changed is listed
    with it; folders of unchanged runs, restored ones (their bed's state elsewhere) and run settings that a
    resumed run may change (time.end, output.*) are not."""
    from fvdem.case import load_case, to_toml
    from fvdem.study.folders import changed_folders
    text = (ROOT / "studies" / "mema2020_stage2.toml").read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
    path = tmp_path / "stage2.toml"
    path.write_text(text)
    study = load_study(path, tmp_path / "out")
    runs = {r.name: r for r in study.runs}
    beds = {b.name: b for b in study.beds}

    def started(spec, **more):
        Path(spec.folder).mkdir(parents=True)
        case = load_case(spec.case, {**spec.overrides, **more})
        Path(spec.folder, "case.toml").write_text(to_toml(case))
    for name in ("ar1_u_over_umf2_r1", "ar4_sp_u_over_umf1.6_r1", "ar4_mp_u_over_umf2.6_r2"):
        started(runs[name], **{"time.end": 30.0, "output.snapshot_interval": 1.0,
                               "particles.initial_state": str(tmp_path / "elsewhere" / "final_state.npz")})
    started(beds["ar1_r2"])
    # a case.toml written by an older fvdem, before a key existed: the run ran as the key's default runs
    older = Path(runs["ar1_u_over_umf2_r1"].folder, "case.toml")
    text_then = older.read_text()
    older.write_text(text_then.replace("\nscheme = ", "\n# scheme = ").replace("\ncount = ", "\n# count = "))
    assert "\nscheme" not in older.read_text() and "\ncount" not in older.read_text()
    assert [(spec.name, keys) for spec, keys in changed_folders(study)] == [  # the bed's count is not the default's
        ("ar1_u_over_umf2_r1", "particles.count: 1000 -> 32500")]
    older.write_text(text_then.replace("\nscheme = ", "\n# scheme = "))  # the scheme at its default: as before
    assert changed_folders(study) == []
    # the SP family's reference velocity and the second AR-1 bed's insertion seed changed since
    path.write_text(text.replace('set = {"gas.umf" = 1.896}  # the AR-4 bed', 'set = {"gas.umf" = 1.7}  #').replace(
        '[beds.ar1]\ncase = "', '[beds.ar1]\nset = {"particles.insertion.seed" = 7}\ncase = "'))
    started(runs["ar1_u_over_umf1.7_r2"])
    listed = {spec.name: keys for spec, keys in changed_folders(load_study(path, tmp_path / "out"))}
    assert listed == {
        "ar4_sp_u_over_umf1.6_r1": "gas.inlet_velocity: 3.0336 -> 2.72; gas.umf: 1.896 -> 1.7",
        "ar1_r2": "particles.insertion.seed: 2 -> 8",  # replica 2's own bed: the seed + 1
        "ar1_u_over_umf1.7_r2": "its bed ar1_r2 changed"}


def test_the_generic_report_writes_the_table_alone(tmp_path):
    """The ``table`` report of the archived stage-1 runs: the generic columns and the costs, no figures, no
    findings; the default report of the same runs adds seed 000's columns, figures and findings."""
    from shutil import copytree

    from fvdem.study import report
    archived = ROOT / "docs" / "data" / "mema2020_stage1"
    for name in ("table", "mema2020"):
        folder = copytree(archived, tmp_path / name)
        index = json.loads((folder / "study.json").read_text())
        (folder / "study.json").write_text(json.dumps({**index, "report": name}))
        written = {p.name for p in report(folder)}
        rows = json.loads((folder / "table.json").read_text())
        if name == "table":
            assert written == {"table.csv", "table.json", "costs.json", "costs.md"}
            costs = json.loads((folder / "costs.json").read_text())  # 14 runs: 12 families and points, 1 processor
            assert sum(c["runs"] for c in costs) == 14 and {c["processor"] for c in costs} == {"not recorded"}
            assert set(rows[0]) == {"name", "family", "gas.u_over_umf", "status", "wall_seconds",
                                    "simulated_seconds", "duration", "replica"}
        else:
            assert {"findings.json", "t95.png"} <= written and "t95" in rows[0] and "void_fraction_binarity" in rows[0]


@pytest.mark.parametrize("path", sorted((ROOT / "studies").glob("*.toml")), ids=lambda p: p.stem)
def test_every_study_file_loads_and_names_its_runs_cases_and_beds(path, tmp_path):
    """Each study file of the repository expands (its families, design, points and beds resolved against its
    case files) with every run's bed among the study's beds: a file edited for a campaign cannot wait until the
    campaign's machine to find a typo."""
    study = load_study(path, tmp_path)
    beds = {b.name for b in study.beds}
    assert study.runs and all(r.bed is None or r.bed in beds for r in study.runs)
    assert len({r.name for r in study.runs}) == len(study.runs)
