"""The study engine (fvdem.study) on small and synthetic studies: a study file expands into checked runs, each
run a task that is skipped at its end, resumed from its checkpoint or reported failed with its cause; the index
(study.json), the queue's order, stop files and deadlines, the generic table, costs, archives and restores, folders
of another definition. The paper's report has its own files (tests/reports/test_mema2020_report.py,
test_mema2020_rules.py); the Dask clusters and batch jobs theirs (test_study_cluster.py)."""
import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from fvdem.case import CaseError
from fvdem.study import STOP_FILE, RunSpec, write_index, load_study, request_stop, run_task, select_runs

from paths import TOOLS
from study_runs import ROOT, SMOKE, fake_run, one_run_study, small_run, synthetic_study, synthetic_text


def test_the_study_files_expand_into_checked_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    smoke = load_study(SMOKE, "relative/out")  # make smoke passes a relative --out
    assert all(Path(r.folder).is_absolute() and Path(r.folder).is_relative_to(tmp_path) for r in smoke.runs)
    assert Path(smoke.beds[0].folder) == tmp_path / "relative" / "out" / "beds" / "small"
    assert [r.name for r in smoke.runs] == ["ar1_u_over_umf2", "ar1_u_over_umf2.9"]
    assert [b.name for b in smoke.beds] == ["small"] and all(r.bed == "small" for r in smoke.runs)
    assert smoke.runs[1].overrides["gas.u_over_umf"] == 2.9 and smoke.runs[1].overrides["time.end"] == 0.02


