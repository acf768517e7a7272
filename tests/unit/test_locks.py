"""One writer per folder (``fvdem.io.locks``): a run folder or a study folder another process is writing is
refused before anything is touched, with who holds it; a lock dies with its process; ``fvdem study --status``
reads where a study stands without writing."""
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from fvdem.cli import main
from fvdem.io.locks import LOCK_FILE, FolderInUse, FolderLock, holder
from fvdem.io.run_folder import prepare_output

from paths import ROOT

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="no advisory locks on Windows")


def _hold(folder: Path, kind: str = "run"):
    """Another process holding ``folder``'s lock (as ``fvdem study`` or a run would), until it is killed."""
    code = ("import sys, time; from fvdem.io.locks import FolderLock; "
            f"lock = FolderLock({str(folder)!r}, {kind!r}).acquire(); print('held', flush=True); time.sleep(120)")
    process = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=ROOT)
    assert process.stdout.readline().strip() == "held"
    return process


def test_a_folder_held_by_another_process_is_refused_naming_it_and_freed_when_it_dies(tmp_path):
    folder = tmp_path / "run"
    process = _hold(folder)
    try:
        record = holder(folder)
        assert record["pid"] == process.pid and record["kind"] == "run" and record["host"]
        with pytest.raises(FolderInUse) as refused:
            FolderLock(folder).acquire(retry=0.1)
        message = str(refused.value)
        assert f"process {process.pid}" in message and str(folder) in message and "-c" in message
    finally:
        process.send_signal(signal.SIGKILL)  # no clean-up of its own: the kernel releases the lock
        process.wait()
    assert holder(folder) is None
    with FolderLock(folder) as lock:
        assert lock.held and holder(folder)["pid"] == os.getpid()
        with FolderLock(folder) as again:  # the holding process may take it again (nested)
            assert again.held
        assert holder(folder)["pid"] == os.getpid()  # still held by the outer one
    assert holder(folder) is None and (folder / LOCK_FILE).exists()


def test_a_run_folder_a_studys_worker_writes_is_refused_with_the_study_to_stop(tmp_path):
    """The worker's command line says little (a Dask process): the refusal names the study that holds the
    folder two levels up, and its --stop."""
    out = tmp_path / "study"
    study, run = _hold(out, "study"), _hold(out / "runs" / "ar1_r1")
    try:
        with pytest.raises(FolderInUse, match=f"fvdem study {out} --stop, or SIGINT to process {run.pid}"):
            FolderLock(out / "runs" / "ar1_r1").acquire(retry=0.1)
    finally:
        for process in (study, run):
            process.send_signal(signal.SIGKILL)
            process.wait()


def test_a_folder_made_for_a_writer_that_wrote_nothing_is_not_left_behind(tmp_path):
    with FolderLock(tmp_path / "new" / "run"):
        pass
    assert not (tmp_path / "new" / "run").exists()


def test_an_output_folder_holding_only_its_lock_is_empty_and_overwrite_keeps_the_lock(tmp_path):
    folder = tmp_path / "run"
    with FolderLock(folder):
        assert prepare_output(folder) == folder  # the lock file is not a result
        (folder / "timeseries.csv").write_text("time\n0\n")
        (folder / "sub").mkdir()
        with pytest.raises(Exception, match="exists and is not empty"):
            prepare_output(folder)
        prepare_output(folder, overwrite=True)
        assert [p.name for p in folder.iterdir()] == [LOCK_FILE] and holder(folder)["pid"] == os.getpid()


def test_a_run_folder_another_process_writes_is_refused_before_anything_is_touched(tmp_path):
    """``fvdem run`` into a folder a running run holds: exit 2 with the holder named; the folder's files are
    the same bytes after (an --overwrite would have cleared them under the running run)."""
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "timeseries.csv").write_text("time\n0.1\n")
    process = _hold(folder)
    try:
        code = main(["run", str(ROOT / "cases" / "demo.toml"), "--out", str(folder), "--overwrite", "--no-progress",
                     "--set", "particles.count=50", "--set", "time.end=0.002", "--set", "output.vtk=false"])
        assert code == 2
        assert (folder / "timeseries.csv").read_text() == "time\n0.1\n"
        assert sorted(p.name for p in folder.iterdir()) == [LOCK_FILE, "timeseries.csv"]
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    # free again: the same command runs, and the run holds its folder while it runs only
    assert main(["run", str(ROOT / "cases" / "demo.toml"), "--out", str(folder), "--overwrite", "--no-progress",
                 "--set", "particles.count=50", "--set", "time.end=0.002", "--set", "output.vtk=false"]) == 0
    assert holder(folder) is None and (folder / "summary.json").exists()


