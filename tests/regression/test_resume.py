"""Checkpoints: a resumed run continues bit-for-bit; a stopped run resumes; a torn write is harmless."""
import json
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import fvdem

CASE = """
name = "resume"
[domain]
upper = [0.04, 0.04, 0.1]
[particles]
shape = "spherocylinder"
count = 150
diameter = "3 mm"
length = "12 mm"
[particles.insertion]
upper = [0.04, 0.04, 0.1]
[time]
end = 0.03
[output]
progress = false
snapshot_interval = 0.01
timeseries_interval = 0.001
checkpoint_interval = 0.01
"""


def final_state(out):
    with np.load(out / "final_state.npz") as data:
        return {k: data[k] for k in data.files}


def test_resume_equals_uninterrupted(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    fvdem.Simulation(fvdem.load_case(path), tmp_path / "straight").run()
    # the same run stopped at 0.012 s (between checkpoints) ...
    fvdem.Simulation(fvdem.load_case(path, {"time.end": 0.012}), tmp_path / "split").run()
    # ... and resumed to the end
    fvdem.Simulation(fvdem.load_case(path), tmp_path / "split", resume=True).run()
    a, b = final_state(tmp_path / "straight"), final_state(tmp_path / "split")
    assert a.keys() == b.keys()
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    ts_a = (tmp_path / "straight" / "timeseries.csv").read_text()
    ts_b = (tmp_path / "split" / "timeseries.csv").read_text()
    assert ts_a == ts_b


def test_a_run_ends_stop_after_mixed_past_its_mixing_time_and_a_raised_margin_runs_it_on(tmp_path):
    """``time.stop_after_mixed``: the run ends that long after t95 instead of at ``time.end`` (here t95 = 0:
    one analysis cell holds both colours, entropy 1 from the start), and says why; resumed under the same case
    it stays ended (no step), with a larger margin it runs on to it, bit-for-bit as a run straight there."""
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    mixed = {"output.mixing_cells": [1, 1, 1], "time.stop_after_mixed": 0.01, "output.vtk": False}
    out = tmp_path / "mixed"
    summary = fvdem.Simulation(fvdem.load_case(path, mixed), out).run()
    assert summary["t95"] == 0.0 and summary["ended"] == "mixed" and not summary["settled"]
    assert summary["simulated_time"] == pytest.approx(0.01) and summary["steps"] == 200
    assert "ended time.stop_after_mixed past its mixing time (t95 0 s)" in (out / "run.log").read_text()
    again = fvdem.Simulation(fvdem.load_case(path, mixed), out, resume=True).run()
    assert again["steps"] == 200 and again["ended"] == "mixed"
    later = {**mixed, "time.stop_after_mixed": 0.02}
    resumed = fvdem.Simulation(fvdem.load_case(path, later), out, resume=True).run()
    assert resumed["simulated_time"] == pytest.approx(0.02) and resumed["ended"] == "mixed"
    fvdem.Simulation(fvdem.load_case(path, later), tmp_path / "straight").run()
    a, b = final_state(tmp_path / "straight"), final_state(out)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    assert (tmp_path / "straight" / "timeseries.csv").read_text() == (out / "timeseries.csv").read_text()
    # without it the run goes to time.end (0.03 s)
    free = fvdem.Simulation(fvdem.load_case(path, {**mixed, "time.stop_after_mixed": None}), out, resume=True).run()
    assert free["ended"] is None and free["simulated_time"] == pytest.approx(0.03)


def test_torn_checkpoint_write_leaves_previous_checkpoint_usable(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    out = tmp_path / "run"
    fvdem.Simulation(fvdem.load_case(path, {"time.end": 0.01}), out).run()
    # a run killed while writing leaves a partial temporary file behind
    (out / "checkpoint.npz.tmp").write_bytes(b"PK\x03\x04 partial")
    sim = fvdem.Simulation(fvdem.load_case(path), out, resume=True)
    assert sim.time == 0.01
    sim.run()
    assert sim.time >= 0.03 - 1e-12


def test_cli_stop_and_resume(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(CASE.replace("end = 0.03", "end = 2.0"))
    out = tmp_path / "run"
    proc = subprocess.Popen([sys.executable, "-m", "fvdem.cli", "run", str(path), "--out", str(out)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 120
    while not (out / "checkpoint.npz").exists() and time.time() < deadline:
        time.sleep(0.2)
    proc.send_signal(signal.SIGINT)
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "--resume" in stderr and "Traceback" not in stderr
    stopped_at = fvdem.Simulation(fvdem.load_case(path), out, resume=True).time
    assert 0 < stopped_at < 2.0
    result = subprocess.run([sys.executable, "-m", "fvdem.cli", "run", str(path), "--out", str(out), "--resume",
                             "--set", "time.end=%r" % (stopped_at + 0.005)], capture_output=True, text=True,
                            timeout=300)
    assert result.returncode == 0, result.stderr
    assert '"simulated_time": %r' % (stopped_at + 0.005) in result.stdout or "simulated_time" in result.stdout


def test_parallel_run_exits_cleanly(tmp_path):
    """numba's parallel runtime must not hang the interpreter at exit."""
    path = tmp_path / "case.toml"
    path.write_text(CASE.replace("end = 0.03", "end = 0.002"))
    start = time.time()
    result = subprocess.run([sys.executable, "-m", "fvdem.cli", "run", str(path), "--out", str(tmp_path / "o"),
                             "--threads", "2"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert time.time() - start < 120


def test_non_finite_state_is_reported_with_the_cause(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(CASE)
    sim = fvdem.Simulation(fvdem.load_case(path))
    sim.particles.velocity[3, 0] = np.nan
    try:
        sim.run(0.002)
    except fvdem.SimulationError as exc:
        message = str(exc)
    else:
        raise AssertionError("a NaN velocity went unnoticed")
    assert "non-finite" in message and "collision time" in message and "DEM time step" in message


def test_cli_exits_3_when_the_run_becomes_unstable(tmp_path):
    # soft walls + a huge initial speed: particles punch through the floor
    text = CASE.replace("[time]", "[contact]\nnormal_stiffness = 1.0\n[time]").replace(
        'count = 150', 'count = 150\ninitial_state = "state.npz"')
    fvdem.Simulation(fvdem.load_case(_write(tmp_path, CASE)), tmp_path / "seed").run(0.001)
    with np.load(tmp_path / "seed" / "final_state.npz") as data:
        state = {k: data[k] for k in data.files}
    state["velocity"][:, 2] = -50.0
    np.savez(tmp_path / "state.npz", **state)
    result = subprocess.run([sys.executable, "-m", "fvdem.cli", "run", str(_write(tmp_path, text, "soft.toml")),
                             "--out", str(tmp_path / "out"), "--set", "time.dem_step=1e-4"],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 3, result.stderr
    assert "left the domain through a wall" in result.stderr and "Traceback" not in result.stderr


def _write(tmp_path, text, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


COUPLED = """
name = "kill"
[domain]
upper = [0.03, 0.03, 0.15]
[particles]
count = 120
diameter = "4 mm"
density = 1442.0
colour = "by_height"
[particles.insertion]
upper = [0.03, 0.03, 0.1]
seed = 2
[gas]
enabled = true
cells = [2, 2, 10]
inlet_velocity = 1.8
[time]
dem_step = 2.5e-5
end = 0.08
[output]
progress = false
snapshot_interval = 0.004
timeseries_interval = 0.001
checkpoint_interval = 0.006
"""


def test_coupled_run_stopped_and_killed_at_random_moments_resumes_bit_for_bit(tmp_path):
    """A small coupled bed run straight, and the same run stopped with SIGTERM and killed with SIGKILL
    at random moments (checkpoints every 6 ms and snapshots every 4 ms, so that some kills land in a
    write), each time resumed with --resume: the final particle state and the time series are
    bit-for-bit those of the straight run (the gas's voidage used to be re-mapped from the final
    positions on resume: positions then drifted by up to 3 cm in 0.3 s)."""
    path = _write(tmp_path, COUPLED)
    fvdem.Simulation(fvdem.load_case(path), tmp_path / "straight").run()
    out = tmp_path / "killed"
    rng = np.random.default_rng(7)
    command = [sys.executable, "-m", "fvdem", "run", str(path), "--out", str(out)]
    signals, attempts = [signal.SIGTERM, signal.SIGKILL, signal.SIGKILL, signal.SIGTERM], 0
    def finished():
        summary = out / "summary.json"  # a stopped run writes one too, marked stopped_early
        return summary.exists() and not json.loads(summary.read_text())["stopped_early"]

    def written():
        return {str(f): (f.stat().st_size, f.stat().st_mtime_ns) for f in out.rglob("*")} if out.exists() else {}

    while not finished():
        resume = ["--resume"] if (out / "checkpoint.npz").exists() else ["--overwrite"]
        before = written()
        proc = subprocess.Popen(command + resume, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        if attempts < len(signals):
            time.sleep(rng.uniform(3.0, 7.0))  # interpreter start and numba's cache load take ~3 s
            proc.send_signal(signals[attempts])
        _, stderr = proc.communicate(timeout=300)
        # a SIGTERM after the run finished lands in the interpreter's shutdown (Python has reset its
        # handlers; numba's threads wind down): killed, with everything written; one while the interpreter
        # still imports fvdem (before `fvdem run` sets its handlers: over 7 s on a busy machine) kills it
        # before it has touched the folder
        assert proc.returncode in (0, 130, -signal.SIGKILL) or (proc.returncode == -signal.SIGTERM and (
            finished() or written() == before)), stderr
        assert "Traceback" not in stderr
        attempts += 1
        assert attempts < 12
    a, b = final_state(tmp_path / "straight"), final_state(out)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    assert (tmp_path / "straight" / "timeseries.csv").read_text() == (out / "timeseries.csv").read_text()


def test_full_disk_stops_the_run_cleanly_and_keeps_the_last_checkpoint(tmp_path, monkeypatch):
    """A write that fails with ENOSPC (a full disk) in the middle of a run raises OutputError naming
    the cause and the remedy; the checkpoint of the last interval is intact and resumes."""
    import errno

    import fvdem.io.run_folder as run_folder
    path = _write(tmp_path, CASE)
    out = tmp_path / "run"
    sim = fvdem.Simulation(fvdem.load_case(path), out)
    sim.run(0.01)  # a complete checkpoint at 0.01 s
    good = (out / "checkpoint.npz").read_bytes()
    real_save = run_folder.save_checkpoint

    def full_disk(target, arrays, meta):
        with open(str(target) + ".tmp", "wb") as fh:
            fh.write(b"PK\x03\x04 half")  # the disk fills during the write
        raise OSError(errno.ENOSPC, "No space left on device", str(target) + ".tmp")

    monkeypatch.setattr(run_folder, "save_checkpoint", full_disk)
    with pytest.raises(fvdem.OutputError) as failure:
        sim.run(0.01)
    message = str(failure.value)
    assert "No space left on device" in message and "--resume" in message
    assert (out / "checkpoint.npz").read_bytes() == good
    monkeypatch.setattr(run_folder, "save_checkpoint", real_save)
    resumed = fvdem.Simulation(fvdem.load_case(path), out, resume=True)
    assert resumed.time == pytest.approx(0.01)


def test_cli_reports_an_unwritable_output_folder_in_one_line(tmp_path):
    path = _write(tmp_path, CASE)
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    result = subprocess.run([sys.executable, "-m", "fvdem", "run", str(path), "--out", str(blocker / "sub")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert len(result.stderr.strip().splitlines()) == 1


def test_resume_refuses_a_case_with_other_physics_and_accepts_safe_changes(tmp_path):
    path = _write(tmp_path, CASE)
    out = tmp_path / "run"
    fvdem.Simulation(fvdem.load_case(path, {"time.end": 0.005}), out).run()
    with pytest.raises(fvdem.OutputError) as refusal:
        fvdem.Simulation(fvdem.load_case(path, {"contact.friction": 0.1, "particles.density": 2000.0}), out,
                         resume=True)
    message = str(refusal.value)
    assert "contact.friction: 0.46" in message or "contact.friction:" in message
    assert "particles.density:" in message and "time.end:" not in message
    sim = fvdem.Simulation(fvdem.load_case(path, {"time.end": 0.01, "output.snapshot_interval": 0.002,
                                                  "run.threads": 1}), out, resume=True)
    assert sim.time == pytest.approx(0.005)


def test_a_checkpoint_of_the_former_layout_is_read_into_the_scenes_histories():
    """Checkpoints written before the scenes (issue 15) kept each history under its own key."""
    from fvdem.io.run_folder import upgrade_writer_state
    former = {"pvd_entries": [[0.0, "particles_00000.vtu"]], "gas_pvd_entries": [[0.0, "gas_00000.vtu"]],
              "wall_seconds": 1.5, "cpu_seconds": 2.5, "settled": False,
              "pressure_history": [[0.1, 900.0]], "mixing_history": [[0.0, 0.1], [0.1, 0.2]],
              "suspension_history": [[0.1, 15.0, 0.01, 0.002, 0.001]], "orientation_history": [[0.1, 0.5, 0.7]]}
    now = upgrade_writer_state(former)
    assert now == {"wall_seconds": 1.5, "cpu_seconds": 2.5, "ended": "",
                   "snapshots": {"particles": [[0.0, "particles_00000.vtu"]], "gas": [[0.0, "gas_00000.vtu"]]},
                   "histories": {"bed_pressure": [[0.1, 900.0]], "mixing": [[0.0, 0.1], [0.1, 0.2]],
                                 "suspension": {"samples": [[0.1, 15.0, 0.01, 0.002, 0.001]],
                                                "orientations": [[0.1, 0.5, 0.7]]}}}
    assert upgrade_writer_state(now) == now
    # a bed that settled before the scenes' end tests (0.2.0) ended "settled"
    assert upgrade_writer_state({"settled": True})["ended"] == "settled"


def test_a_signal_while_the_run_is_set_up_stops_it_cleanly(tmp_path, monkeypatch, capsys):
    """SIGTERM before Simulation.run installs its handlers (loading the state, numba's cache) exits with
    130 and a message, not a kill; the caller's handlers come back (issue 19's CI flake on a fresh clone)."""
    import os
    import fvdem.simulation
    from fvdem.cli import main
    path = _write(tmp_path, CASE)

    class Interrupted(fvdem.simulation.Simulation):
        def __init__(self, *args, **kwargs):
            os.kill(os.getpid(), signal.SIGTERM)  # arrives while the run is being built
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(fvdem.simulation, "Simulation", Interrupted)
    before = signal.getsignal(signal.SIGTERM)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 130
    assert "stopped before the run started" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGTERM) is before


@pytest.mark.parametrize("split", [0.012, 0.036])
def test_a_ramped_inlet_resumes_bit_for_bit_during_and_after_its_ramp(tmp_path, split):
    """With gas.inlet_ramp the gas starts with no inflow and the ramp raises it while it lasts. A run
    resumed after the ramp's end used to keep no inflow at all (the bed collapsed: found in the subset
    study, where every run resumed after its 1 s ramp lost its gas); resumed during or after the ramp
    it is the straight run bit for bit, with the full inflow at the end."""
    text = COUPLED.replace("inlet_velocity = 1.8", "inlet_velocity = 1.8\ninlet_ramp = 0.024")
    path = _write(tmp_path, text.replace("end = 0.08", "end = 0.048"))
    fvdem.Simulation(fvdem.load_case(path), tmp_path / "straight").run()
    fvdem.Simulation(fvdem.load_case(path, {"time.end": split}), tmp_path / "split").run()
    resumed = fvdem.Simulation(fvdem.load_case(path), tmp_path / "split", resume=True)
    assert resumed.gas.solver.inlet_velocity == pytest.approx(1.8 * min(1.0, split / 0.024))
    resumed.run()
    assert resumed.gas.solver.inlet_velocity == 1.8
    a, b = final_state(tmp_path / "straight"), final_state(tmp_path / "split")
    for key in a:
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)
    assert (tmp_path / "straight" / "timeseries.csv").read_text() == (tmp_path / "split" / "timeseries.csv").read_text()


def test_a_time_series_of_another_version_resumes_with_its_columns_kept_by_name(tmp_path):
    """A checkpoint written by a version with other time-series columns: on resume the rows up to the
    checkpoint keep their values under their names, a new column reads nan there, a dropped one goes."""
    from fvdem.io.timeseries import TimeseriesWriter
    path = tmp_path / "timeseries.csv"
    path.write_text("time,kinetic_energy,old_column\n0.1,1.5,7\n0.2,2.5,8\n0.3,3.5,9\n")
    writer = TimeseriesWriter(path, ["time", "vertical_momentum", "kinetic_energy"])
    writer.start(resume_time=0.2)
    writer.append({"time": 0.25, "vertical_momentum": 0.5, "kinetic_energy": 3.0})
    rows = [line.split(",") for line in path.read_text().split()]
    assert rows[0] == ["time", "vertical_momentum", "kinetic_energy"]
    assert rows[1] == ["0.1", "nan", "1.5"] and rows[2] == ["0.2", "nan", "2.5"]
    assert [float(v) for v in rows[3]] == [0.25, 0.5, 3.0] and len(rows) == 4