def test_a_wrong_study_is_refused_with_every_key_path_before_anything_runs(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text(f'''name = "bad"
duration = -1
colour = "red"
[families.a]
case = "{ROOT / 'cases' / 'demo.toml'}"
bed = "nowhere"
[families.a.set]
"particles.count" = -5
[axes]
"gas.u_over_umf" = [2.0]
''')
    with pytest.raises(CaseError) as failure:
        load_study(path, tmp_path / "out")
    text = "\n".join(failure.value.problems)
    assert "duration = -1" in text and "colour = 'red': unknown key" in text
    assert "families.a.bed = 'nowhere'" in text and "a_u_over_umf2: particles.count = -5" in text
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(path), "--out", str(tmp_path / "o")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "Traceback" not in result.stderr and not (tmp_path / "o").exists()


def test_a_failing_run_comes_back_with_its_cause():
    run = RunSpec("broken", "ar1", str(ROOT / "cases" / "ar1.toml"), {"time.end": 0.01}, "/nonexistent/run")
    result = run_task(run, 1, bed_state="/nonexistent/final_state.npz")
    assert result["status"] == "failed" and "does not exist" in result["error"]


def test_a_run_that_fails_mid_run_comes_back_with_the_last_lines_of_its_log(tmp_path, monkeypatch):
    """Inside a study worker a run's warnings and its end go to its run.log; a failure reports the log's tail."""
    import fvdem.simulation as simulation
    from fvdem.dem.system import SimulationError
    _, run = small_run(tmp_path, 0.02)
    original = simulation.Model.advance

    def advance_then_fail(self, steps):
        original(self, steps)
        if self.time >= 0.004:
            raise SimulationError("non-finite particle velocity (a stand-in failure)")
    monkeypatch.setattr(simulation.Model, "advance", advance_then_fail)
    result = run_task(run, 1)
    assert result["status"] == "failed" and "stand-in failure" in result["error"]
    tail = "\n".join(result["log_tail"])
    assert "started: demo" in tail and "error at t = 0.004" in tail and "stand-in failure" in tail


def test_a_findings_numbers_read_as_one_line():
    from fvdem.study.reports import describe_values
    assert describe_values({"1.6": {"ar4_mp": "> 20 (not mixed)", "ar1": 16.901617}, "2": {"ar1": [1.7301, 2.0]}}) \
        == "1.6: (ar4_mp: > 20 (not mixed); ar1: 16.9); 2: (ar1: 1.73, 2)"
    assert describe_values(3.0) == "3" and describe_values(None) == "None"


def test_only_selects_runs_and_their_beds_and_refuses_a_name_the_study_lacks(tmp_path):
    study = load_study(synthetic_study(tmp_path), tmp_path)
    one = select_runs(study, ["ar1_u_over_umf2.9"])
    assert [r.name for r in one.runs] == ["ar1_u_over_umf2.9"] and [b.name for b in one.beds] == ["small"]
    assert select_runs(study, None) is study
    with pytest.raises(CaseError) as err:
        select_runs(study, ["ar1_u_over_umf3"])
    assert "ar1_u_over_umf3" in str(err.value) and "ar1_u_over_umf2.9" in str(err.value)
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(synthetic_study(tmp_path)), "--out",
                             str(tmp_path / "s"), "--only", "nope"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "Traceback" not in result.stderr and "nope" in result.stderr


def test_a_familys_own_duration_and_a_wrong_one(tmp_path):
    text = synthetic_text().replace('bed = "small"', 'bed = "small"\nduration = 0.05', 1)
    path = tmp_path / "study.toml"
    path.write_text(text)
    runs = load_study(path, tmp_path / "out").runs
    assert all(r.duration == 0.05 and r.overrides["time.end"] == 0.05 for r in runs)
    path.write_text(text.replace("duration = 0.05", 'duration = "long"'))
    with pytest.raises(CaseError) as err:
        load_study(path, tmp_path / "out")
    assert "families.ar1.duration" in str(err.value) and "'long'" in str(err.value)


def test_durations_tables_give_the_runs_they_match_their_own_duration_and_a_wrong_one_is_refused(tmp_path):
    text = synthetic_text()
    assert "[[durations]]" not in text and '"gas.u_over_umf" = [2.0, 2.9]' in text
    # a second family beside ar1
    text = text.replace("[axes]", f'[families.b]\ncase = "{ROOT / "cases" / "demo.toml"}"\nbed = "small"\n\n[axes]')
    path = tmp_path / "study.toml"
    path.write_text(text + '\n[[durations]]\n"gas.u_over_umf" = [2.0]\nduration = 0.05\n'
                    '\n[[durations]]\nfamily = "ar1"\n"gas.u_over_umf" = 2.0\nduration = 0.07\n')
    study = load_study(path, tmp_path / "out")
    runs = {(r.family, r.point["gas.u_over_umf"]): r for r in study.runs}
    assert len(runs) == 4
    for (family, ratio), run in runs.items():  # the last matching table decides; unmatched runs keep the study's
        expected = (0.07 if family == "ar1" else 0.05) if ratio == 2.0 else study.duration
        assert run.duration == expected and run.overrides["time.end"] == expected, (family, ratio)
    _refused_tables(path, text, "durations", (
        ('"gas.u_over_umf" = 1.6\nduration = 1.0', "durations[0].gas.u_over_umf", "1.6"),
        ('family = "ar9"\nduration = 1.0', "durations[0].family", "'ar9'"),
        ('"gas.umf" = 1.9\nduration = 1.0', "durations[0].gas.umf", "1.9"),
        ('family = "ar1"\nduration = -2', "durations[0].duration", "-2")))
    path.write_text('durations = 3\n' + text)
    with pytest.raises(CaseError) as err:
        load_study(path, tmp_path / "out")
    assert "durations" in str(err.value) and "[[durations]]" in str(err.value)


def test_points_tables_add_replicas_where_two_lie_within_their_spread_and_leave_the_runs_before_alone(tmp_path):
    """[[points]]: a third replica at one point (a finding open within the replicas' spread), from its own
    settled bed; the runs and beds the study had keep their names, and so their folders. A family of one
    replica raised at one point keeps its first run's unsuffixed name. Wrong tables are refused by key."""
    text = synthetic_text()
    path = tmp_path / "study.toml"
    two = text.replace('bed = "small"', 'bed = "small"\nreplicas = 2', 1)
    path.write_text(two)
    before = load_study(path, tmp_path / "out")
    path.write_text(two + '\n[[points]]\nfamily = "ar1"\n"gas.u_over_umf" = 2.0\nreplicas = 3\nduration = 0.05\n')
    after = load_study(path, tmp_path / "out")
    added = [r for r in after.runs if r.name not in {b.name for b in before.runs}]
    assert [r.name for r in added] == ["ar1_u_over_umf2_r3"] and added[0].bed == "small_r3"
    kept = {r.name: r for r in after.runs}  # the same folders, the same physics (a duration is not physics)
    assert all(kept[r.name].folder == r.folder and kept[r.name].physics == r.physics for r in before.runs)
    assert {r.name: r.duration for r in after.runs if r.point["gas.u_over_umf"] == 2.0} == {
        "ar1_u_over_umf2_r1": 0.05, "ar1_u_over_umf2_r2": 0.05, "ar1_u_over_umf2_r3": 0.05}
    assert "small_r3" in [b.name for b in after.beds]
    path.write_text(text + '\n[[points]]\n"gas.u_over_umf" = 2.9\nreplicas = 2\n')
    names = [r.name for r in load_study(path, tmp_path / "out").runs]
    assert names == ["ar1_u_over_umf2", "ar1_u_over_umf2.9", "ar1_u_over_umf2.9_r2"]
    _refused_tables(path, text, "points", (
        ('"gas.u_over_umf" = 2.0\nreplicas = 0', "points[0].replicas", "0"),
        ('"gas.u_over_umf" = 2.0', "points[0]", "sets none of duration, replicas"),
        ('family = "ar9"\nreplicas = 2', "points[0].family", "'ar9'"),
        ('"gas.u_over_umf" = 2.0\nreplica = 2', "points[0].replica", "did you mean")))


def test_a_lower_priority_tranche_starts_only_once_the_runs_queued_before_it_have_started(tmp_path):
    """``priority`` (a family's, or a [[points]] table's): a run of a lower tier is handed on only once every
    run of the tiers above has been, whatever its replica and even where it fits a deadline and they do not;
    a run in progress counts in the top tier. Without priorities the order is the replicas' (a new family's
    first replica before an earlier family's second). A wrong priority is refused by key."""
    from fvdem.study.runner import _Queue
    from fvdem.study.status import format_status, study_status
    text = synthetic_text()
    text = text.replace('bed = "small"', 'bed = "small"\nreplicas = 2', 1)
    text = text.replace("[axes]", f'[families.late]\ncase = "{ROOT / "cases" / "demo.toml"}"\nbed = "small"\n'
                        'set = {"particles.count" = 150}\n\n[axes]')
    path = tmp_path / "study.toml"
    path.write_text(text)
    plain = load_study(path, tmp_path / "out")
    assert {r.priority for r in plain.runs} == {0}
    first = [r.name for r in _Queue(plain.runs, 6).take(0)[1]]
    assert first.index("late_u_over_umf2") < first.index("ar1_u_over_umf2_r2")  # replicas first, without tiers
    path.write_text(text + '\n[[points]]\nfamily = "late"\npriority = -1\n')
    study = load_study(path, tmp_path / "out")
    tiers = {r.name: r.priority for r in study.runs}
    assert tiers == {"ar1_u_over_umf2_r1": 0, "ar1_u_over_umf2.9_r1": 0, "ar1_u_over_umf2_r2": 0,
                     "ar1_u_over_umf2.9_r2": 0, "late_u_over_umf2": -1, "late_u_over_umf2.9": -1}
    queue = _Queue(study.runs, 6, fits=lambda runs: {"late_u_over_umf2", "late_u_over_umf2.9"})
    taken = [r.name for r in queue.take(0)[1]]
    assert set(taken[:4]) == {n for n, t in tiers.items() if t == 0} and set(taken[4:]) == {
        "late_u_over_umf2", "late_u_over_umf2.9"}  # though only the late ones fit
    (tmp_path / "out").mkdir()
    assert write_index(tmp_path / "out", study)["runs"][-1]["priority"] == -1  # --status says why they wait
    assert ("2 of the runs not started wait at priority -1 (the study file's), until every run of a higher priority "
            "has started: late") in format_status(study_status(tmp_path / "out"))
    queue = _Queue(study.runs, 1)
    begun = next(r for r in study.runs if r.name == "late_u_over_umf2.9")
    Path(begun.folder).mkdir(parents=True)
    (Path(begun.folder) / "summary.json").write_text(json.dumps({"simulated_time": 0.01, "stopped_early": True}))
    assert [r.name for r in queue.take(0)[1]] == ["late_u_over_umf2.9"]  # in progress: the top tier
    assert [r.name for r in queue.take(0)[1]][0].startswith("ar1_")
    path.write_text(text.replace('bed = "small"\nreplicas = 2', 'bed = "small"\nreplicas = 2\npriority = 3', 1))
    assert {r.priority for r in load_study(path, tmp_path / "out").runs if r.family == "ar1"} == {3}
    path.write_text(text.replace('bed = "small"\nreplicas = 2', 'bed = "small"\nreplicas = 2\npriority = "low"', 1))
    with pytest.raises(CaseError) as err:
        load_study(path, tmp_path / "out")
    assert "families.ar1.priority = 'low': an integer -1000-1000" in str(err.value)
    _refused_tables(path, text, "points", (
        ('family = "late"\npriority = 2000', "points[0].priority", "2000"),
        ('family = "late"\npriority = true', "points[0].priority", "True"),
        ('family = "late"\npriorty = -1', "points[0].priorty", "did you mean 'priority'")))


def test_exclude_tables_leave_out_the_runs_they_match_and_a_wrong_one_is_refused(tmp_path):
    """[[exclude]]: family and axis values, each one value or a list (as [[durations]] and [[points]]); a misspelt
    key or a value the study lacks would leave out nothing, silently, and an empty table every run: refused."""
    text = synthetic_text()
    text = text.replace("[axes]", f'[families.b]\ncase = "{ROOT / "cases" / "demo.toml"}"\nbed = "small"\n\n[axes]')
    path = tmp_path / "study.toml"
    path.write_text(text + '\n[[exclude]]\nfamily = ["ar1", "b"]\n"gas.u_over_umf" = 2.9\n'
                    '\n[[exclude]]\nfamily = "b"\n"gas.u_over_umf" = [2.0]\n')
    assert [r.name for r in load_study(path, tmp_path / "out").runs] == ["ar1_u_over_umf2"]
    _refused_tables(path, text, "exclude", (
        ('famly = "ar1"', "exclude[0].famly", "did you mean 'family'"),
        ('family = "ar9"', "exclude[0].family", "'ar9'"),
        ('"gas.u_over_umf" = [2.0, 1.6]', "exclude[0].gas.u_over_umf", "[2.0, 1.6]")))
    path.write_text(text + "\n[[exclude]]\n")
    with pytest.raises(CaseError) as err:
        load_study(path, tmp_path / "out")
    assert "exclude[0] = {}" in str(err.value) and "every run" in str(err.value)


def _refused_tables(path, text, heading, cases):
    """Each ``(table, key, shown)``: the study ``text`` with that ``[[heading]]`` table is refused, naming the key
    path and the value."""
    for table, key, shown in cases:
        path.write_text(text + f"\n[[{heading}]]\n" + table + "\n")
        with pytest.raises(CaseError) as err:
            load_study(path, path.parent / "out")
        assert key in str(err.value) and shown in str(err.value), str(err.value)


def test_the_stop_file_checkpoints_a_running_run_and_keeps_queued_runs_from_starting(tmp_path):
    """A run polls its study's STOP file between chunks: it stops with a checkpoint, comes back
    'stopped', does not count as finished, and the next invocation resumes it to the end."""
    out, run = small_run(tmp_path, 0.02)
    out.mkdir(parents=True)
    request_stop(out)  # before the start: the run does not start
    assert run_task(run, 1)["status"] == "stopped" and not Path(run.folder).exists()
    (out / STOP_FILE).unlink()

    import fvdem.simulation as simulation
    original = simulation.Model.advance

    def advance_then_stop(self, steps):  # the request arrives while the run is running
        original(self, steps)
        if self.time >= 0.004:
            request_stop(out)
    simulation.Model.advance = advance_then_stop
    try:
        stopped = run_task(run, 1)
    finally:
        simulation.Model.advance = original
    assert stopped["status"] == "stopped" and 0.004 <= stopped["simulated_seconds"] < 0.02
    assert (Path(run.folder) / "checkpoint.npz").exists()
    (out / STOP_FILE).unlink()
    resumed = run_task(run, 1)
    assert resumed["status"] == "resumed" and resumed["simulated_seconds"] == pytest.approx(0.02)
    assert run_task(run, 1)["status"] == "skipped"
    # a longer duration (a [[durations]] table added after the run finished) continues it from its end
    from dataclasses import replace
    longer = replace(run, duration=0.024, overrides={**run.overrides, "time.end": 0.024})
    extended = run_task(longer, 1)
    assert extended["status"] == "resumed" and extended["simulated_seconds"] == pytest.approx(0.024)
    assert "resumed at t = 0.02 s" in (Path(run.folder) / "run.log").read_text()


def test_the_index_lists_every_run_and_a_partial_invocation_keeps_the_others_results(tmp_path):
    out = tmp_path / "study"
    study = load_study(synthetic_study(tmp_path), out)
    out.mkdir()
    first, second = (r.name for r in study.runs)
    index = write_index(out, study)
    assert [(r["name"], r["status"]) for r in index["runs"]] == [(first, "pending"), (second, "pending")]
    write_index(out, study, [{"name": first, "status": "finished", "t95": 1.0}])
    # --only the second: the first keeps its result
    index = write_index(out, select_runs(study, [second]), [{"name": second, "status": "failed"}])
    assert {r["name"]: r["status"] for r in index["runs"]} == {first: "finished", second: "failed"}
    assert json.loads((out / "study.json").read_text())["runs"] == index["runs"]
    # a run taken out of the study file (a replica or a point the study no longer plans) leaves the index where it
    # never started, and stays where its folder holds something: nothing on disk goes unlisted
    from dataclasses import replace
    fewer = replace(study, runs=study.runs[:1])
    assert [r["name"] for r in write_index(out, fewer)["runs"]] == [first]
    write_index(out, study, [{"name": second, "status": "stopped", "folder": str(out / "runs" / second)}])
    (out / "runs" / second).mkdir(parents=True)
    assert [r["name"] for r in write_index(out, fewer)["runs"]] == [first, second]
    # --only keeps the planned runs it leaves out, started or not
    (out / "runs" / second).rmdir()
    assert [r["name"] for r in write_index(out, select_runs(study, [first]))["runs"]] == [first, second]
    # and lists, pending, those it leaves out that the index never had (runs new in the study file, started with
    # --only: the campaign's expansion families, 2026-12-05, whose index read 55 runs of the file's 63)
    (out / "study.json").unlink()
    index = write_index(out, select_runs(study, [first]), [{"name": first, "status": "finished", "t95": 1.0}])
    assert [(r["name"], r["status"]) for r in index["runs"]] == [(first, "finished"), (second, "pending")]
    assert index["runs"][1]["duration"] == study.runs[1].duration and index["runs"][1]["replica"] == 1


def test_a_run_taken_out_of_the_study_file_after_it_began_is_not_planned_and_supersede_moves_it(tmp_path):
    """A replica taken out of the study file while it was in progress stayed in the index, and so in ``--status``,
    "in progress" and counted in what is left, for good (the campaign's fifth AR-4 MP bed cut short at 1.6 Umf,
    2026-12-05, moved aside by hand): it is listed not planned, neither counted nor waited for,
    back to planned where the file lists it again, and ``--supersede`` moves its folder to superseded/."""
    from fvdem.cli import _changed_folders
    from fvdem.study import report
    from fvdem.study.reports import findings_page
    from fvdem.study.status import format_status, study_status
    out = tmp_path / "study"
    study = load_study(synthetic_study(tmp_path), out)
    out.mkdir()
    first, second = study.runs
    folder = Path(second.folder)
    folder.mkdir(parents=True)
    (folder / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.004,0.2\n")  # 0.004 s of its 0.02
    (folder / "checkpoint.npz").write_bytes(b"a checkpoint")
    write_index(out, study, [{"name": second.name, "family": second.family, "status": "stopped",
                              "folder": str(folder), "point": second.point}])
    assert {r["name"]: r["state"] for r in study_status(out)["runs"]} == {first.name: "not started",
                                                                         second.name: "in progress"}
    fewer = replace(study, runs=study.runs[:1])
    index = write_index(out, fewer)
    assert [(r["name"], r.get("planned")) for r in index["runs"]] == [(first.name, None), (second.name, False)]
    status = study_status(out)
    assert {r["name"]: r["state"] for r in status["runs"]} == {first.name: "not started", second.name: "not planned"}
    assert status["left_simulated_seconds"] == pytest.approx(first.duration)  # the other's 0.016 s not counted
    assert status["expected_left_simulated_seconds"] == pytest.approx(first.duration)
    text = format_status(status)
    assert f"1 not started of 1 runs; 0 of {first.duration:g} simulated s done" in text
    assert "1 run(s) not planned" in text and "--supersede" in text
    report(out)  # the table lists it; a findings page neither counts nor draws it
    table = json.loads((out / "table.json").read_text())
    assert {r["name"]: r["status"] for r in table} == {first.name: "pending", second.name: "not planned"}
    page = findings_page("t", table, [], [])
    assert "0 of 1 runs at their end, 0 on the way, 1 not started, and 1 not planned" in page
    # listed again by the file, it is planned again
    assert "planned" not in write_index(out, study)["runs"][1]
    assert {r["name"]: r["state"] for r in study_status(out)["runs"]}[second.name] == "in progress"
    write_index(out, fewer)
    # a run without --supersede is not refused (the runner never starts it): a note names it
    said = []
    assert _changed_folders(fewer, out, False, said.append) == 0 and folder.is_dir()
    assert len(said) == 1 and second.name in said[0] and "--supersede" in said[0]
    said.clear()
    assert _changed_folders(fewer, out, True, said.append) == 0  # --supersede moves it aside, nothing deleted
    moved = out / "superseded" / second.name
    assert not folder.exists() and (moved / "checkpoint.npz").read_bytes() == b"a checkpoint"
    assert "no longer lists run" in (moved / "SUPERSEDED.txt").read_text()
    assert len(said) == 1 and str(moved) in said[0]
    assert [r["name"] for r in write_index(out, fewer)["runs"]] == [first.name]
    # an ended run the file no longer lists is a result: it stays where it is, planned or not
    (folder / "summary.json").parent.mkdir(parents=True)
    (folder / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.02,0.2\n")
    (folder / "summary.json").write_text(json.dumps({"simulated_time": 0.02, "ended": True}))
    write_index(out, study, [{"name": second.name, "family": second.family, "status": "finished",
                              "folder": str(folder), "point": second.point}])
    write_index(out, fewer)
    assert {r["name"]: r["state"] for r in study_status(out)["runs"]}[second.name] == "ended"
    assert _changed_folders(fewer, out, True, said.append) == 0 and folder.is_dir()


@pytest.mark.slow
def test_ctrl_c_stops_the_study_with_its_runs_checkpointed_and_the_same_command_continues(tmp_path):
    """SIGINT to `fvdem study` while a run is past its first checkpoint: the run checkpoints at its
    next chunk (not at its last scheduled checkpoint), the study exits 130 naming the stopped run,
    and the same command resumes it to the end; `--stop` asks the same from another process."""
    import signal
    import time
    study = one_run_study(tmp_path, "stop", checkpoint_interval=0.1)
    out = tmp_path / "study"
    command = [sys.executable, "-m", "fvdem", "study", str(study), "--out", str(out), "--workers", "1", "--json"]
    # its own process group, signalled as a whole: what Ctrl-C on a terminal does (the workers get it too)
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    folder = out / "runs" / "small_u_over_umf2"
    deadline = time.time() + 300
    while not (folder / "checkpoint.npz").exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
    assert (folder / "checkpoint.npz").exists(), "the run never wrote a checkpoint"
    import os
    os.killpg(proc.pid, signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "stopped: 1 run(s)" in stderr
    result = json.loads(stdout.strip().splitlines()[-1])
    (run,) = result["runs"]
    assert result["stopped"] and run["status"] == "stopped" and 0.1 <= run["simulated_seconds"] < 0.3
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["stopped_early"]
    # the checkpoint is the stop's, not the last scheduled one
    from fvdem.io.checkpoint import load_checkpoint
    assert load_checkpoint(folder / "checkpoint.npz")[1]["time"] == pytest.approx(run["simulated_seconds"])
    again = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert again.returncode == 0, again.stderr
    (run,) = json.loads(again.stdout.strip().splitlines()[-1])["runs"]
    assert run["status"] == "resumed" and run["simulated_seconds"] == pytest.approx(0.3)
    stop = subprocess.run([sys.executable, "-m", "fvdem", "study", str(out), "--stop"], capture_output=True,
                          text=True, timeout=120)
    assert stop.returncode == 0 and (out / "STOP").exists()


@pytest.mark.slow
def test_the_progress_view_polls_while_runs_take_longer_than_its_interval(tmp_path):
    """Runs longer than the poll interval: the study keeps waiting and updating its view (Dask's wait
    raises when nothing finished within its timeout; that once ended the study with its runs cancelled)."""
    from fvdem.study import run_study
    lines = []
    result = run_study(load_study(synthetic_study(tmp_path), tmp_path / "study"), tmp_path / "study", workers=1, log=lines.append,
                       poll=0.05)
    assert [r["status"] for r in result["runs"]] == ["finished", "finished"]
    assert sum(line.startswith(("[1/2]", "[2/2]")) for line in lines) == 2  # one line per finished run


def test_replicas_start_from_their_own_settled_beds_differ_and_a_resumed_replica_is_itself(tmp_path):
    """Replica k >= 2 of a run that starts from a bed starts from its own bed, settled with insertion seed
    (the bed's + k - 1): the replicas differ from the first step (from one bed they would be bit-for-bit
    copies), and a replica stopped mid-run and resumed ends bit-for-bit where it ends uninterrupted."""
    import numpy as np

    from fvdem.study import prepare_bed
    text = synthetic_text().replace("replicas = 1", "replicas = 2")
    path = tmp_path / "replicas.toml"
    path.write_text(text.replace('"time.end" = 0.03', '"time.end" = 0.01'))
    study = load_study(path, tmp_path / "out")
    assert [b.name for b in study.beds] == ["small", "small_r2"]
    assert study.beds[1].overrides["particles.insertion.seed"] == 2 and "particles.insertion.seed" not in study.beds[0].overrides
    assert [(r.name, r.bed, r.replica) for r in study.runs] == [
        ("ar1_u_over_umf2_r1", "small", 1), ("ar1_u_over_umf2_r2", "small_r2", 2),
        ("ar1_u_over_umf2.9_r1", "small", 1), ("ar1_u_over_umf2.9_r2", "small_r2", 2)]
    states = {b.name: prepare_bed(b, 1) for b in study.beds}
    with np.load(states["small"]) as a, np.load(states["small_r2"]) as b:
        assert a["position"].shape == b["position"].shape and np.abs(a["position"] - b["position"]).max() > 1e-3
    first, second = study.runs[0], study.runs[1]
    results = [run_task(r, 1, states[r.bed]) for r in (first, second)]
    assert all(r["status"] == "finished" for r in results)
    with np.load(Path(first.folder) / "final_state.npz") as a, np.load(Path(second.folder) / "final_state.npz") as b:
        assert not np.array_equal(a["position"], b["position"])
    # replica 2 again, stopped after its first chunk past 0.006 s and resumed
    import fvdem.simulation as simulation
    again = replace(second, folder=str(tmp_path / "out" / "runs" / "again"))
    original = simulation.Model.advance

    def advance_then_stop(self, steps):
        original(self, steps)
        if self.time >= 0.006:
            request_stop(tmp_path / "out")
    simulation.Model.advance = advance_then_stop
    try:
        assert run_task(again, 1, states[again.bed])["status"] == "stopped"
    finally:
        simulation.Model.advance = original
    (tmp_path / "out" / STOP_FILE).unlink()
    assert run_task(again, 1, states[again.bed])["status"] == "resumed"
    with np.load(Path(second.folder) / "final_state.npz") as a, np.load(Path(again.folder) / "final_state.npz") as b:
        for key in a.files:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_familys_own_replicas_and_a_wrong_count(tmp_path):
    text = synthetic_text()
    path = tmp_path / "study.toml"
    path.write_text(text.replace('bed = "small"', 'bed = "small"\nreplicas = 3', 1))
    study = load_study(path, tmp_path / "out")
    assert [r.name for r in study.runs][:3] == ["ar1_u_over_umf2_r1", "ar1_u_over_umf2_r2", "ar1_u_over_umf2_r3"]
    assert [b.name for b in study.beds] == ["small", "small_r2", "small_r3"]
    path.write_text(text.replace('bed = "small"', 'bed = "small"\nreplicas = 0', 1))
    with pytest.raises(CaseError) as err:
        load_study(path, tmp_path / "out")
    assert "families.ar1.replicas = 0" in str(err.value)


def test_an_archive_drops_a_run_the_study_no_longer_lists_where_it_holds_nothing_of_it(tmp_path):
    """A replica taken out of the study file before it started leaves the archive's index; a run the archive
    holds results of stays, listed or not."""
    from fvdem.study import archive
    out, dest = tmp_path / "study", tmp_path / "archive"
    folder = out / "runs" / "ar1_u_over_umf2"
    fake_run(folder, "ar1", 2.0, 0.5, [0.4, 0.42, 0.98, 1.0])
    done = {"name": folder.name, "family": "ar1", "status": "finished", "folder": str(folder), "t95": None,
            "point": {"gas.u_over_umf": 2.0}, "replica": 1}
    ghost = {"name": "ar1_u_over_umf2_r2", "family": "ar1", "status": "pending", "folder": str(out / "runs" / "r2"),
             "t95": None, "point": {"gas.u_over_umf": 2.0}, "replica": 2}
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "table", "runs": [done, ghost]}))
    archive(out, dest)
    assert [r["name"] for r in json.loads((dest / "study.json").read_text())["runs"]] == [done["name"], ghost["name"]]
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "table", "runs": [done]}))  # the study file dropped the replica
    archive(out, dest)
    assert [r["name"] for r in json.loads((dest / "study.json").read_text())["runs"]] == [done["name"]]
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "table", "runs": []}))  # nor the run: the archive keeps it
    archive(out, dest)
    assert [r["name"] for r in json.loads((dest / "study.json").read_text())["runs"]] == [done["name"]]