def test_a_second_study_in_a_folder_a_study_runs_in_is_refused_and_moves_nothing(tmp_path, capsys):
    out = tmp_path / "study"
    out.mkdir()
    (out / "STOP").write_text("stop requested\n")  # the running study's own stop request: not removed
    process = _hold(out, "study")
    try:
        code = main(["study", str(ROOT / "studies" / "smoke.toml"), "--out", str(out), "--workers", "1"])
        err = capsys.readouterr().err
        assert code == 2 and f"study folder {out} is in use" in err and f"process {process.pid}" in err
        assert f"fvdem study {out} --stop" in err and "Traceback" not in err
        assert sorted(p.name for p in out.iterdir()) == [LOCK_FILE, "STOP"]
        (out / "study.toml").write_text('name = "smoke"\n')
        (out / "STOP").unlink()
        assert main(["study", str(out), "--stop"]) == 0  # names the study it stops
        assert f"process {process.pid}" in capsys.readouterr().out and (out / "STOP").exists()
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    (out / "STOP").unlink()
    assert main(["study", str(out), "--stop"]) == 0  # nobody holds it: written anyway, and said so
    assert "no fvdem study holds" in capsys.readouterr().out and (out / "STOP").exists()


def _status_folder(tmp_path) -> Path:
    """A study folder as a campaign leaves it: a run at its end (mixed), one in progress (a checkpoint), one with
    results but no checkpoint (as an archive holds a run in progress: it starts again), one not started."""
    out = tmp_path / "study"
    rows = []
    for name, family, held, summary in (
            ("a_r1", "ar1", 5.0, {"simulated_time": 5.0, "ended": "mixed", "t95": 3.0, "cpu_seconds": 1000.0,
                                  "peak_memory_mb": 400.0, "provenance": {"cpu": "AMD EPYC (family 26, model 2)"}}),
            ("b_r1", "ar4", 3.0, {"simulated_time": 2.0, "stopped_early": True, "cpu_seconds": 1200.0,
                                  "peak_memory_mb": 350.0}),
            ("b_r2", "ar4", 0.0, None),
            ("c_r1", "ar4", 1.0, None)):
        folder = out / "runs" / name
        folder.mkdir(parents=True)
        if held:
            times = [0.01 * k for k in range(int(round(held / 0.01)) + 1)]
            (folder / "timeseries.csv").write_text("time,mixing_entropy\n" + "".join(
                f"{t!r},{min(1.0, t / 3.5)!r}\n" for t in times))
        if summary:
            (folder / "summary.json").write_text(json.dumps(summary))
        if name == "b_r1":
            (folder / "checkpoint.npz").write_bytes(b"a checkpoint at 2 s")
        rows.append({"name": name, "family": family, "status": "pending", "folder": f"runs/{name}",
                     "point": {"gas.u_over_umf": 2.0}, "replica": int(name[-1]), "duration": 8.0})
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": rows,
                                                "scheduler": "LocalCluster(2 workers x 1 numba threads)"}))
    return out