def test_the_findings_page_shows_a_findings_note_beside_its_numbers():
    from fvdem.study.reports import findings_page
    rows = [{"status": "finished", "simulated_seconds": 6.4}, {"status": "running", "simulated_seconds": 1.0}]
    page = findings_page("t", rows, [{"finding": "terminal t95", "verdict": "does not hold", "values": {"2.9": 4.3612},
                                      "rule": "within 25 %", "note": "bed at the outlet: ar4_mp at 2.9 Umf"}], [])
    assert "1 of 2 runs at their end, 1 on the way, 0 not started; 1 finding: 1 does not hold." in page
    assert "| terminal t95 | does not hold | 2.9: 4.36 (bed at the outlet: ar4_mp at 2.9 Umf) | within 25 % |" in page
    # an open finding with numbers says why beside them
    page = findings_page("t", rows, [{"finding": "expands more", "verdict": "open", "values": {"1.6": 1.63},
                                      "why": "1.6 Umf within the replicas' spread", "rule": "r"}], [])
    assert "| expands more | open | 1.6: 1.63; 1.6 Umf within the replicas' spread | r |" in page
    # the runs that would decide the open findings (the report's plan.toml), in full; none where all are decided
    plan = '# t: the replicas\n[[points]]\nfamily = "ar1"\n"gas.u_over_umf" = 1.6\nreplicas = 3\n'
    page = findings_page("t", rows, [{"finding": "expands more", "verdict": "open", "why": "w"}], [], plan)
    assert "## What would decide the open findings" in page and f"```toml\n{plan}```" in page
    page = findings_page("t", rows, [{"finding": "expands more", "verdict": "holds"}], [], plan)
    assert "would decide" not in page


def test_the_costs_of_the_ended_runs_per_family_point_and_processor():
    """``cost_table``: what the ended runs cost, grouped by family, point and processor (a run resumed on another
    machine counts where its summary was written), the families in the study's order and each point's values
    ascending; the median and range of the CPU seconds per simulated second, the mean core-hours a run, the
    median wall seconds per simulated second, the largest peak memory; a run without CPU seconds is left out."""
    from fvdem.study.reports import cost_table, costs_page
    zen1, zen5 = "AMD EPYC (family 23, model 1), 2 CPUs", "AMD EPYC (family 26, model 2), 2 CPUs"

    def run(cpu, simulated, processor, wall=None, memory=None):
        return {"cpu_seconds": cpu, "simulated_time": simulated, "wall_seconds": wall, "peak_memory_mb": memory,
                "threads": 1, **({"provenance": {"cpu": processor}} if processor else {})}

    spent = [("ar4", {"gas.u_over_umf": 2.0}, run(3000.0, 5.0, zen1, 4000.0, 400.0)),  # 600 a simulated second
             ("ar1", {"gas.u_over_umf": 2.0}, run(1000.0, 4.0, zen1, 1200.0, 350.0)),  # 250
             ("ar4", {"gas.u_over_umf": 2.0}, run(3600.0, 5.0, zen1, 4200.0, 420.0)),  # 720
             ("ar4", {"gas.u_over_umf": 2.0}, run(2700.0, 5.0, zen1, 3000.0, 380.0)),  # 540
             ("ar4", {"gas.u_over_umf": 1.6}, run(6000.0, 20.0, None)),  # 300, made before the processor was kept
             ("ar4", {"gas.u_over_umf": 2.0}, run(1450.0, 5.0, zen5, 1500.0, 378.0)),  # 290
             ("ar1", {"gas.u_over_umf": 1.6}, run(None, 16.0, zen1))]  # no CPU seconds: left out
    costs = cost_table(spent)
    assert [(c["family"], c["point"]["gas.u_over_umf"], c["processor"], c["runs"]) for c in costs] == [
        ("ar4", 1.6, "not recorded", 1), ("ar4", 2.0, zen1, 3), ("ar4", 2.0, zen5, 1), ("ar1", 2.0, zen1, 1)]
    old = costs[1]
    assert old["cpu_per_simulated_second"] == {"median": 600.0, "min": 540.0, "max": 720.0}
    assert old["core_hours_per_run"] == pytest.approx((3000.0 + 3600.0 + 2700.0) / 3 / 3600.0)
    assert old["wall_per_simulated_second"] == pytest.approx(800.0) and old["peak_memory_mb"] == 420.0
    assert old["simulated_seconds"] == [5.0, 5.0] and old["threads"] == 1
    assert costs[0]["wall_per_simulated_second"] is None and costs[0]["peak_memory_mb"] is None
    page = costs_page("t", costs)
    assert page.startswith("# t: what the runs cost\n") and "6 ended run(s) with their CPU seconds" in page
    assert f"| ar4 | gas.u_over_umf: 2 | {zen1} | 3 | 1 | 5 | 600 (540-720) | 0.86 | 800 | 420 |" in page
    assert f"| ar4 | gas.u_over_umf: 2 | {zen5} | 1 | 1 | 5 | 290 | 0.40 | 300 | 378 |" in page
    assert "| ar4 | gas.u_over_umf: 1.6 | not recorded | 1 | 1 | 20 | 300 | 1.67 | - | - |" in page
    assert cost_table([]) == [] and "0 ended run(s)" in costs_page(None, [])