def test_the_status_says_each_runs_state_its_values_and_the_core_hours_left(tmp_path, capsys):
    from fvdem.study.status import study_status
    out = _status_folder(tmp_path)
    before = {p: p.read_bytes() for p in out.rglob("*") if p.is_file()}
    status = study_status(out)
    runs = {r["name"]: r for r in status["runs"]}
    assert [runs[n]["state"] for n in ("a_r1", "b_r1", "b_r2", "c_r1")] == ["ended", "in progress", "not started",
                                                                            "partial"]
    assert runs["c_r1"]["simulated_seconds"] == 1.0 and runs["c_r1"]["left"] == 8.0  # starts again from t = 0
    assert runs["a_r1"]["t95"] == 3.0 and runs["a_r1"]["left"] == 0.0  # ended mixed: nothing left
    assert runs["b_r1"]["simulated_seconds"] == pytest.approx(3.0)  # its time series, past its last stop
    assert runs["b_r1"]["mixing_entropy"] == pytest.approx(3.0 / 3.5) and runs["b_r1"]["t95"] is None
    # rates from the summaries: ar1 1000 CPU s over 5 s, ar4 1200 over the 2 s its last stop recorded
    families = status["families"]
    assert families["ar1"]["cpu_per_simulated_second"] == pytest.approx(200.0)
    assert families["ar4"]["cpu_per_simulated_second"] == pytest.approx(600.0)
    assert families["ar4"]["left_simulated_seconds"] == pytest.approx(5.0 + 8.0 + 8.0)
    # the processors the rates were measured on: ar1's run names its own, ar4's summary none (an older run)
    assert status["processors"] == {"AMD EPYC (family 26, model 2)": 1, "not recorded": 1}
    assert status["left_core_hours"] == pytest.approx(21.0 * 600.0 / 3600.0)
    assert status["running"] is None and status["counts"]["ended"] == 1 and status["hours_at_running_now"] is None
    # a run a process writes now is "running", and the hours left are spread over the runs running now
    process = _hold(out / "runs" / "b_r1")
    try:
        import time
        before_status = time.time()
        now = study_status(out)
        assert {r["name"]: r["state"] for r in now["runs"]}["b_r1"] == "running"
        assert now["hours_at_running_now"] == pytest.approx(now["left_core_hours"])
        # its end: the 5 s it is expected to run yet at ar4's 600 CPU s per simulated s, at one thread (its
        # summary names none), from now, to the minute
        running = {r["name"]: r for r in now["runs"]}["b_r1"]
        assert running["expected_cpu_seconds_left"] == pytest.approx(5.0 * 600.0)
        from datetime import datetime
        end = datetime.fromisoformat(running["expected_end"]).timestamp()
        assert before_status + 3000.0 - 60.0 <= end <= time.time() + 3000.0
        assert "expected_end" not in {r["name"]: r for r in now["runs"]}["b_r2"]  # not running
        assert main(["study", str(out), "--status"]) == 0
        text = capsys.readouterr().out
        assert f"b_r1 about {running['expected_end'][11:16]}" in text
        assert ("measured on: AMD EPYC (family 26, model 2) (1 run(s)); a processor not recorded (runs made before "
                "fvdem recorded it) (1 run(s))") in text
        assert "expected_end" not in text and "expected_cpu" not in text  # a line of their own, not table columns
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    assert main(["study", str(out), "--status"]) == 0
    text = capsys.readouterr().out
    assert "not running" in text and "1 ended, 1 in progress, 1 partial, 1 not started of 4 runs" in text
    assert "at most 3.5 core-hours" in text and "ar4 600 (1 run(s)), peak 350 MB" in text
    assert main(["study", str(out), "--status", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["counts"]["not started"] == 1
    (out / "runs" / "b_r1" / LOCK_FILE).unlink()  # the probe's lock file aside, nothing was written
    assert {p: p.read_bytes() for p in out.rglob("*") if p.is_file()} == before
    assert main(["study", str(tmp_path), "--status"]) == 2  # not a study folder


def test_the_status_scales_its_rates_to_the_processor_the_study_computes_on_now(tmp_path, capsys, monkeypatch):
    """A campaign moved to another machine (2026-12-06: a Zen 5 EPYC ran the paper's AR-4 runs at about 290 CPU s
    per simulated second, the Zen 1 before at 650-900): the families measured there take their rate there, the
    others their rate elsewhere times the median ratio of the families measured on both; a status read where no
    run was measured, or a study of one processor, takes the rates as measured."""
    import fvdem.provenance
    from fvdem.study.status import study_status
    out = _status_folder(tmp_path)  # a_r1 (ar1) at 200 CPU s per simulated second, b_r1 (ar4) at 600: the old machine
    old, new = "AMD EPYC (family 23, model 1), 2 CPUs", "AMD EPYC (family 26, model 2), 2 CPUs"
    for name, cpu, processor in (("a_r1", 1000.0, old), ("b_r1", 1200.0, old)):
        summary = json.loads((out / "runs" / name / "summary.json").read_text())
        summary["cpu_seconds"], summary["provenance"] = cpu, {"cpu": processor}
        (out / "runs" / name / "summary.json").write_text(json.dumps(summary))
    # a second ar1 run, ended on the new machine at 80 CPU s per simulated second (0.4 times the old one's 200)
    index = json.loads((out / "study.json").read_text())
    index["runs"].append({**index["runs"][0], "name": "a_r2", "folder": "runs/a_r2", "replica": 2})
    (out / "study.json").write_text(json.dumps(index))
    (out / "runs" / "a_r2").mkdir()
    (out / "runs" / "a_r2" / "timeseries.csv").write_bytes((out / "runs" / "a_r1" / "timeseries.csv").read_bytes())
    (out / "runs" / "a_r2" / "summary.json").write_text(json.dumps(
        {"simulated_time": 5.0, "ended": "mixed", "t95": 3.0, "cpu_seconds": 400.0, "provenance": {"cpu": new}}))
    monkeypatch.setattr(fvdem.provenance, "cpu_model", lambda: new)  # the study computes on the new machine now
    status = study_status(out)
    families = status["families"]
    assert status["processors"] == {old: 2, new: 1} and status["processor_now"] == new
    assert status["processor_factor"] == pytest.approx(0.4)
    assert families["ar1"]["cpu_per_simulated_second"] == pytest.approx(140.0)  # as measured, both machines
    assert families["ar1"]["cpu_per_simulated_second_now"] == pytest.approx(80.0)  # its own run there
    assert families["ar4"]["cpu_per_simulated_second"] == pytest.approx(600.0)
    assert families["ar4"]["cpu_per_simulated_second_now"] == pytest.approx(240.0)  # 600 x 0.4
    assert status["left_core_hours"] == pytest.approx(21.0 * 240.0 / 3600.0)
    runs = {r["name"]: r for r in status["runs"]}
    assert runs["c_r1"]["expected_cpu_seconds_left"] == pytest.approx(runs["c_r1"]["expected_left"] * 240.0)
    assert main(["study", str(out), "--status"]) == 0
    text = capsys.readouterr().out
    assert (f"the estimates below at the rates on {new}, where the study computes now: 0.4 times those elsewhere"
            in text and ": ar1 80; ar4 240" in text)
    # read on a third machine, or where one processor measured everything: the rates as measured
    monkeypatch.setattr(fvdem.provenance, "cpu_model", lambda: "another")
    status = study_status(out)
    assert status["processor_factor"] is None and status["left_core_hours"] == pytest.approx(21.0 * 600.0 / 3600.0)
    assert "cpu_per_simulated_second_now" not in status["families"]["ar4"]
    (out / "runs" / "a_r2" / "summary.json").write_text(json.dumps(
        {"simulated_time": 5.0, "ended": "mixed", "t95": 3.0, "cpu_seconds": 400.0, "provenance": {"cpu": old}}))
    monkeypatch.setattr(fvdem.provenance, "cpu_model", lambda: old)
    status = study_status(out)
    assert status["processor_factor"] is None and status["families"]["ar1"]["cpu_per_simulated_second"] == 140.0
    assert main(["study", str(out), "--status"]) == 0
    assert "the estimates below" not in capsys.readouterr().out


def test_the_status_says_which_beds_settle_while_the_runs_wait(tmp_path, capsys):
    """Runs in progress with none running: the study is settling beds (a campaign given new replicas, 2026-12-05,
    settled four beds for five minutes first). The status lists the beds begun in ``beds/``: settled (a final
    state and a summary not stopped early), settling (a process holds the folder), in progress (a checkpoint)."""
    from fvdem.study.status import study_status
    out = _status_folder(tmp_path)
    for name, files in (("a", {"final_state.npz": b"s", "summary.json": b'{"simulated_time": 0.4, "cpu_seconds": 150}',
                               "timeseries.csv": b"time\n0.0\n0.4\n"}),
                        ("a_r2", {"checkpoint.npz": b"c", "timeseries.csv": b"time\n0.0\n0.2\n",
                                  "summary.json": b'{"simulated_time": 0.1, "stopped_early": true}'}),
                        ("a_r3", {"timeseries.csv": b"time\n0.0\n0.05\n"})):
        (out / "beds" / name).mkdir(parents=True)
        for file, data in files.items():
            (out / "beds" / name / file).write_bytes(data)
    beds = {b["name"]: b for b in study_status(out)["beds"]}
    assert {n: b["state"] for n, b in beds.items()} == {"a": "settled", "a_r2": "in progress", "a_r3": "begun"}
    assert beds["a"]["cpu_seconds"] == 150 and beds["a_r2"]["simulated_seconds"] == pytest.approx(0.2)
    process = _hold(out / "beds" / "a_r3")
    try:
        assert {b["name"]: b["state"] for b in study_status(out)["beds"]}["a_r3"] == "settling"
        assert main(["study", str(out), "--status"]) == 0
        text = capsys.readouterr().out
        assert "beds: 1 of 3 begun settled; a_r2 in progress (0.2 s), a_r3 settling (0.05 s)" in text
    finally:
        process.send_signal(signal.SIGKILL)
        process.wait()
    assert study_status(_status_folder(tmp_path / "none"))["beds"] == []


def test_the_status_expects_runs_to_end_where_their_point_ended_or_past_their_t95(tmp_path, capsys):
    """Besides the most (every run to its duration), the status expects a run to end where its point's ended
    replicas in its family ended, and a run that has mixed time.stop_after_mixed past its t95."""
    from fvdem.study.status import study_status
    out = _status_folder(tmp_path)
    index = json.loads((out / "study.json").read_text())
    mixed = out / "runs" / "m_r1"  # mixed at 3.325 s (entropy t / 3.5), 4 s held, ends 2 s past t95
    mixed.mkdir()
    (mixed / "timeseries.csv").write_text("time,mixing_entropy\n" + "".join(
        f"{0.01 * k!r},{min(1.0, 0.01 * k / 3.5)!r}\n" for k in range(401)))
    (mixed / "checkpoint.npz").write_bytes(b"a checkpoint at 4 s")
    (mixed / "case.toml").write_text("[time]\nstop_after_mixed = 2.0\n")
    index["runs"] += [{"name": "a_r2", "family": "ar1", "status": "pending", "folder": "runs/a_r2",
                       "point": {"gas.u_over_umf": 2.0}, "replica": 2, "duration": 8.0},
                      {"name": "m_r1", "family": "ar1", "status": "pending", "folder": "runs/m_r1",
                       "point": {"gas.u_over_umf": 2.9}, "replica": 1, "duration": 8.0}]
    (out / "study.json").write_text(json.dumps(index))
    status = study_status(out)
    runs = {r["name"]: r for r in status["runs"]}
    assert runs["a_r2"]["left"] == 8.0 and runs["a_r2"]["expected_left"] == pytest.approx(5.0)  # as a_r1 ended
    assert runs["m_r1"]["t95"] == pytest.approx(3.325, abs=0.006)
    assert runs["m_r1"]["left"] == pytest.approx(4.0)
    assert runs["m_r1"]["expected_left"] == pytest.approx(1.325, abs=0.006)
    # no ended replica of its family at its point: to its duration (a partial run from t = 0)
    assert [runs[n]["expected_left"] for n in ("a_r1", "b_r1", "b_r2", "c_r1")] == [0.0, pytest.approx(5.0), 8.0, 8.0]
    ar1 = status["families"]["ar1"]
    assert ar1["expected_left_simulated_seconds"] == pytest.approx(6.325, abs=0.006)
    assert ar1["expected_core_hours"] == pytest.approx(6.325 * 200.0 / 3600.0, rel=1e-3)
    assert status["expected_core_hours"] == pytest.approx(ar1["expected_core_hours"] + 21.0 * 600.0 / 3600.0)
    assert status["left_core_hours"] == pytest.approx((8.0 + 4.0) * 200.0 / 3600.0 + 21.0 * 600.0 / 3600.0)
    assert main(["study", str(out), "--status"]) == 0
    assert f"about {status['expected_core_hours']:.1f} core-hours if each run ends" in capsys.readouterr().out
    # the case read as a case: a margin with its unit, and a margin of 0 (the run ends at its t95)
    (mixed / "case.toml").write_text('[time]\nstop_after_mixed = "2 s"\n')
    runs = {r["name"]: r for r in study_status(out)["runs"]}
    assert runs["m_r1"]["expected_left"] == pytest.approx(1.325, abs=0.006)
    (mixed / "case.toml").write_text("[time]\nstop_after_mixed = 0.0\n")
    runs = {r["name"]: r for r in study_status(out)["runs"]}
    assert runs["m_r1"]["expected_left"] == 0.0  # mixed at 3.325 s, 4 s held: at its end


def test_the_status_expects_a_family_of_the_same_physics_to_end_and_run_at_its_kins_t95_and_rate(tmp_path, capsys):
    """The index lists each run's physics and time.stop_after_mixed (``write_index``): a family not measured yet
    whose runs have the physics of another's (a "<name>_t95" family ending when it mixes beside <name>) takes that
    family's CPU rate (not the slowest family's) and ends where that family's ended runs at its point mixed, plus its
    own margin; an unmixed run cut short before its duration tells nothing of its end, one at its duration says it
    runs there."""
    from fvdem.study.status import study_status
    out = _status_folder(tmp_path)
    index = json.loads((out / "study.json").read_text())
    for row in index["runs"]:
        row.update(physics="p-ar1" if row["family"] == "ar1" else "p-ar4", stop_after_mixed=2.0)
    cut = out / "runs" / "x_r1"  # ar1's physics at its point, cut short unmixed at 1 s (an expansion run)
    cut.mkdir()
    (cut / "summary.json").write_text(json.dumps({"simulated_time": 1.0, "cpu_seconds": 150.0}))
    index["runs"] += [
        {"name": "x_r1", "family": "ar1_cut", "status": "pending", "folder": "runs/x_r1", "replica": 1,
         "point": {"gas.u_over_umf": 2.0}, "duration": 1.0, "physics": "p-ar1", "stop_after_mixed": 2.0},
        *({"name": f"t_r{k}", "family": "ar1_t95", "status": "pending", "folder": f"runs/t_r{k}", "replica": k,
           "point": {"gas.u_over_umf": 2.0}, "duration": 8.0, "physics": "p-ar1", "stop_after_mixed": 0.0}
          for k in (1, 2)),
        {"name": "a_r2", "family": "ar1", "status": "pending", "folder": "runs/a_r2", "replica": 2,
         "point": {"gas.u_over_umf": 2.0}, "duration": 8.0, "physics": "p-ar1", "stop_after_mixed": 2.0},
        {"name": "n_r1", "family": "ar1_none", "status": "pending", "folder": "runs/n_r1", "replica": 1,
         "point": {"gas.u_over_umf": 2.0}, "duration": 8.0, "physics": "p-ar1", "stop_after_mixed": None},
        {"name": "u_r1", "family": "ar4_t95", "status": "pending", "folder": "runs/u_r1", "replica": 1,
         "point": {"gas.u_over_umf": 2.0}, "duration": 8.0, "physics": "p-ar9", "stop_after_mixed": 0.0}]
    (out / "study.json").write_text(json.dumps(index))
    status = study_status(out)
    runs, families = {r["name"]: r for r in status["runs"]}, status["families"]
    # a_r1 mixed at 3 s (ended 2 s past it); x_r1 cut short unmixed at 1 s is left out of the expectation
    assert [runs[n]["expected_left"] for n in ("t_r1", "t_r2", "a_r2")] == [pytest.approx(3.0)] * 2 + [
        pytest.approx(5.0)]
    assert runs["n_r1"]["expected_left"] == 8.0  # no margin: to its duration
    assert families["ar1_t95"]["rate_from"] == ["ar1", "ar1_cut"]  # the measured ones: 1000 CPU s / 5 s, 150 / 1
    rate = (1000.0 + 150.0) / 6.0
    assert families["ar1_t95"]["expected_core_hours"] == pytest.approx(6.0 * rate / 3600.0)
    assert runs["t_r1"]["expected_cpu_seconds_left"] == pytest.approx(3.0 * rate)
    assert "rate_from" not in families["ar4_t95"] and status["unmeasured"] == ["ar4_t95"]  # none of its physics
    assert runs["u_r1"]["expected_left"] == 8.0
    assert main(["study", str(out), "--status"]) == 0
    text = capsys.readouterr().out
    assert "(ar4_t95 at the slowest family's rate: none measured yet)" in text
    assert "(ar1_t95 at ar1 and ar1_cut's, ar1_none at ar1 and ar1_cut's: the same physics, none measured" in text
    # a run of the same physics that ended unmixed at its duration: this one runs there too
    (cut / "summary.json").write_text(json.dumps({"simulated_time": 8.0, "cpu_seconds": 150.0}))
    index["runs"][-6]["duration"] = 8.0
    (out / "study.json").write_text(json.dumps(index))
    runs = {r["name"]: r for r in study_status(out)["runs"]}
    assert runs["t_r1"]["expected_left"] == pytest.approx((3.0 + 8.0) / 2)


def test_study_and_summary_files_are_replaced_at_once_for_readers_polling_them(tmp_path):
    """study.json and summary.json are read while they are rewritten (--status, a study's progress, --report):
    written to a temporary file and renamed over the old one, nothing else left in the folder."""
    from fvdem.io.run_folder import write_text_atomic
    path = tmp_path / "study.json"
    path.write_text('{"old": 1}\n')
    before = os.stat(path).st_ino
    write_text_atomic(path, '{"new": 2}\n')
    assert json.loads(path.read_text()) == {"new": 2} and os.stat(path).st_ino != before  # a new file, renamed
    assert [p.name for p in tmp_path.iterdir()] == ["study.json"]