def test_a_run_that_ended_mixed_is_done_until_its_margin_is_raised(tmp_path):
    """The study skips a run its case ended early (``time.stop_after_mixed`` past t95; a bed at rest) while the
    case still asks for that end; a raised margin, or none, has it resume."""
    from types import SimpleNamespace

    from fvdem.study.records import run_at_end as _finished

    def case(margin=None, settled=False):
        return SimpleNamespace(time=SimpleNamespace(end=8.0, stop_when_settled=settled, stop_after_mixed=margin))

    def summary(**values):
        (tmp_path / "summary.json").write_text(json.dumps({"simulated_time": 5.5, "stopped_early": False, **values}))

    summary(ended="mixed", t95=3.5)
    assert _finished(tmp_path, case(2.0)) and not _finished(tmp_path, case(3.0)) and not _finished(tmp_path, case())
    summary(ended="mixed", t95=3.5, stopped_early=True)
    assert not _finished(tmp_path, case(2.0))
    summary(settled=True)  # a bed from before the summary said why it ended (0.2.0)
    assert _finished(tmp_path, case(settled=True)) and not _finished(tmp_path, case())
    summary(simulated_time=8.0, ended=None)
    assert _finished(tmp_path, case())
    # a study's run: ends mixed (t95 = 0 on one analysis cell) short of its duration, then skipped; resumed
    # to a raised margin
    out, run = small_run(tmp_path / "s", 0.02)
    mixed = replace(run, overrides={**run.overrides, "output.mixing_cells": [1, 1, 1], "time.stop_after_mixed": 0.004})
    first = run_task(mixed, 1)
    assert first["status"] == "finished" and first["ended"] == "mixed"
    assert first["simulated_seconds"] == pytest.approx(0.004)
    assert run_task(mixed, 1)["status"] == "skipped"
    later = run_task(replace(mixed, overrides={**mixed.overrides, "time.stop_after_mixed": 0.008}), 1)
    assert later["status"] == "resumed" and later["simulated_seconds"] == pytest.approx(0.008)


def _study_table(**changes):
    import tomllib
    table = tomllib.loads(synthetic_text())
    table.update(changes)
    return table


def test_runs_that_would_share_a_folder_or_have_an_unsafe_one_are_refused_with_their_axes(tmp_path):
    from fvdem.study import study_from_table
    with pytest.raises(CaseError) as err:
        study_from_table(_study_table(axes={"gas.u_over_umf": [2.0, 2.0000001]}), SMOKE, tmp_path)
    text = str(err.value)
    assert "both named 'ar1_u_over_umf2'" in text and "gas.u_over_umf = 2.0000001" in text
    with pytest.raises(CaseError) as err:
        study_from_table(_study_table(axes={"gas.u_over_umf": [2.0], "domain.upper": [[0.06, 0.06, 0.6]]}),
                         SMOKE, tmp_path)
    assert "is not a plain folder name" in str(err.value) and "domain.upper = [0.06, 0.06, 0.6]" in str(err.value)
    path = tmp_path / "dup.toml"
    path.write_text(synthetic_text()
                    .replace("[2.0, 2.9]", "[2.0, 2.0000001]"))
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(path), "--out", str(tmp_path / "o")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "Traceback" not in result.stderr and not (tmp_path / "o").exists()


def test_a_wrong_study_key_or_cluster_option_is_refused_with_a_did_you_mean(tmp_path):
    from fvdem.study import study_from_table
    with pytest.raises(CaseError) as err:
        study_from_table(_study_table(replica=2, cluster={"kind": "slurm", "workers": "two", "memroy": "2GB"}),
                         SMOKE, tmp_path)
    text = str(err.value)
    assert "replica = 2: unknown key (did you mean 'replicas'?)" in text
    assert "cluster.memroy = '2GB': unknown key for kind = 'slurm' (did you mean 'memory'?)" in text
    assert "cluster.workers = 'two': an integer >= 1" in text and "cluster.memory: missing" in text
    for cluster, fragment in (({"kind": "local", "memory": "2GB"}, "cluster.memory = '2GB': unknown key for kind = 'local'"),
                              ({"kind": "pbs", "memory": "lots"}, "cluster.memory = 'lots': a memory size"),
                              ({"kind": "slurm", "memory": "2GB", "walltime": "soon"}, "cluster.walltime = 'soon'"),
                              ({"kind": "kubernetes"}, "cluster.kind = 'kubernetes'")):
        with pytest.raises(CaseError) as err:
            study_from_table(_study_table(cluster=cluster), SMOKE, tmp_path)
        assert fragment in str(err.value)
    study_from_table(_study_table(cluster={"kind": "slurm", "memory": "2GB", "walltime": "1-00:00:00",
                                           "workers": 2, "queue": "compute"}), SMOKE, tmp_path)


def test_mutated_study_files_are_refused_by_key_and_never_crash_the_loader():
    """tools/fuzz_cases.py --studies: 300 mutations of the shipped study files (the recorded run: 100,000)."""
    sys.path.insert(0, str(TOOLS))
    import fuzz_cases
    assert fuzz_cases.main(["--studies", "--count", "300", "--seed", "7", "--json"]) == 0


def test_a_bed_is_submitted_with_the_first_run_the_queue_hands_on_that_starts_from_it(tmp_path, monkeypatch):
    """Submitted at the study's start, a later replica's bed took a free worker ahead of the runs in progress
    (the campaign's restart with new replicas, 2026-12-05: four new beds settled before two runs in progress
    went on): Dask orders by priority only the tasks it holds, and the queue holds the runs back. A bed goes
    to Dask with the first run that starts from it; a run at its end is handed on without it."""
    import distributed

    from fvdem.study import runner
    submitted, done, states = [], [], []

    class Future:
        def __init__(self, key, fn, args):
            self.key, self.fn, self.args = key, fn, args

        def result(self):
            if not hasattr(self, "value"):
                self.value = self.fn(*[a.result() if isinstance(a, Future) else a for a in self.args])
            return self.value

    class Client:
        def submit(self, fn, *args, key, pure, priority):
            submitted.append(key.split("-", 2)[2])
            return Future(key, fn, args)

    def fake_bed(bed, threads):
        done.append(f"bed-{bed.name}")
        return f"{bed.name}.npz"

    def fake_run(run, threads, bed_state=None):
        done.append(f"run-{run.name}")
        states.append(bed_state)
        Path(run.folder).mkdir(parents=True, exist_ok=True)
        (Path(run.folder) / "summary.json").write_text(json.dumps({"simulated_time": run.duration}))
        return {"name": run.name, "family": run.family, "status": "finished", "folder": run.folder,
                "simulated_seconds": run.duration, "point": run.point, "bed_state": bed_state}

    def first_completed(pending, timeout=None, return_when=None):  # the earliest submitted run ends first
        first = next(iter(sorted(pending, key=lambda f: submitted.index(f.key.split("-", 2)[2]))))
        first.result()
        return {first}, pending - {first}
    monkeypatch.setattr(runner, "make_client", lambda *a: (Client(), "fake"))
    monkeypatch.setattr(runner, "close_client", lambda client: None)
    monkeypatch.setattr(runner, "prepare_bed", fake_bed)
    monkeypatch.setattr(runner, "run_task", fake_run)
    monkeypatch.setattr(distributed, "wait", first_completed)
    text = synthetic_text().replace("replicas = 1", "replicas = 2")
    (tmp_path / "s.toml").write_text(text)
    study = load_study(tmp_path / "s.toml", tmp_path / "out")
    summary = runner.run_study(study, tmp_path / "out", workers=2, log=lambda *a: None, poll=0.01)
    assert [r["status"] for r in summary["runs"]] == ["finished"] * 4
    assert submitted == ["bed-small", "run-ar1_u_over_umf2_r1", "run-ar1_u_over_umf2.9_r1", "bed-small_r2",
                         "run-ar1_u_over_umf2_r2", "run-ar1_u_over_umf2.9_r2"]
    assert done.index("bed-small_r2") > done.index("run-ar1_u_over_umf2_r1")
    assert states == ["small.npz"] * 2 + ["small_r2.npz"] * 2
    # again: every run at its end, none settles a bed or gets one
    submitted.clear(), states.clear()
    runner.run_study(study, tmp_path / "out", workers=2, log=lambda *a: None, poll=0.01)
    assert sorted(submitted) == sorted(f"run-{r.name}" for r in study.runs) and states == [None] * 4


def test_a_study_names_its_report_and_an_unknown_report_is_refused(tmp_path):
    text = synthetic_text()
    path = tmp_path / "named.toml"
    path.write_text(text.replace('report = "table"', 'report = "bed"'))
    study = load_study(path, tmp_path / "out")
    assert study.report == "bed" and {r.report for r in study.runs} == {"bed"}
    assert load_study(SMOKE, tmp_path / "named").report == "mema2020"  # the smoke study names the paper's
    path.write_text(text.replace('report = "table"', ''))
    assert load_study(path, tmp_path / "default").report == "table"  # the engine's default: the generic table
    path.write_text(text.replace('report = "table"', 'report = "tabel"'))
    with pytest.raises(CaseError) as refused:
        load_study(path, tmp_path / "out")
    assert "report = 'tabel': a registered report (did you mean 'table'?): bed, mema2020, table" in str(refused.value)


@pytest.mark.slow
def test_a_study_lost_with_its_machine_continues_from_its_archive(tmp_path, capsys, monkeypatch):
    """fvdem study STUDY --out NEW --restore ARCHIVE: the runs the archive holds at their end are copied into
    NEW and skipped, with no bed settled for them; a run the archive holds in progress starts again (an
    archive has no checkpoint) from a bed settled again, and ends bit-for-bit as it did on the lost machine;
    a run folder that exists is never replaced; a run whose case changed since is not restored; an archive of
    another study, or a folder that is no archive, is refused (exit 2) before anything runs; ``--adopt`` takes
    another study's ended runs of the same name, case and bed."""
    from fvdem.cli import main
    from fvdem.study import archive, restore, run_study
    path = tmp_path / "smoke.toml"
    path.write_text(synthetic_text())
    lost, dest = tmp_path / "lost", tmp_path / "archive"
    run_study(load_study(path, lost), lost, workers=1, log=lambda line: None)
    archive(lost, dest)
    first, second = (r.name for r in load_study(path, lost).runs)

    def study(out, *args):
        capsys.readouterr()
        code = main(["study", str(path), "--out", str(out), "--workers", "1", "--json", *args])
        captured = capsys.readouterr()
        return code, (json.loads(captured.out) if code == 0 else None), captured.err

    code, result, err = study(tmp_path / "new", "--restore", str(dest))
    assert code == 0 and [r["status"] for r in result["runs"]] == ["skipped", "skipped"]
    assert "restore from" in err and "2 restored" in err
    assert not (tmp_path / "new" / "beds").exists()  # no run needed its bed
    assert "restored from the archive" in (tmp_path / "new" / "runs" / first / "run.log").read_text()
    # stopped before the queue hands anything on: runs at their end still come back "skipped", not "stopped"
    # (a stopped campaign once listed its finished runs as stopped, and its archive's findings lost them)
    import fvdem.study.runner as runner
    progress = runner._StudyProgress.__init__

    def stop_at_once(self, *args):
        progress(self, *args)
        request_stop(tmp_path / "new")
    monkeypatch.setattr(runner._StudyProgress, "__init__", stop_at_once)
    result = run_study(load_study(path, tmp_path / "new"), tmp_path / "new", workers=1, log=lambda line: None)
    assert [r["status"] for r in result["runs"]] == ["skipped", "skipped"] and result.get("stopped")
    monkeypatch.undo()
    # the archive holds the second run in progress (the machine was lost while it ran)
    summary = dest / "runs" / second / "summary.json"
    summary.write_text(json.dumps({**json.loads(summary.read_text()), "simulated_time": 0.01, "stopped_early": True}))
    code, result, err = study(tmp_path / "again", "--restore", str(dest))
    assert code == 0 and [r["status"] for r in result["runs"]] == ["skipped", "finished"]
    assert f"restore: {second}: in progress (starts again" in err and "1 restored, 1 in progress" in err
    assert (tmp_path / "again" / "beds" / "small" / "final_state.npz").exists()
    assert ((tmp_path / "again" / "runs" / second / "timeseries.csv").read_text()
            == (lost / "runs" / second / "timeseries.csv").read_text())
    # never over a run folder that exists; not where the case changed since it ran
    assert restore(load_study(path, tmp_path / "again"), dest) == [(first, "exists"), (second, "exists")]
    changed = tmp_path / "changed.toml"
    changed.write_text(path.read_text().replace('"particles.count" = 150\n"gas.inlet_ramp"',
                                                '"particles.count" = 150\n"contact.friction" = 0.2\n"gas.inlet_ramp"'))
    outcomes = dict(restore(load_study(changed, tmp_path / "changed"), dest))
    assert outcomes[first].startswith("case differs: contact.friction: ")
    assert not (tmp_path / "changed" / "runs" / first).exists()
    # refused: an archive of another study; no archive at all
    index = json.loads((dest / "study.json").read_text())
    (dest / "study.json").write_text(json.dumps({**index, "study": "another"}))
    for source, said in ((dest, "an archive of study 'another', not 'smoke'"),
                         (tmp_path / "lost" / "runs", "no study.json")):
        code, _, err = study(tmp_path / "refused", "--restore", str(source))
        assert code == 2 and said in err and "Traceback" not in err
        assert not (tmp_path / "refused" / "runs").exists()
    # adopted: another study's archive (an earlier stage) gives its ended runs of the same name, case and bed;
    # its run in progress is left for this study to run; a changed case is not adopted
    adopted = tmp_path / "adopted"
    assert restore(load_study(path, adopted), dest, adopt=True) == [(first, "adopted"), (second, "in progress")]
    assert "adopted from the archive of study 'another'" in (adopted / "runs" / first / "run.log").read_text()
    assert not (adopted / "runs" / second).exists()
    assert dict(restore(load_study(changed, tmp_path / "changed2"), dest, adopt=True))[first].startswith(
        "case differs: contact.friction: ")
    code, _, err = study(tmp_path / "refused", "--adopt", str(tmp_path / "lost" / "runs"))
    assert code == 2 and "--adopt" in err and "no study.json" in err and "Traceback" not in err


def test_the_eta_counts_only_what_this_invocation_simulated():
    """A study resumed or restored with 60 of its 464 simulated seconds in its folders: the time left comes from
    what it simulated since it started (10 s in 100 s of wall time), not from the runs it skipped."""
    import time

    from fvdem.study import progress_line
    started = time.perf_counter() - 100.0
    line = progress_line(9, 44, "r", "finished", "", started, 70.0, 464.0, " simulated s", work_start=60.0)
    assert float(line.rsplit("ETA ", 1)[1].split()[0]) == pytest.approx(394.0 / 0.1, rel=0.01)
    assert line.endswith("s (1 h 06 min)")  # 3,940 s: an hour or more reads in hours too
    assert progress_line(44, 44, "r", "finished", "", started).endswith("ETA 0 s")  # seconds alone below an hour
    assert progress_line(8, 44, "r", "skipped", "", started, 60.0, 464.0, work_start=60.0).endswith("ETA ?")


def test_until_takes_a_clock_time_an_iso_time_or_a_duration_and_refuses_a_past_or_wrong_one():
    """``--until``: "+<duration>" from now, "HH:MM[:SS]" at its next occurrence (tomorrow once passed today), an
    ISO date and time; a moment not to come, or no such form, is None (the command line's usage error, exit 2)."""
    from datetime import datetime, timedelta

    from fvdem.study.cluster import until_epoch
    now = datetime(2026, 12, 5, 2, 30).astimezone().timestamp()  # local 02:30
    assert until_epoch("+90m", now) == now + 5400 and until_epoch("+1:30:00", now) == now + 5400
    assert until_epoch("+2h", now) == now + 7200
    assert until_epoch("04:45", now) == now + 8100  # today, 2 h 15 min on
    assert until_epoch("04:45:30", now) == now + 8130
    assert until_epoch("01:00", now) == (datetime(2026, 12, 5, 1, 0).astimezone() + timedelta(days=1)).timestamp()
    assert until_epoch("2026-12-05T04:45", now) == now + 8100
    assert until_epoch("2026-12-05T04:45+00:00", now) == datetime.fromisoformat("2026-12-05T04:45+00:00").timestamp()
    for wrong in ("25:00", "04:61", "+0m", "+soon", "2026-12-05T02:00", "tonight", "", None):
        assert until_epoch(wrong, now) is None, wrong
    refused = subprocess.run([sys.executable, "-m", "fvdem", "study", str(ROOT / "studies" / "smoke.toml"), "--out",
                              "never", "--until", "25:00"], capture_output=True, text=True, timeout=120)
    assert refused.returncode == 2 and "argument --until: '25:00': a time to come" in refused.stderr
    assert "Traceback" not in refused.stderr and not Path("never").exists()


def test_a_study_stops_at_its_deadline_with_nothing_lost(tmp_path):
    """A deadline already past when the study starts: it stops before any run starts (each listed stopped, no
    folder written), says so in its result, and the same study without the deadline runs them."""
    import time

    from fvdem.study import run_study
    out = tmp_path / "study"
    lines = []
    result = run_study(load_study(one_run_study(tmp_path, "until", 0.1), out), out, workers=1,
                       log=lines.append, until=time.time() - 1.0)
    assert result["stopped"] and result["until_reached"] and result["until"]
    assert [r["status"] for r in result["runs"]] == ["stopped"] and not (out / "runs" / "small_u_over_umf2").exists()
    assert any("--until" in line and "reached: stopping" in line for line in lines)
    assert any(line.startswith("stops at ") and "(--until), in 0 h 00 min" in line for line in lines)


@pytest.mark.slow
def test_a_changed_study_is_refused_then_superseded_in_its_folder_and_its_archive(tmp_path, capsys):
    """fvdem study with a study file whose family setting changed since its runs ran: refused (exit 2, every
    folder named with the keys, no traceback, nothing moved); with --supersede the old folders move to
    OUT/superseded/ (with the reason) and their runs run again under the new case; the archive then moves its
    copies of the old runs to its own superseded/ and holds the new ones, so that its report is of one
    definition; nothing is deleted."""
    from fvdem.cli import main
    from fvdem.study import archive
    path = tmp_path / "smoke.toml"
    path.write_text(synthetic_text())
    out, dest = tmp_path / "study", tmp_path / "archive"

    def study(*args):
        capsys.readouterr()
        code = main(["study", str(path), "--out", str(out), "--workers", "1", "--json", *args])
        captured = capsys.readouterr()
        return code, (json.loads(captured.out) if code == 0 else None), captured.err

    assert study()[0] == 0
    archive(out, dest)
    first, second = (r.name for r in load_study(path, out).runs)
    before = (out / "runs" / first / "timeseries.csv").read_text()
    path.write_text(path.read_text().replace('"gas.inlet_ramp" = 0.005', '"gas.inlet_ramp" = 0.005\n'
                                             '"contact.friction" = 0.2'))
    code, _, err = study()
    assert code == 2 and "2 folder(s)" in err and "Traceback" not in err and "--supersede" in err
    assert f"{out / 'runs' / first}: contact.friction: 0.46 -> 0.2" in err
    assert not (out / "superseded").exists() and (out / "runs" / first / "timeseries.csv").read_text() == before
    assert main(["study", str(path), "--out", str(out), "--report"]) == 0  # reports what is there, with a warning
    assert "warning: 2 folder(s)" in capsys.readouterr().err
    code, result, err = study("--supersede")
    assert code == 0 and [r["status"] for r in result["runs"]] == ["finished", "finished"]
    assert f"superseded: {first} (contact.friction: 0.46 -> 0.2) moved to {out / 'superseded' / first}" in err
    assert (out / "superseded" / first / "timeseries.csv").read_text() == before
    assert "contact.friction" in (out / "superseded" / first / "SUPERSEDED.txt").read_text()
    assert (out / "runs" / first / "timeseries.csv").read_text() != before
    assert '\nfriction = 0.2' in (out / "runs" / first / "case.toml").read_text()
    assert study()[0] == 0  # the same command again: nothing to supersede, both skipped
    written = archive(out, dest)
    assert dest / "superseded" / first in written and dest / "superseded" / second in written
    assert "\nfriction = 0.46" in (dest / "superseded" / first / "case.toml").read_text()
    assert "\nfriction = 0.2" in (dest / "runs" / first / "case.toml").read_text()
    assert ((dest / "runs" / first / "summary.json").read_text()
            != (dest / "superseded" / first / "summary.json").read_text())
    archive(out, dest)  # again: the archive holds the new definition, nothing more moves
    assert sorted(p.name for p in (dest / "superseded").iterdir()) == sorted([first, second])
