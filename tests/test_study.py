"""fvdem study (issue 17): a study file expands into checked runs, runs them as Dask tasks with the
settled bed prepared once, skips finished runs on a second call, and reports a failed run's cause."""
import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from fvdem.case import CaseError
from fvdem.study import STOP_FILE, RunSpec, write_index, load_study, request_stop, run_task, select_runs
from fvdem.study.runner import _priority

ROOT = Path(__file__).resolve().parents[1]
SMOKE = ROOT / "studies" / "smoke.toml"


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
    _, run = _small_run(tmp_path, 0.02)
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


@pytest.mark.slow
def test_the_smoke_study_runs_on_a_local_cluster_and_a_second_call_starts_nothing(tmp_path):
    out = tmp_path / "study"
    command = [sys.executable, "-m", "fvdem", "study", str(SMOKE), "--out", str(out), "--workers", "2", "--json"]
    first = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert first.returncode == 0, first.stderr
    result = json.loads(first.stdout.strip().splitlines()[-1])
    assert result["study"] == "smoke" and result["scheduler"].startswith("LocalCluster(2 workers")
    assert [r["status"] for r in result["runs"]] == ["finished", "finished"]
    assert all((Path(r["folder"]) / "summary.json").exists() for r in result["runs"])
    # one progress view: simulated seconds over all runs, runs done, time left (a line per 2 % in a log)
    assert "study smoke (simulated s): 100% 0.0400/0.0400 s, 2/2 runs done" in first.stderr
    assert "Port 8787" not in first.stderr
    assert "LocalCluster(2 workers x 1 numba threads); Dask dashboard at http://" in first.stderr  # printed at start
    # both runs started from the one settled bed
    for r in result["runs"]:
        assert (out / "beds" / "small" / "final_state.npz").as_posix() in (Path(r["folder"]) / "case.toml").read_text()
    assert (out / "t95.png").exists() and (out / "table.csv").exists()
    second = subprocess.run(command, capture_output=True, text=True, timeout=600)
    assert [r["status"] for r in json.loads(second.stdout.strip().splitlines()[-1])["runs"]] == ["skipped", "skipped"]


def _one_run_study(tmp_path, name, checkpoint_interval):
    """A study of one 0.3 s run of the 150-sphere demo bed at 2 Umf (run small_u_over_umf2)."""
    study = tmp_path / f"{name}.toml"
    study.write_text(f'''name = "{name}"
duration = 0.3
[settings]
"output.vtk" = false
"output.checkpoint_interval" = {checkpoint_interval}
"output.timeseries_interval" = 0.005
[families.small]
case = "{ROOT / 'cases' / 'demo.toml'}"
[families.small.set]
"particles.count" = 150
[axes]
"gas.u_over_umf" = [2.0]
''')
    return study


@pytest.mark.slow
def test_a_worker_killed_mid_run_is_replaced_and_the_run_resumes_from_its_checkpoint(tmp_path):
    """SIGKILL the worker process while its run is past a checkpoint: Dask gives the task to a new
    worker, the run resumes from the checkpoint and ends bit-for-bit where an uninterrupted run does."""
    import signal
    import time

    import numpy as np
    import psutil
    study = _one_run_study(tmp_path, "kill", checkpoint_interval=0.02)
    out = tmp_path / "study"
    command = [sys.executable, "-m", "fvdem", "study", str(study), "--out", str(out), "--workers", "1", "--json"]
    proc = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    checkpoint = out / "runs" / "small_u_over_umf2" / "checkpoint.npz"
    deadline = time.time() + 300
    while not checkpoint.exists() and time.time() < deadline and proc.poll() is None:
        time.sleep(0.2)
    assert checkpoint.exists(), "the run never wrote a checkpoint"
    workers = [p for p in psutil.Process(proc.pid).children(recursive=True)
               if "spawn_main" in " ".join(p.cmdline()) and "resource_tracker" not in " ".join(p.cmdline())]
    assert workers, "no worker process found"
    for worker in workers:
        worker.send_signal(signal.SIGKILL)
    stdout, stderr = proc.communicate(timeout=600)
    assert proc.returncode == 0, stderr
    (run,) = json.loads(stdout.strip().splitlines()[-1])["runs"]
    assert run["status"] == "resumed" and run["simulated_seconds"] == pytest.approx(0.3)
    # the same run uninterrupted
    import fvdem
    straight = tmp_path / "straight"
    case = fvdem.load_case(ROOT / "cases" / "demo.toml", {"particles.count": 150, "gas.u_over_umf": 2.0,
                                                           "time.end": 0.3, "output.vtk": False,
                                                           "output.checkpoint_interval": 0.02,
                                                           "output.timeseries_interval": 0.005,
                                                           "output.progress": False})
    fvdem.Simulation(case, straight, threads=1).run()
    with np.load(straight / "final_state.npz") as a, np.load(Path(run["folder"]) / "final_state.npz") as b:
        for key in a.files:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


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


def test_the_report_pairs_the_families_of_the_papers_figures(tmp_path, monkeypatch):
    """Figs. 3 / 7 (AR-1 against AR-4 MP) and 9 (AR-4 MP drag only against full) at the velocities both
    families ran, with every replica of each; a family without its partner draws no pair."""
    import fvdem.analysis.plots as plots
    from fvdem.study import report
    import fvdem.reports.mema2020.figures as mema
    drawn, plot_mixing, plot_void_fractions = {}, plots.plot_mixing, mema.plot_void_fractions
    monkeypatch.setattr(plots, "plot_mixing", lambda folders, path: drawn.setdefault(
        Path(path).name, [Path(f).name for f in folders]) and plot_mixing(folders, path))
    monkeypatch.setattr(mema, "plot_void_fractions", lambda runs, path: drawn.setdefault(
        Path(path).name, [Path(r["folder"]).name for r in runs]) and plot_void_fractions(runs, path))
    plot_t95, named = plots.plot_t95, {}

    def t95_chart(folders, path, names, **kw):  # each run's name on Fig. 4, and the runs set aside
        named.update(zip([Path(f).name for f in folders], names), aside=kw.get("aside"))
        return plot_t95(folders, path, names=names, **kw)
    monkeypatch.setattr(plots, "plot_t95", t95_chart)
    runs = []
    for family, ratio in (("ar1", 2.0), ("ar4_mp", 2.0), ("ar4_mp", 2.9), ("ar4_mp_drag", 2.9), ("ar1", 1.6),
                          ("ar1_r2", 2.0), ("ar1_r3", 2.0)):
        folder = tmp_path / "runs" / f"{family}_{ratio}"
        family = family.removesuffix("_r2").removesuffix("_r3")
        folder.mkdir(parents=True)
        on_its_way = folder.name == "ar1_r3_2.0"  # a replica on its way, not yet mixed (in its start-up)
        (folder / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.5,0.6\n"
                                               + ("" if on_its_way else "1.0,0.97\n"))
        (folder / "case.toml").write_text(f'name = "{family}"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = {ratio}\n')
        runs.append({"name": folder.name, "family": family, "status": "stopped" if on_its_way else "finished",
                     "folder": str(folder), "t95": None if on_its_way else 1.0, "point": {"gas.u_over_umf": ratio}})
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    names = sorted(Path(p).name for p in report(tmp_path))
    assert "fig3_mixing_2.png" in names and "fig7_void_fraction_2.png" in names and "fig9_mixing_2.9.png" in names
    assert not any(n.startswith(("fig3_mixing_1.6", "fig3_mixing_2.9", "fig9_mixing_2.png")) for n in names)
    assert {"mixing_ar1.png", "mixing_ar4_mp.png", "t95.png", "table.csv", "table.json"} <= set(names)
    assert drawn["fig3_mixing_2.png"] == ["ar1_2.0", "ar1_r2_2.0", "ar1_r3_2.0", "ar4_mp_2.0"]  # every AR-1 replica
    # the void fractions of the fluidized bed: the replica on its way and not yet mixed waits
    assert drawn["fig7_void_fraction_2.png"] == ["ar1_2.0", "ar1_r2_2.0", "ar4_mp_2.0"]
    # the paper's own charts: Fig. 3 at its 1.6, 1.7 and 2.9 Umf (none here ran both there), Fig. 9 a at every
    # velocity drag only ran
    assert "fig3_mixing.png" not in names and "fig9_mixing.png" in names
    assert "fig7_void_fraction.png" in names  # the paper's Fig. 7 panels: 2.0 Umf is one
    # AR-4 MP at 2.9 in a taller column (family ar4_mp_tall): once mixed, it stands for ar4_mp's run there in the
    # pairs, as in the findings (the roofed run keeps its own chart); on its way, it waits
    for family, on_its_way in (("ar1", False), ("ar4_mp_tall", False)):
        folder = tmp_path / "runs" / f"{family}_2.9"
        folder.mkdir(parents=True)
        (folder / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.5,0.6\n1.0,0.97\n")
        (folder / "case.toml").write_text(f'name = "{family}"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = 2.9\n')
        runs.append({"name": folder.name, "family": family, "status": "finished", "folder": str(folder), "t95": 1.0,
                     "point": {"gas.u_over_umf": 2.9}})
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    drawn.clear()
    names = sorted(Path(p).name for p in report(tmp_path))
    assert drawn["fig3_mixing_2.9.png"] == ["ar1_2.9", "ar4_mp_tall_2.9"]
    assert drawn["fig9_mixing_2.9.png"] == ["ar4_mp_drag_2.9", "ar4_mp_tall_2.9"]
    assert drawn["fig7_void_fraction_2.9.png"] == ["ar1_2.9", "ar4_mp_tall_2.9"]
    assert "mixing_ar4_mp.png" in names and "mixing_ar4_mp_tall.png" in names
    # Fig. 4: AR-4 MP's line through the taller column's run, the paper's column's run there a cross beside it
    aside = "ar4_mp: the paper's column, set aside (particles pinned at its outlet)"
    assert named["ar4_mp_tall_2.9"] == "ar4_mp" and named["ar4_mp_2.0"] == "ar4_mp" and named["ar4_mp_2.9"] == aside
    assert named["aside"] == {aside: "ar4_mp"}
    runs[-1] = {**runs[-1], "status": "stopped", "t95": None}
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    drawn.clear()
    (tmp_path / "runs" / "ar4_mp_tall_2.9" / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.5,0.6\n")
    report(tmp_path)
    assert drawn["fig3_mixing_2.9.png"] == ["ar1_2.9", "ar4_mp_2.9"]


def test_the_share_of_the_window_with_the_bed_top_at_the_outlet():
    """``bed_at_roof``: over the window (1 s after a 1 s ramp, for 3 s), the share of samples whose bed_top lies
    within 1 cm of the outlet."""
    import numpy as np
    from fvdem.reports.mema2020.table import _at_roof
    time = np.round(np.arange(0, 8.001, 0.01), 2)
    top = np.where((time >= 2.0) & (time < 3.5), 1.05, 0.6)  # at the roof for the first half of 2-5 s
    series = {"time": time, "bed_top": top}
    assert _at_roof(series, 1.05, ramp=1.0) == pytest.approx(150 / 301, abs=1e-9)
    assert _at_roof({**series, "bed_top": np.full_like(time, 1.045)}, 1.05, ramp=1.0) == 1.0  # within 1 cm
    assert _at_roof(series, None, ramp=1.0) is None and _at_roof({"time": time}, 1.05) is None


def test_the_share_of_the_particles_pinned_at_the_outlet_at_the_end(tmp_path):
    """``roof_share``: the column's top layer of the mixing grid at the last snapshot, from a run's snapshots or
    its archived colour-by-layer record; 0 where the bed's top never reached the outlet (nothing read), and
    where the record stops below the top layer."""
    import json

    import numpy as np
    from fvdem.analysis.plots import COLOUR_LAYERS
    from fvdem.scenes.observables import colour_layer_record
    from fvdem.reports.mema2020.table import _reaches_roof, _roof_share
    time = np.round(np.arange(0, 6.001, 0.5), 2)
    series = {"time": time, "bed_top": np.where(time >= 1.5, 1.05, 0.5)}
    record = {"z_lower": 0.0, "layer_height": 0.03, "times": [0.0, 6.0],
              "count": [[100] * 34 + [0], [90] * 34 + [40]], "fraction": [[0.5] * 35, [0.5] * 35]}
    (tmp_path / COLOUR_LAYERS).write_text(json.dumps(record))
    assert _reaches_roof(series, 1.05) and not _reaches_roof(series, None) and not _reaches_roof(None, 1.05)
    assert _roof_share(series, 1.05, colour_layer_record(tmp_path)) == pytest.approx(40 / (90 * 34 + 40))
    low = {**series, "bed_top": np.full_like(time, 0.6)}
    assert not _reaches_roof(low, 1.05) and _roof_share(low, 1.05, None) == 0.0  # never up there: nothing to read
    short = {**record, "count": [[100] * 20, [100] * 20]}  # no snapshot reached above 0.6 m
    (tmp_path / COLOUR_LAYERS).write_text(json.dumps(short))
    assert _roof_share(series, 1.05, colour_layer_record(tmp_path)) == 0.0
    assert colour_layer_record(tmp_path / "none") is None and _roof_share(series, 1.05, None) is None
    assert _roof_share(series, None, record) is None and _roof_share(None, 1.05, record) is None


def test_the_dense_beds_height_and_expansion_from_the_centres_by_layer():
    """``_centre_quantile``: the height under a share of the centres, spread evenly within their layer (uniform
    counts: the share of the filled height); ``_dense_bed_expansion``: its mean over the window at the snapshots
    over its first, unmoved by the few particles thrown far above the bed that set the 99 % top."""
    import numpy as np
    from fvdem.reports.mema2020.table import _centre_quantile, _dense_bed_expansion
    assert _centre_quantile([100] * 10, 0.0, 0.03) == pytest.approx(0.9 * 0.3)  # uniform over 0-0.3 m
    assert _centre_quantile([100] * 10, 0.1, 0.03, share=0.5) == pytest.approx(0.1 + 0.15)
    assert _centre_quantile([0, 50, 50], 0.0, 0.1, share=0.5) == pytest.approx(0.2)  # the first layer holds none
    assert _centre_quantile([0, 0], 0.0, 0.03) is None
    settled = [100] * 10  # 0.27 m under 90 %
    expanded = [50] * 20  # 0.54 m
    spout = [50] * 20 + [0] * 10 + [1] * 5  # five centres thrown 0.3 m above it: 90 % of 1,005 lies at 0.543 m
    times = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5]
    record = {"z_lower": 0.0, "layer_height": 0.03, "times": times, "count": [settled] * 3 + [expanded] * 9}
    assert _dense_bed_expansion(record, ramp=1.0) == pytest.approx(2.0)  # window 2-5 s: all expanded
    thrown = {**record, "count": [settled] * 3 + [expanded, spout] * 4 + [expanded]}
    mean = np.mean([0.9 * 1005 / 50 * 0.03, 0.54] * 3 + [0.9 * 1005 / 50 * 0.03])  # the seven from 2.0 to 5.0 s
    assert _dense_bed_expansion(thrown, ramp=1.0) == pytest.approx(mean / 0.27)
    assert _dense_bed_expansion(thrown, ramp=1.0) < 2.02  # the spout moves it by under 1 %
    assert _dense_bed_expansion(None) is None and _dense_bed_expansion({**record, "count": []}) is None


def test_how_many_replicas_would_tell_comes_with_their_core_hours():
    """``replicas_to_tell``: the replicas in all of each series that bring the standard error times Student's t
    (at the plan's degrees of freedom) below what tells the difference, at the least cost (equal spreads and
    costs: equal counts, ``sqrt(sum var / n)``; a series 4 times the cost gets half the replicas); ``to_tell``:
    them, with the core-hours of those to add at a replica's CPU seconds there so far (``_replica_cost``: the mean
    of the runs at their end, of one column alone where asked)."""
    from fvdem.reports.mema2020.rules import _replica_cost
    from fvdem.reports.mema2020.spread import critical, replicas_to_tell, satterthwaite, to_tell

    def margin_squared(n, m):  # t^2 (1 / n + 1 / m) at the Welch-Satterthwaite degrees of freedom, unit variances
        return critical(satterthwaite([1 / n, 1 / m], [n - 1, m - 1])) ** 2 * (1 / n + 1 / m)
    # many replicas: t about 2 (2.006 at df 401): 202 and 201 bring it below 0.2^2, 201 and 201 do not
    assert replicas_to_tell([(2, 1.0, None), (2, 1.0, None)], 0.2, None) == [202, 201]
    assert margin_squared(202, 201) <= 0.04 < margin_squared(201, 201)
    assert replicas_to_tell([(2, 1.0, 4.0), (2, 1.0, 1.0)], 0.2, None) == [152, 303]  # cost 911 against 1,000
    assert margin_squared(152, 303) <= 0.04 < margin_squared(151, 303)
    # few: two a side already hold the difference to 2 standard errors (2 / 2 = 1 = (2 / 2)^2), but at df 2 t is
    # 4.53; four a side (df 6, t 2.52: 6.33 x 2 / 4 = 3.17 <= 4), where three (df 4, t 2.87: 8.24 x 2 / 3) fall short
    assert replicas_to_tell([(2, 1.0, None), (2, 1.0, None)], 2.0, None) == [4, 4]
    assert critical(2) == pytest.approx(4.5265, abs=1e-4) and critical(None) == 2.0
    assert replicas_to_tell([(2, 1.0, None), (2, 1.0, None)], 0.0, None) is None  # nothing to tell
    assert replicas_to_tell([(2, 1.0, None), (2, 1.0, None)], 1e-4, None) is None  # beyond MAX_PLANNED
    assert replicas_to_tell([(50, 1.0, None), (50, 1.0, None)], 2.0, None) is None  # none missing

    def run(family, v, cpu, status="finished", **more):
        return {"family": family, "gas.u_over_umf": v, "status": status, "cpu_seconds": cpu, **more}
    rows = [run("ar1", 1.6, 1000.0), run("ar1", 1.6, 3000.0), run("ar1", 1.6, 50.0, status="stopped"),
            run("ar1", 2.0, 9000.0), run("ar4_mp", 1.6, 7200.0, column="ar4_mp_expansion"), run("ar4_mp", 1.6, 72000.0)]
    assert _replica_cost(rows, "ar1", 1.6) == 2000.0  # the run on its way left out
    assert _replica_cost(rows, "ar4_mp", 1.6, "ar4_mp_expansion") == 7200.0  # the runs cut short alone
    assert _replica_cost(rows, "ar4_mp", 1.6) == (7200.0 + 72000.0) / 2 and _replica_cost(rows, "ar4_sp", 1.6) is None
    # where runs ended when they mixed ("<family>_t95", ``cut_at_t95``), the replicas to add are of those
    rows.append(run("ar1", 2.0, 6000.0, column="ar1_t95", cut_at_t95=True))
    assert _replica_cost(rows, "ar1", 2.0) == 6000.0 and _replica_cost(rows, "ar1", 1.6) == 2000.0
    # 14 of each: AR-1 has 4 (10 more at 2000 s), AR-4 MP 3 (11 more at 7200 s): 27.6 core-hours
    series = [("ar1", 4, 2000.0), ("ar4_mp", 3, 7200.0)]
    assert to_tell([14, 14], series) == (
        "about 14 of ar1 and 14 of ar4_mp in all would tell (now 4 and 3), if the means and spread stay: [[points]]; "
        "about 27.6 core-hours at their runs' cost so far")
    assert to_tell([14, 14], [series[0], ("ar4_mp", 3, None)]).endswith("stay: [[points]]")  # a cost unknown
    assert to_tell(None, series) == "more replicas would tell: [[points]]"


def test_a_findings_numbers_read_as_one_line():
    from fvdem.study.reports import describe_values
    assert describe_values({"1.6": {"ar4_mp": "> 20 (not mixed)", "ar1": 16.901617}, "2": {"ar1": [1.7301, 2.0]}}) \
        == "1.6: (ar4_mp: > 20 (not mixed); ar1: 16.9); 2: (ar1: 1.73, 2)"
    assert describe_values(3.0) == "3" and describe_values(None) == "None"


def test_the_papers_fig7_pools_each_familys_replicas_panel_by_panel(tmp_path, monkeypatch):
    """Fig. 7 as the paper draws it: a panel per velocity, one histogram per family, its replicas pooled by
    their cells, each replica's binarity in the label; a velocity without snapshots says so."""
    import fvdem.analysis.plots as plots
    from fvdem.reports.mema2020.figures import plot_void_fraction_panels
    from fvdem.reports.mema2020.table import VOID_FRACTION
    edges = [0.05 * k for k in range(21)]
    runs = []
    for name, family, cells, peak, binarity in (("a1", "ar1", 100, 9, 0.4), ("a2", "ar1", 300, 10, 0.5),
                                                ("b1", "ar4_mp", 200, 11, None)):
        folder = tmp_path / name
        folder.mkdir()
        density = [0.0] * 20
        density[peak] = 20.0  # all cells in one bin of width 0.05
        (folder / VOID_FRACTION).write_text(json.dumps({"below": 0.3, "edges": edges, "density": density,
                                                        "cells": cells, "binarity": binarity}))
        runs.append({"name": name, "family": family, "folder": str(folder)})
    empty = tmp_path / "empty"
    empty.mkdir()
    figures, real_save = [], plots._save
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or real_save(fig, path))
    plot_void_fraction_panels({2.0: runs, 1.6: [{"name": "e", "family": "ar1", "folder": str(empty)}]},
                              tmp_path / "fig7.png")
    first, second = figures[0].axes  # one row of two
    assert first.get_title() == "1.6 Umf: no gas snapshots" and not first.get_lines()
    assert second.get_title() == "2 Umf"
    lines = {line.get_label(): line.get_ydata() for line in second.get_lines()}
    assert set(lines) == {"ar1 (2 runs, binarity 0.40, 0.50)", "ar4_mp (1 run, binarity -)"}
    pooled = lines["ar1 (2 runs, binarity 0.40, 0.50)"]
    assert pooled[9] == pytest.approx(20.0 * 100 / 400) and pooled[10] == pytest.approx(20.0 * 300 / 400)
    assert sum(pooled) * 0.05 == pytest.approx(1.0)  # still a density


def test_a_run_in_progress_is_reported_from_its_time_series_not_from_an_earlier_stops_summary(tmp_path):
    """A run stopped once early and running again: its summary.json is from the first stop; the table
    takes t95, the pressure drop and its fluctuation and the bed height from what the time series holds now."""
    import numpy as np
    from fvdem.study import report
    folder = tmp_path / "runs" / "ar1_2.9"
    folder.mkdir(parents=True)
    (folder / "case.toml").write_text('name = "ar1"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = 2.9\n')
    (folder / "summary.json").write_text(json.dumps({"stopped_early": True, "bed_pressure_drop_std_second_half": 5.0,
                                                     "bed_weight_per_area": 1000.0, "bed_height": 0.2,
                                                     "pressure_drop_over_weight": 1.03, "simulated_time": 0.07}))
    t = np.linspace(0.0, 3.0, 31)
    drop = 1.0 + 0.3 * np.sin(5.0 * t)
    entropy = np.minimum(1.0, t / 2.0)
    top = 0.3 + 0.05 * np.sin(3.0 * t)
    fastest = 12.0 + 4.0 * t
    overlap = 0.04 + 0.001 * np.arange(len(t))  # 0.04 ... 0.07, then one impact
    overlap[17] = 0.3
    (folder / "timeseries.csv").write_text(
        "time,mixing_entropy,pressure_drop_over_weight,bed_top,gas_max_speed,max_overlap_over_diameter\n"
        + "".join(f"{a},{b},{c},{d},{e},{f}\n" for a, b, c, d, e, f in zip(t, entropy, drop, top, fastest, overlap)))
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [
        {"name": "ar1_2.9", "family": "ar1", "status": "stopped", "folder": str(folder), "t95": None,
         "point": {"gas.u_over_umf": 2.9}}]}))
    report(tmp_path)
    row = json.loads((tmp_path / "table.json").read_text())[0]
    half = t >= 1.5
    assert row["simulated_seconds"] == 3.0 and row["t95"] == pytest.approx(1.9, abs=0.02)
    assert row["pressure_drop_over_weight"] == pytest.approx(np.mean(drop[half]))
    assert row["pressure_drop_std_over_weight"] == pytest.approx(np.std(drop[half]))
    # the bed's surface over one window in every run, from 1 s after the inlet ramp (none here) for 3 s (the
    # summary's packed-bed height of 0.2 m is not a fluidized bed's height)
    window = (t >= 1.0) & (t <= 4.0)
    assert row["bed_height"] == pytest.approx(np.mean(top[window]))
    assert row["bed_expansion"] == pytest.approx(np.mean(top[window]) / 0.3)  # over the bed it started as
    # the largest cell gas speed over the inlet velocity (2.9 x 1.58 m/s), over the same window: channels
    assert row["gas_max_speed_over_inlet"] == pytest.approx(np.mean(fastest[window]) / (2.9 * 1.58))
    # the contacts' depth over the whole run: the impact is its largest, not its median or 99th percentile
    assert row["overlap_max"] == 0.3 and row["overlap_median"] == pytest.approx(0.055)  # the 16th of 31
    assert row["overlap_p99"] == pytest.approx(np.percentile(overlap, 99)) and row["overlap_p99"] < 0.3
    # runs of different lengths (8 s; ended at 5.5 s, 2 s past t95) over one window: a bed rising slowly
    # stands as high in both (over their second halves it would not: 6 s against 4.1 s)
    from fvdem.reports.mema2020.table import _bed_surface
    runs = [{"time": np.linspace(0.0, end, int(end * 100) + 1)} for end in (8.0, 5.5)]
    for series in runs:
        series["bed_top"] = 0.3 + 0.01 * series["time"]
    assert _bed_surface(runs[0], 1.0) == pytest.approx(_bed_surface(runs[1], 1.0)) == pytest.approx(0.335)
    assert _bed_surface(runs[0]) == pytest.approx(0.36) and _bed_surface(runs[1]) == pytest.approx(0.34125)


def test_the_papers_findings_are_checked_from_the_t95_table():
    from fvdem.reports.mema2020 import check_findings

    def row(family, ratio, t95):
        return {"family": family, "status": "finished", "gas.u_over_umf": ratio, "t95": t95}

    rows = [row("ar1", 1.6, 6.0), row("ar4_mp", 1.6, 4.0), row("ar1", 2.0, 3.0), row("ar4_mp", 2.0, 2.5),
            row("ar4_mp_drag", 2.0, 3.5), row("ar1", 2.9, 2.7), row("ar1", 2.6, 2.5), row("ar4_mp", 2.9, None)]
    verdicts = {f["finding"].split(" (")[0].split(",")[0]: f["verdict"] for f in check_findings(rows)
                if f.get("readings") != "second"}  # the first set (the second: tests/test_mema2020_readings.py)
    assert verdicts["AR-4"] == "holds"  # 4.0 < 6.0 and 2.5 < 3.0
    assert verdicts["lift and torque shorten AR-4 mixing"] == "holds"  # 2.5 < 3.5 at 2.0 Umf
    assert verdicts["single- against multi-particle closures: only a slight effect on AR-4 mixing"] == "open"
    assert verdicts["terminal t95 of ar1 about 2.6 s"] == "holds"  # 2.5 and 2.7: spread 7 %, mean 2.6
    assert verdicts["terminal t95 of ar4_mp about 2.3 s"] == "open"  # one velocity above 2.3, not mixed
    # a difference within 10 % without replicas cannot be told from chaos
    close = check_findings([row("ar1", 2.0, 3.0), row("ar4_mp", 2.0, 2.9)])[0]
    assert close["verdict"] == "open" and "too noisy" in close["why"]
    slower = check_findings([row("ar1", 2.0, 3.0), row("ar4_mp", 2.0, 4.0)])[0]
    assert slower["verdict"] == "does not hold"

    # a run not mixed by its end mixes later than one that mixed before that end (a lower bound)
    def unmixed(family, ratio, end, entropy):
        return dict(row(family, ratio, None), simulated_seconds=end, final_mixing_entropy=entropy)
    bound = check_findings([unmixed("ar1", 2.0, 6.0, 0.79), dict(row("ar4_mp", 2.0, 4.1), simulated_seconds=6.0)])[0]
    assert bound["verdict"] == "holds" and bound["values"]["2"]["ar4_mp"] == 4.1
    against = check_findings([row("ar1", 2.0, 3.0), unmixed("ar4_mp", 2.0, 6.0, 0.9)])[0]
    assert against["verdict"] == "does not hold"
    late = check_findings([row("ar1", 2.0, 7.0), unmixed("ar4_mp", 2.0, 6.0, 0.9)])[0]
    assert late["verdict"] == "open"  # mixed after the other's end: nothing follows
    # neither mixed by the same end: the higher mixing entropy there mixes faster (the paper's Figs. 3 and 9 a),
    # by the same rules: 16 % apart without replicas tells; replicas within their spread, or ends that differ, do not
    neither = check_findings([unmixed("ar1", 2.0, 6.0, 0.79), unmixed("ar4_mp", 2.0, 6.0, 0.943)])[0]
    assert neither["verdict"] == "holds"
    assert neither["values"]["2"]["mixing_entropy_at_end"] == {"ar4_mp": [0.943], "ar1": [0.79]}
    behind = check_findings([unmixed("ar1", 2.0, 6.0, 0.943), unmixed("ar4_mp", 2.0, 6.0, 0.79)])[0]
    assert behind["verdict"] == "does not hold"
    spread = check_findings([unmixed("ar1", 2.0, 20.0, 0.93), unmixed("ar4_mp", 2.0, 20.0, 0.946),
                             unmixed("ar4_mp", 2.0, 20.0, 0.852)])[0]  # means 0.899 against 0.93: within spread
    assert spread["verdict"] == "open" and "replicas' spread (neither mixed: ar4_mp against ar1, mixing " \
        "entropy at their end, 20 s" in spread["why"]
    uneven = check_findings([unmixed("ar1", 2.0, 8.0, 0.79), unmixed("ar4_mp", 2.0, 6.0, 0.943)])[0]
    assert uneven["verdict"] == "open" and "their ends differ (too short)" in uneven["why"]
    # replicas, one not mixed by the paper's 20 s: the family's mean t95 is bounded below by counting that run at
    # its end. AR-1 at 16.5 and 17.3 s (mean 16.9): AR-4 MP at > 20 and 19.5 s has a mean above 19.75, slower
    # (decided: 2.85 s apart, beyond Student's t times the standard error of the difference, 5.51 x 0.472 s = 2.60 s
    # at 1.68 degrees of freedom); at > 20 and 15 s (mean above 17.5) the difference, 0.6 s, lies within it (12.4
    # x 2.53 s): the order is open; at > 20 and 11 s the mean is only above 15.5: open, run it longer
    ar1 = [dict(row("ar1", 1.6, t), simulated_seconds=t + 2.0) for t in (16.5, 17.3)]
    slower = check_findings(ar1 + [unmixed("ar4_mp", 1.6, 20.0, 0.946), dict(row("ar4_mp", 1.6, 19.5),
                                                                             simulated_seconds=20.0)])[0]
    assert slower["verdict"] == "does not hold"
    assert slower["values"]["1.6"] == {"ar4_mp": "> 19.8 (1 of 2 not mixed by its end, at 20 s)",
                                       "ar1": pytest.approx(16.9)}
    within = check_findings(ar1 + [unmixed("ar4_mp", 1.6, 20.0, 0.946), dict(row("ar4_mp", 1.6, 15.0),
                                                                             simulated_seconds=17.0)])[0]
    assert within["verdict"] == "open"
    assert ("1.6 Umf within the replicas' spread (ar4_mp against ar1, t95 [s]: means 17.5 (20, 15) against 16.9 "
            "(16.5, 17.3), within 12.4 standard errors (31.4)") in within["why"]
    unknown = check_findings(ar1 + [unmixed("ar4_mp", 1.6, 20.0, 0.946), dict(row("ar4_mp", 1.6, 11.0),
                                                                              simulated_seconds=13.0)])[0]
    assert unknown["verdict"] == "open" and "only known to exceed 15.5 s, against 16.9 s" in unknown["why"]
    assert "run it longer" in unknown["why"]
    # the campaign's lift and torque at 1.6 Umf: AR-4 MP not mixed by 20 s in either replica (a mean above 20)
    # against drag only at 19.44 and 17.0 s (18.2, standard error of the difference 1.73, taking drag only's
    # variance for both): within their spread; drag only's mean lies at most 18.22 - 20 + 4.53 x 1.73 = 6.03 s
    # above MP's bound (Student's t at 2 degrees of freedom): open. With four replicas a side of the same values
    # (standard error 0.996, df 6, t 2.52) at most 0.73 s above, within 10 % of 20 s: MP is not the faster by
    # 10 %, so lift and torque do not shorten mixing there; drag only at 19.44 and 15.0 s (up to 14 s above) leaves
    # it open
    mp = [unmixed("ar4_mp", 1.6, 20.0, 0.946), unmixed("ar4_mp", 1.6, 20.0, 0.852)]
    claim = "lift and torque shorten AR-4 mixing"
    drag = [dict(row("ar4_mp_drag", 1.6, t), simulated_seconds=20.0) for t in (19.44, 17.0)]
    two = next(f for f in check_findings(mp + drag) if f["finding"] == claim)
    assert two["verdict"] == "open" and "within 4.53 standard errors (7.81)" in two["why"]
    lift = next(f for f in check_findings(mp * 2 + drag * 2) if f["finding"] == claim)
    assert lift["verdict"] == "does not hold"
    assert lift["values"]["1.6"]["alike"] == ("not below: the mean 20, a lower bound (runs not mixed by their end), "
                                              "against 18.2, which with 2.52 standard errors lies at most 0.727 above "
                                              "it, within 10 % of the larger (2)")
    drag[1]["t95"] = 15.0
    open_ = next(f for f in check_findings(mp + drag) if f["finding"] == claim)
    assert open_["verdict"] == "open"
    # how many would tell it: the one-sided likeness (MP's bound not below drag only's mean by 10 %, 2 s): t times
    # the standard error of the difference below 2 + 2.78 = 4.78 (drag only's variance 9.857 on both sides, MP's
    # being unknown): five of each (df 8, t 2.37: 5.61 x 9.857 x 2 / 5 = 22.1 <= 22.8), not the two-sided order's
    # 2.78 (12 of each; the planner said 11 and 10 before the plans became one-sided, and 4 and 4 with 2 for t)
    assert "about 5 of ar4_mp and 5 of ar4_mp_drag in all would tell (now 2 and 2)" in open_["why"]
    from fvdem.reports.mema2020.spread import replicas_to_tell, told_alike
    var = 4.44 ** 2 / 2
    assert replicas_to_tell([(2, var, None), (2, var, None)], 2.78, 2.0, bounded=True) == [5, 5]
    assert replicas_to_tell([(2, var, None), (2, var, None)], 2.78, 2.0) == [12, 12]  # two-sided: the order
    # and at these means and spread five and five do tell it, four and five not yet
    d = (var / 2.5) ** 0.5  # five values of mean 17.22 and variance ``var``
    five = [17.22 + k * d for k in (-2, -1, 0, 1, 2)]
    assert told_alike([20.0] * 5, five, bounded=True).startswith("not below: the mean 20")
    assert told_alike([20.0] * 4, five, bounded=True) is None
    # SP against MP "only a slight effect": mean t95s within 20 % of MP's; an unmixed family's mean a lower
    # bound, which decides once the gap it leaves reaches 20 % (SP mixed at 4.26 s, MP not by 20 s: > 0.79)
    claim = "single- against multi-particle closures: only a slight effect on AR-4 mixing"

    def slight(rows):
        return next(f for f in check_findings(rows) if f["finding"] == claim)
    apart = slight([dict(row("ar4_sp", 1.6, 4.26), simulated_seconds=6.26), unmixed("ar4_mp", 1.6, 20.0, 0.946)])
    assert apart["verdict"] == "does not hold" and apart["values"] == {"1.6": "> 0.787 (MP not mixed by its end)"}
    near = slight([row("ar4_sp", 2.0, 4.0), row("ar4_mp", 2.0, 4.5), row("ar4_sp", 2.9, 3.0), row("ar4_mp", 2.9, 2.8)])
    assert near["verdict"] == "holds" and near["values"]["2"] == pytest.approx(1 / 9)
    short = slight([unmixed("ar4_sp", 2.0, 6.0, 0.9), row("ar4_mp", 2.0, 5.5)])  # SP > 6: the gap > 9 %, unknown
    assert short["verdict"] == "open" and "at 2 Umf" in short["why"]
    # replicas within their spread yet alike: the difference of the means with t standard errors within 10 % of
    # the larger mean decides against a claimed order (AR-4 MP 4.3 s against AR-1 4.35, six replicas each: 0.05 s
    # faster on the means, within 2.4 x 0.05 s (df 7.4); 0.17 s at most, within 0.435 s: not faster; with two each
    # the same spread leaves 0.87 s, df 1.5: open). Wider spreads or a single run each tell no likeness: open
    pairs = [row("ar1", 2.0, 4.3), row("ar1", 2.0, 4.4), row("ar4_mp", 2.0, 4.2), row("ar4_mp", 2.0, 4.4)]
    assert check_findings(pairs)[0]["verdict"] == "open"
    alike = check_findings(pairs * 3)[0]
    assert alike["verdict"] == "does not hold"
    assert alike["values"]["2"]["alike"] == ("alike: the means 4.3 and 4.35 differ by 0.05, with 2.4 standard errors "
                                             "at most 0.17, within 10 % of the larger (0.435)")
    wide = check_findings([row("ar1", 2.0, 4.0), row("ar1", 2.0, 4.7), row("ar4_mp", 2.0, 4.0),
                           row("ar4_mp", 2.0, 4.6)])[0]
    assert wide["verdict"] == "open" and "replicas' spread" in wide["why"]
    # a bound (a run not mixed by its end, counted there) bounds one side: AR-4 MP's mean above 4.375 against
    # AR-1's 4.35 (standard error of the difference 0.056, df 1.5: t 6.61) lies at most 0.344 s above it: not
    # faster by 10 %;
    # AR-1's mean above 4.375 against AR-4 MP's 4.35 leaves AR-4 MP faster by any amount: open
    bounded = check_findings([dict(row("ar1", 2.0, 4.3), simulated_seconds=8.0),
                              dict(row("ar1", 2.0, 4.4), simulated_seconds=8.0),
                              unmixed("ar4_mp", 2.0, 4.35, 0.9),
                              dict(row("ar4_mp", 2.0, 4.4), simulated_seconds=8.0)])[0]
    assert bounded["verdict"] == "does not hold" and bounded["values"]["2"]["alike"].startswith(
        "not below: the mean 4.38, a lower bound (runs not mixed by their end), against 4.35, which with 6.61 "
        "standard errors lies at most 0.344 above it")
    other = check_findings([unmixed("ar1", 2.0, 4.35, 0.9), dict(row("ar1", 2.0, 4.4), simulated_seconds=8.0),
                            dict(row("ar4_mp", 2.0, 4.3), simulated_seconds=8.0),
                            dict(row("ar4_mp", 2.0, 4.4), simulated_seconds=8.0)])[0]
    assert other["verdict"] == "open" and "alike" not in other["values"]["2"]
    # one velocity where it is not faster decides, whatever another leaves open
    mixed_up = check_findings([row("ar1", 2.0, 3.0), row("ar4_mp", 2.0, 4.0), row("ar1", 1.7, 3.0),
                               row("ar4_mp", 1.7, 2.9)])[0]
    assert mixed_up["verdict"] == "does not hold"


def test_replicas_all_counted_at_one_end_have_an_unknown_spread_not_none():
    """Two AR-4 MP replicas both unmixed by 20 s (counted at 20, 20: sample variance 0) against one drag-only run
    mixed at 19.8 s: the error of the difference is not 0 (which would tell a 1 % gap); each side takes the
    other's variance, and where neither has one the 10 % rule decides."""
    from fvdem.reports.mema2020.spread import within_spread
    assert within_spread([20.0, 20.0], [19.8]) == "means 20 (20, 20) against 19.8 (19.8), within 10 % and no " \
        "spread known"
    assert within_spread([20.0, 20.0], [15.0]) is None  # 25 % apart: told
    # a spread on one side serves both: 16.5, 17.3 (sample variance 0.32) against 20, 20: error
    # sqrt(0.32 / 2 + 0.32 / 2) = 0.566 with the lender's degree of freedom on both sides (df 2: t 4.53), so 3.1 s
    # apart is told and 0.9 s is not
    assert within_spread([20.0, 20.0], [16.5, 17.3]) is None
    assert "within 4.53 standard errors (2.56)" in within_spread([18.0, 18.0], [16.5, 17.3])


def test_values_within_their_spread_are_alike_only_where_the_spread_rules_out_a_difference_of_ten_percent():
    """The equivalence side of the spread rule: 4.23 (4.21, 4.25) against 4.29 (4.30, 4.28) lie 0.06 apart, the
    standard error of the difference sqrt(0.0008 / 2 + 0.0002 / 2) = 0.0224: 0.148 with Student's t at 1.47
    degrees of freedom (6.61), within 10 % of 4.29; 4.0 / 4.7 against 4.0 / 4.6 are within their spread but not
    alike; one run each tells nothing of likeness, and one run takes the other family's variance (and its degrees
    of freedom)."""
    from fvdem.reports.mema2020.spread import told_alike
    assert told_alike([4.21, 4.25], [4.30, 4.28]).startswith("alike: the means 4.23 and 4.29 differ by 0.06, with 6.61 "
                                                         "standard errors at most 0.208")
    assert told_alike([4.0, 4.7], [4.0, 4.6]) is None
    assert told_alike([4.21], [4.30]) is None
    # 4.25 against 4.2, 4.3, 4.2, 4.3 (variance 0.00333 both sides, df 3 each: 4.4 in all, t 2.76): 0 + 0.178 < 0.425;
    # against two (df 1 each) not: t 5.5
    assert told_alike([4.2, 4.3] * 2, [4.25]).endswith("with 2.76 standard errors at most 0.178, within 10 % of the "
                                                   "larger (0.425)")
    assert told_alike([4.2, 4.3], [4.25]) is None
    # more replicas of the same spread tell two values 3 % apart alike, where two each did not
    assert told_alike([4.0, 4.3], [4.15, 4.45]) is None
    assert told_alike([4.0, 4.3] * 4, [4.15, 4.45] * 4) is not None


def test_the_bed_expansion_figure_draws_what_the_finding_counts(tmp_path, monkeypatch):
    """``bed_expansion.png`` (the report's, from the table's rows) shows the runs the expansion finding counts:
    a "<family>_expansion" family's runs as their family's, a taller column's in place of the paper's column's
    at its velocity, a bed whose top stood at the outlet apart (a cross), runs still on their way left out."""
    import fvdem.reports.mema2020.figures as mema
    from fvdem.reports.mema2020 import check_findings

    def row(family, ratio, height, status="finished", **more):
        return {"family": family, "status": status, "gas.u_over_umf": ratio, "t95": 3.0, "simulated_seconds": 8.0,
                "bed_expansion": height, **more}

    rows = [row("ar1", 1.6, 1.73), row("ar1", 1.6, 1.75), row("ar4_mp", 1.6, 1.63), row("ar4_mp", 1.6, 2.57),
            row("ar4_mp_expansion", 1.6, 2.2), row("ar1_expansion", 1.6, 1.72),
            row("ar1", 2.9, 3.1, bed_at_roof=1.0), row("ar1_tall", 2.9, 2.7), row("ar4_mp", 2.9, 4.0),
            row("ar4_mp", 2.9, 5.0, bed_at_roof=0.9), row("ar4_mp", 2.0, 2.8, status="running", t95=None),
            row("ar4_sp", 1.6, 1.9)]
    drawn = {}
    real = mema.plot_expansion
    monkeypatch.setattr(mema, "plot_expansion", lambda measured, roofed, path: drawn.update(
        measured=measured, roofed=roofed) or real(measured, roofed, path))
    assert mema.draw_table_figures(tmp_path, rows) == [tmp_path / "bed_expansion.png"]
    assert (tmp_path / "bed_expansion.png").stat().st_size > 10_000
    shown = sorted((r["family"], r["gas.u_over_umf"], r["bed_expansion"]) for r in drawn["measured"])
    finding = {f["finding"]: f for f in check_findings(rows)}["AR-4 beds expand more than AR-1 at the same U/Umf"]
    counted = sorted((family, float(v), h) for v, pair in finding["values"].items()
                     for family, heights in pair.items() for h in heights)
    assert shown == counted == [("ar1", 1.6, 1.72), ("ar1", 1.6, 1.73), ("ar1", 1.6, 1.75), ("ar1", 2.9, 2.7),
                                ("ar4_mp", 1.6, 1.63), ("ar4_mp", 1.6, 2.2), ("ar4_mp", 1.6, 2.57),
                                ("ar4_mp", 2.9, 4.0)]
    assert [(r["family"], r["bed_expansion"]) for r in drawn["roofed"]] == [("ar4_mp", 5.0)]  # the 1.05 m AR-1 aside
    assert mema.draw_table_figures(tmp_path, [row("ar4_sp", 1.6, 1.9)]) == []  # neither family: no figure


def test_runs_that_end_when_they_mix_count_for_the_t95_findings_alone(tmp_path, monkeypatch):
    """A family "<name>_t95" (<name>'s case ending when it mixes, from beds of its own: t95 is the entropy's first
    crossing, the same as a whole run's) counts as <name>'s in the t95 findings and Fig. 4, and "<name>_tall_t95"
    as a taller column's; neither in the bed expansion (a window it may not reach) nor in the void fractions
    (over the second half of a run that ended at t95)."""
    from fvdem.reports.mema2020 import check_findings
    from fvdem.reports.mema2020.figures import draw_figures

    def row(family, v, t95, height, binarity):
        return {"family": family, "status": "finished", "gas.u_over_umf": v, "t95": t95, "simulated_seconds": 8.0,
                "bed_expansion": height, "void_fraction_binarity": binarity}

    base = [row("ar1", 2.0, 4.21, 2.11, 0.38), row("ar1", 2.0, 5.45, 2.21, 0.42),
            row("ar4_mp", 2.0, 4.81, 2.84, 0.49), row("ar4_mp", 2.0, 5.48, 2.56, 0.51),
            row("ar1_tall", 2.9, 2.89, 2.68, 0.37), row("ar1_tall", 2.9, 3.62, 3.14, 0.38),
            row("ar4_mp_tall", 2.9, 2.64, 3.8, 0.47), row("ar4_mp_tall", 2.9, 2.89, 4.2, 0.50)]
    # cut at their t95, with heights and binarities that would turn both findings were they counted
    cut = [row("ar1_t95", 2.0, 4.6, 3.5, 0.9), row("ar1_t95", 2.0, 4.9, 3.6, 0.9),
           row("ar4_mp_t95", 2.0, 4.2, 1.2, 0.1), row("ar1_tall_t95", 2.9, 3.1, 3.3, 0.9),
           row("ar4_mp_tall_t95", 2.9, 2.7, 1.3, 0.1)]
    as_whole = [dict(r, family=r["family"][:-len("_t95")], bed_expansion=None, void_fraction_binarity=None)
                for r in cut]

    def found(rows):
        return {f["finding"]: f for f in check_findings(rows)}

    with_cut, alone, counted = found(base + cut), found(base), found(base + as_whole)
    expansion, binarity = "AR-4 beds expand more than AR-1 at the same U/Umf", "AR-1 void fractions more binary " \
        "than AR-4 (Fig. 7)"
    assert with_cut[expansion] == alone[expansion] and with_cut[binarity] == alone[binarity]
    shrinks = "the AR-1/AR-4 difference shrinks at the highest velocity (2.9 Umf)"
    assert with_cut[shrinks] == counted[shrinks] != alone[shrinks]
    assert with_cut[shrinks]["values"]["difference at 2.9 Umf"] == pytest.approx((2.89 + 3.62 + 3.1) / 3
                                                                                 - (2.64 + 2.89 + 2.7) / 3)
    assert {k: f for k, f in with_cut.items() if k not in (expansion, binarity)} == \
        {k: f for k, f in counted.items() if k not in (expansion, binarity)}
    # Fig. 4 draws them as their family's, Fig. 7 leaves them out
    import fvdem.analysis.plots as plots
    import fvdem.reports.mema2020.figures as mema
    drawn = {}
    monkeypatch.setattr(plots, "plot_t95", lambda folders, path, names=None, **kw: drawn.update(t95=sorted(names)))
    monkeypatch.setattr(mema, "plot_void_fraction_panels", lambda panels, path: drawn.update(
        fig7={v: sorted(r["name"] for r in pair) for v, pair in panels.items()}))
    for name in ("plot_mixing_by_velocity", "plot_mixing"):
        monkeypatch.setattr(plots, name, lambda *args, **kwargs: None)
    monkeypatch.setattr(mema, "plot_void_fractions", lambda *args, **kwargs: None)
    runs = [{"name": f"{r['family']}_{k}", "family": r["family"], "status": "finished", "t95": r["t95"],
             "point": {"gas.u_over_umf": r["gas.u_over_umf"]}, "folder": str(tmp_path / f"run{k}")}
            for k, r in enumerate(base + cut)]
    draw_figures(tmp_path, runs)
    assert drawn["t95"] == ["ar1"] * 7 + ["ar4_mp"] * 6  # 4 and 4 whole, 3 and 2 cut at t95
    assert drawn["fig7"] == {2.0: ["ar1_0", "ar1_1", "ar4_mp_2", "ar4_mp_3"],
                             2.9: ["ar1_tall_4", "ar1_tall_5", "ar4_mp_tall_6", "ar4_mp_tall_7"]}  # whole runs alone


def test_the_sharp_drop_the_shrinking_differences_mp_against_sp_and_the_bed_expansion_findings():
    from fvdem.reports.mema2020 import check_findings

    def row(family, ratio, t95, end=8.0, height=None):  # height: the bed's expansion
        return {"family": family, "status": "finished", "gas.u_over_umf": ratio, "t95": t95,
                "simulated_seconds": end, "bed_expansion": height}

    def found(rows):
        return {f["finding"].split(" (")[0]: f for f in check_findings(rows) if f.get("readings") != "second"}

    # AR-1: not mixed by 8 s at 1.7, 4.2 s at 2.0, then 3.6, 3.15, 3.1: a drop of more than 8 / 4.2 = 1.9 into
    # 2 Umf (a lower bound), 1.17 and less above it
    ar1 = [row("ar1", 1.7, None), row("ar1", 2.0, 4.2), row("ar1", 2.3, 3.6), row("ar1", 2.6, 3.15),
           row("ar1", 2.9, 3.1)]
    drop = found(ar1)["AR-1's mixing time drops sharply at 2 Umf"]
    assert drop["verdict"] == "holds" and drop["values"]["drop 1.7 -> 2 Umf"] == "> 1.9"
    assert drop["values"]["drops above 2 Umf"]["2.3"] == pytest.approx(4.2 / 3.6)
    gentle = [row("ar1", 1.7, 5.0), *ar1[1:]]  # 5.0 / 4.2 = 1.19: not sharp
    assert found(gentle)["AR-1's mixing time drops sharply at 2 Umf"]["verdict"] == "does not hold"
    later = [row("ar1", 1.7, 6.0), row("ar1", 2.0, 4.2), row("ar1", 2.3, 2.0)]  # 1.43 into 2 Umf, 2.1 after
    assert found(later)["AR-1's mixing time drops sharply at 2 Umf"]["verdict"] == "does not hold"
    short = [row("ar1", 1.7, None, end=5.0), row("ar1", 2.0, 4.2)]  # > 1.19 only: run 1.7 longer
    assert found(short)["AR-1's mixing time drops sharply at 2 Umf"]["verdict"] == "open"
    assert found(ar1[1:])["AR-1's mixing time drops sharply at 2 Umf"]["verdict"] == "open"  # nothing below 2
    # a replica still running and not yet mixed, or one not started, is left out, not taken as a bound at its
    # current time (nor as unmixed by the other findings)
    running = dict(row("ar1", 2.9, None, end=0.8), status="stopped")
    waiting = dict(row("ar1", 2.6, None, end=0.0), status="pending")
    everything = found(ar1 + [running, waiting])
    assert everything["AR-1's mixing time drops sharply at 2 Umf"]["values"]["t95"]["2.9"] == 3.1
    assert everything["terminal t95 of ar1 about 2.6 s"]["verdict"] == "does not hold"  # 3.6, 3.15, 3.1

    # AR-1 minus AR-4 MP: > 8 - 5 = 3 s at 1.7 (AR-1 unmixed), 1.2 s at 2.0, 0.3 s at 2.9: shrinks
    mp = [row("ar4_mp", 1.7, 5.0), row("ar4_mp", 2.0, 3.0), row("ar4_mp", 2.9, 2.8)]
    shrink = found(ar1 + mp)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert shrink["verdict"] == "holds" and shrink["values"]["difference at 2.9 Umf"] == pytest.approx(0.3)
    assert shrink["values"]["differences up to 2 Umf"] == {"1.7": "> 3", "2": pytest.approx(1.2)}
    wide = mp[:2] + [row("ar4_mp", 2.9, 1.0)]  # 2.1 s at 2.9 against 1.2 s at 2.0
    assert found(ar1 + wide)["the AR-1/AR-4 difference shrinks at the highest velocity"]["verdict"] == "does not hold"
    # the sizes compare beyond their noise: without replicas, 2 standard errors of a difference are 10 % of its
    # larger t95 (1.5 s at 2.9 against 1.2 s at 2.0: 0.3 s apart, within 2 hypot(0.155, 0.21) = 0.52 s)
    near_sizes = found(ar1 + mp[:2] + [row("ar4_mp", 2.9, 1.6)])[
        "the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert near_sizes["verdict"] == "open" and "2 Umf: ar1 minus ar4_mp 1.2 s in size against 1.5 s at 2.9 Umf, " \
        "within 2 standard errors of their difference (0.522 s" in near_sizes["why"]
    # the study's highest velocity for AR-4 not run yet (its 2.9 Umf run not started): the finding waits for
    # it, though both mixed at 2.3, where the difference (0.05 s) is smaller than at 2.0
    early = mp[:2] + [row("ar4_mp", 2.3, 3.55), dict(row("ar4_mp", 2.9, None, end=0.0), status="stopped")]
    waits = found(ar1 + early)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert waits["verdict"] == "open" and "waits for the study's highest velocity, 2.9 Umf" in waits["why"]
    # the size of the difference, not its sign: the campaign's first replicas (AR-1 16.9, 13.5, 4.21, 3.14 s at
    # 1.6, 1.7, 2.0, 2.9; AR-4 MP > 20, 8.51, 4.81, and 4.36 under the 1.05 m roof): at 2.9 AR-4 MP lags by 1.22
    # s, more than the 0.6 s at 2.0 (a difference that changed sign and grew), while the signed difference (-1.22)
    # was the smallest; yet 0.62 s apart lies within the noise of one run each (2 hypot(0.218, 0.24) = 0.649 s),
    # and AR-4 MP's bound at 1.6 (size above 3.1) does not pass 1.22 by its noise (2.05 s): open
    campaign = [row("ar1", 1.6, 16.9, end=20.0), row("ar1", 1.7, 13.5, end=16.0), row("ar1", 2.0, 4.21),
                row("ar1", 2.9, 3.14), row("ar4_mp", 1.6, None, end=20.0), row("ar4_mp", 1.7, 8.51, end=16.0),
                row("ar4_mp", 2.0, 4.81), row("ar4_mp", 2.9, 4.36)]
    first = found(campaign)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert first["verdict"] == "open" and first["values"]["difference at 2.9 Umf"] == pytest.approx(-1.22)
    assert "2 Umf: ar1 minus ar4_mp 0.6 s in size against 1.22 s at 2.9 Umf" in first["why"]
    assert "1.6 Umf: ar1 minus ar4_mp only bounded (< -3.1 s), not past the 1.22 s" in first["why"]
    # AR-4 MP at 2.9 lagging by 1.76 s: 1.16 s past the 0.6 s at 2.0, beyond its noise (0.687 s)
    campaign[-1] = row("ar4_mp", 2.9, 4.9)
    grew = found(campaign)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert grew["verdict"] == "does not hold" and grew["values"]["difference at 2.9 Umf"] == pytest.approx(-1.76)
    # AR-4 MP unmixed at 1.6: AR-1 minus AR-4 below 16.9 - 20, a size above 3.1
    assert grew["values"]["differences up to 2 Umf"]["1.6"] == "< -3.1"
    assert "note" not in grew
    # a run whose bed stood at the outlet (rods pinned at the roof) counts, and each finding whose numbers hold its
    # velocity names it in a note; one whose numbers do not (up to 2 Umf) is left without
    roofed = campaign[:7] + [dict(row("ar4_mp", 2.9, 4.9), bed_at_roof=1.0)]
    noted = found(roofed)
    assert noted["the AR-1/AR-4 difference shrinks at the highest velocity"]["note"] == \
        "bed at the outlet, particles pinned at the roof: ar4_mp at 2.9 Umf"
    assert noted["the AR-1/AR-4 difference shrinks at the highest velocity"]["verdict"] == "does not hold"
    assert "note" not in noted["AR-4"]
    roofed[-1]["roof_share"] = 0.0469  # the share of its particles up there at the end, where the table has it
    assert found(roofed)["the AR-1/AR-4 difference shrinks at the highest velocity"]["note"].endswith(
        "ar4_mp at 2.9 Umf (4.7 % of the particles there at the end)")
    # the same point in a taller column (family "ar4_mp_tall", the stage-1 run: 2.64 s in 2.1 m) stands for
    # ar4_mp's runs there once it has mixed: AR-1 minus AR-4 0.5 s at 2.9, told smaller than at 1.6 and 1.7,
    # within the noise of the 0.6 s at 2.0
    roofed[-1]["column_height"] = 1.05
    tall = dict(row("ar4_mp_tall", 2.9, 2.64), column_height=2.1)
    unroofed = found(roofed + [tall])["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert unroofed["verdict"] == "open" and unroofed["values"]["difference at 2.9 Umf"] == pytest.approx(0.5)
    assert unroofed["why"].startswith("2 Umf: ar1 minus ar4_mp 0.6 s in size against 0.5 s at 2.9 Umf")
    assert unroofed["note"] == ("t95 from a column without the roof: ar4_mp at 2.9 Umf from the taller column "
                                "(ar4_mp_tall); in the paper's 1.05 m column t95 4.9 s (4.7 % of the particles "
                                "pinned at its outlet at the end)")
    assert found(roofed + [tall])["terminal t95 of ar4_mp about 2.3 s"]["values"] == {"2.9": 2.64}
    assert "note" not in found(roofed + [tall])["AR-4"]  # up to 2 Umf: the paper's column's runs
    # a taller run on its way and not yet mixed is left out: the paper's column's runs stand until it has mixed
    going = dict(tall, t95=None, status="stopped", simulated_seconds=1.5)
    waits = found(roofed + [going])["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert waits["verdict"] == "does not hold" and waits["values"]["difference at 2.9 Umf"] == pytest.approx(-1.76)
    assert waits["note"] == "bed at the outlet, particles pinned at the roof: ar4_mp at 2.9 Umf (4.7 % of the " \
                            "particles there at the end)"
    # replicas shrink the noise: two of each at 2.0 and 2.9, 0.1 s apart (standard error of a difference 0.071 s,
    # 2 degrees of freedom each, 4 for the two: t 2.87), tell 0.26 s at 2.9 from 0.6 s at 2.0 (0.34 s apart, beyond
    # 2.87 hypot(0.071, 0.071) = 0.29 s); 0.36 s (0.24 apart) would not be
    replicated = campaign[:2] + campaign[4:6] + [
        row("ar1", 2.0, 4.21), row("ar1", 2.0, 4.31), row("ar1", 2.9, 3.14), row("ar1", 2.9, 3.24),
        row("ar4_mp", 2.0, 4.81), row("ar4_mp", 2.0, 4.91), row("ar4_mp", 2.9, 3.4), row("ar4_mp", 2.9, 3.5)]
    closer = found(replicated)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert closer["verdict"] == "holds" and closer["values"]["difference at 2.9 Umf"] == pytest.approx(-0.26)
    nearer = replicated[:-2] + [row("ar4_mp", 2.9, 3.5), row("ar4_mp", 2.9, 3.6)]
    assert found(nearer)["the AR-1/AR-4 difference shrinks at the highest velocity"]["verdict"] == "open"
    # sizes alike: AR-1 minus AR-4 MP 0.6 s at 2.0 against 0.5 s at 2.9 (each with a replicas' standard error of
    # 0.0707 s), 0.1 s apart, with t times its noise (2.87 x 0.1 s) 0.387 s, within 10 % of the larger t95 (0.485
    # s): it did not shrink from 2.0 Umf, though it did from 1.6 and 1.7
    same = campaign[:2] + campaign[4:6] + [
        row("ar1", 2.0, 4.2), row("ar1", 2.0, 4.3), row("ar1", 2.9, 3.1), row("ar1", 2.9, 3.2),
        row("ar4_mp", 2.0, 4.8), row("ar4_mp", 2.0, 4.9), row("ar4_mp", 2.9, 2.6), row("ar4_mp", 2.9, 2.7)]
    kept = found(same)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert kept["verdict"] == "does not hold"
    assert kept["values"]["differences up to 2 Umf"]["2"] == (
        "-0.6, alike in size: 0.6 s against 0.5 s at 2.9 Umf, with 2.87 standard errors (0.287 s) within 10 % of the "
        "larger t95 (0.485 s)")
    # within the noise with replicas: AR-1 minus AR-4 MP 0.55 s at 2.0 against 0.45 s at 2.9, the per-run
    # variances summing to 0.165 s^2: likeness (0.1 s + t errors within 10 % of 4.955 s) needs t times the error
    # of a size's difference below 0.396 s; the noisiest series take more and the quiet ones fewer: 7, 5, 3 and 4
    # replicas in all (variances 0.076, 0.042, 0.013 and 0.034 over them: 0.0321 at 14.6 degrees of freedom, t
    # 2.19: 0.154 <= 0.396^2 = 0.156; with 2 for t it was 6, 4, 2 and 4)
    spread = campaign[:1] + campaign[4:6] + [
        row("ar1", 2.0, 4.21), row("ar1", 2.0, 4.6), row("ar1", 2.9, 3.14), row("ar1", 2.9, 3.3),
        row("ar4_mp", 2.0, 4.81), row("ar4_mp", 2.0, 5.1), row("ar4_mp", 2.9, 2.64), row("ar4_mp", 2.9, 2.9)]
    plan = found(spread)["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert plan["verdict"] == "open" and "2 Umf: ar1 minus ar4_mp 0.55 s in size against 0.45 s at 2.9 Umf, within " \
        "3.27 standard errors of their difference (0.938 s; about 7 of ar1 at 2 Umf, 5 of ar4_mp at 2 Umf, 3 of ar1 " \
        "at 2.9 Umf and 4 of ar4_mp at 2.9 Umf in all would tell (now 2, 2, 2 and 2), if the means and spread stay: " \
        "[[points]])" in plan["why"]
    # a bound that does not reach the size at the top by its noise tells nothing there: open (AR-1 at 19.5 against
    # AR-4 MP unmixed at 20: a size above 0.5 only, against 0.36 at 2.9)
    near = [row("ar1", 1.6, 19.5, end=20.0)] + replicated[1:]
    assert "1.6 Umf: ar1 minus ar4_mp only bounded (< -0.5 s)" in found(near)[
        "the AR-1/AR-4 difference shrinks at the highest velocity"]["why"]
    unknown = found([near[0], campaign[1], row("ar1", 2.0, 4.21), row("ar1", 2.9, 3.14)] + campaign[4:6] + [
        row("ar4_mp", 2.0, 2.21), row("ar4_mp", 2.9, 4.14)])["the AR-1/AR-4 difference shrinks at the highest velocity"]
    assert unknown["verdict"] == "open" and "1.6 Umf: ar1 minus ar4_mp only bounded (< -0.5 s)" in unknown["why"]
    # lift and torque: drag only minus full 1.0 s at 1.7 and 2.0, 0.1 s at 2.9
    drag = [row("ar4_mp_drag", 1.7, 6.0), row("ar4_mp_drag", 2.0, 4.0), row("ar4_mp_drag", 2.9, 2.9)]
    lift = found(mp + drag)["the effect of lift and torque shrinks at the highest velocity"]
    assert lift["verdict"] == "holds"
    unmixed_top = drag[:2] + [row("ar4_mp_drag", 2.9, None)]
    assert found(mp + unmixed_top)["the effect of lift and torque shrinks at the highest velocity"]["verdict"] == "open"

    # MP against SP above 2 Umf: MP faster by more than 10 % at 2.9 holds; within 10 % needs replicas
    sp = [row("ar4_sp", 2.0, 2.0), row("ar4_sp", 2.9, 3.3)]
    widen = found(mp + sp)["MP closures widen the AR-1/AR-4 difference above 2 Umf"]
    assert widen["verdict"] == "holds" and list(widen["values"]) == ["2.9"]  # 2.0 Umf is not above 2
    assert found(mp + [row("ar4_sp", 2.9, 2.9)])["MP closures widen the AR-1/AR-4 difference above 2 Umf"]["verdict"] \
        == "open"
    # with replicas, the difference of the means against t times its standard error decides (four a side: df
    # 4.4-6, t 2.5-2.8): 2.85 against 2.8 (0.05 within 0.178, and with it at most 0.228 apart, within 10 % of 2.85:
    # alike, so MP is not faster), 2.85 against 2.8 from 3.0 and 2.6 (two a side, df 1.2: within 2.2, not alike:
    # open), 2.825 against 2.975 (0.15 beyond t x 0.018: holds, though within 10 %), 2.825 against 2.65 (does not
    # hold); two a side would tell none of them (df 1-2: t 4.5-7)
    def at_29(family, times):
        return [row(family, 2.9, t) for t in times]
    replicas = mp + at_29("ar4_mp", (2.9, 2.8, 2.9)) + at_29("ar4_sp", (2.9, 2.7) * 2)  # 2.85 against 2.8
    alike = found(replicas)["MP closures widen the AR-1/AR-4 difference above 2 Umf"]
    assert alike["verdict"] == "does not hold" and alike["values"]["2.9"]["alike"] == (
        "alike: the means 2.85 and 2.8 differ by 0.05, with 2.76 standard errors at most 0.228, within 10 % of the "
        "larger (0.285)")
    assert found(mp + at_29("ar4_mp", (2.9,)) + at_29("ar4_sp", (2.9, 2.7)))[
        "MP closures widen the AR-1/AR-4 difference above 2 Umf"]["verdict"] == "open"
    replicas = mp + at_29("ar4_mp", (2.9,)) + at_29("ar4_sp", (3.0, 2.6))
    overlapping = found(replicas)["MP closures widen the AR-1/AR-4 difference above 2 Umf"]
    assert overlapping["verdict"] == "open"
    assert "(ar4_mp against ar4_sp, t95 [s]: means 2.85 (2.8, 2.9) against 2.8 (3, 2.6), within 10.7 standard errors " \
        "(2.2)" in overlapping["why"]
    apart = mp + at_29("ar4_mp", (2.85, 2.8, 2.85)) + at_29("ar4_sp", (2.95, 3.0) * 2)
    assert found(apart)["MP closures widen the AR-1/AR-4 difference above 2 Umf"]["verdict"] == "holds"
    behind = mp + at_29("ar4_mp", (2.85, 2.8, 2.85)) + at_29("ar4_sp", (2.6, 2.7) * 2)
    assert found(behind)["MP closures widen the AR-1/AR-4 difference above 2 Umf"]["verdict"] == "does not hold"

    # bed expansion: AR-4 MP higher at both velocities holds; a run stopped short is left out
    beds = [row("ar1", 1.6, None, height=0.34), row("ar4_mp", 1.6, None, height=0.40),
            row("ar1", 2.9, 3.1, height=0.61), row("ar4_mp", 2.9, 2.8, height=0.70),
            dict(row("ar4_mp", 2.3, None, end=1.0, height=0.2), status="stopped"), row("ar1", 2.3, 3.6, height=0.5)]
    grow = found(beds)["AR-4 beds expand more than AR-1 at the same U/Umf"]
    assert grow["verdict"] == "holds" and set(grow["values"]) == {"1.6", "2.9"}
    beds[1] = row("ar4_mp", 1.6, None, height=0.30)
    assert found(beds)["AR-4 beds expand more than AR-1 at the same U/Umf"]["verdict"] == "does not hold"
    beds[1] = row("ar4_mp", 1.6, None, height=0.35)  # within 10 % of 0.34 without replicas
    assert "too noisy" in found(beds)["AR-4 beds expand more than AR-1 at the same U/Umf"]["why"]
    # a replica that erupted (the campaign's AR-4 MP at 1.6: 1.63 and 2.57 against AR-1's 1.73 and 1.75): the
    # mean is above, by 0.36, within t times the standard error of the difference (13.9 x 0.47 at 1.0 degrees of
    # freedom): open; four more replicas near 2.3 bring the error down and decide
    erupted = [row("ar1", 1.6, None, height=1.73), row("ar1", 1.6, None, height=1.75),
               row("ar4_mp", 1.6, None, height=1.63), row("ar4_mp", 1.6, None, height=2.57)]
    spread = found(erupted)["AR-4 beds expand more than AR-1 at the same U/Umf"]
    assert spread["verdict"] == "open"
    assert "(AR-4 MP against AR-1: means 2.1 (1.63, 2.57) against 1.74 (1.73, 1.75), within 13.9 standard errors " \
        "(6.55)" in spread["why"]
    # how many would tell, if the means and the spread stay: t times the standard error sqrt(0.4418 / n_4 + 0.0002
    # / n_1) below 0.36 (the order; likeness would need 0.21 - 0.36 < 0): AR-1's spread is a 2,000th of AR-4 MP's,
    # so AR-4 MP gets them, 0.4418 / 17 + 0.0001 = 0.0261 <= (0.36 / 2.17)^2 = 0.0275 (t at df 16; with 16: 0.0277
    # against 0.0273; with 2 for t it was 14)
    assert "about 17 of ar4_mp and 2 of ar1 in all would tell (now 2 and 2), if the means and spread stay: " \
        "[[points]] of ar4_mp_expansion and ar1_expansion" in spread["why"]
    assert "core-hours" not in spread["why"]  # no run's cost known
    # the replicas cut short, with what they cost (AR-4 MP's 2,200 CPU s, AR-1's 1,000): the core-hours of the
    # replicas each lacks at those costs, only theirs (the full runs' cost is not what a replica cut short takes)
    cut = [dict(row("ar4_mp_expansion", 1.6, None, end=5.0, height=2.0), cpu_seconds=2200.0),
           dict(row("ar1_expansion", 1.6, None, end=5.0, height=1.74), cpu_seconds=1000.0)]
    costed = found([dict(r, cpu_seconds=50000.0) for r in erupted] + cut)[
        "AR-4 beds expand more than AR-1 at the same U/Umf"]
    more = costed["why"].split("about ")[1].split(" in all")[0]  # "<n> of ar4_mp and <m> of ar1"
    n, m = (int(part.split(" of ")[0]) for part in more.split(" and "))
    assert "(now 3 and 3)" in costed["why"] and n > m  # AR-4 MP noisier and cheaper per variance cut
    assert f"; about {((n - 3) * 2200.0 + (m - 3) * 1000.0) / 3600.0:.3g} core-hours at their runs' cost so far" \
        in costed["why"]
    # alike: 1.75 (1.72, 1.78, twice) against 1.74 (1.73, 1.75, twice), within 10 % with t (3.0 at df 3.7) times the
    # error: not more (two a side, df 1.2, t 9: open)
    even = erupted[:2] * 2 + [row("ar4_mp", 1.6, None, height=h) for h in (1.72, 1.78) * 2]
    alike = found(even)["AR-4 beds expand more than AR-1 at the same U/Umf"]
    assert alike["verdict"] == "does not hold" and alike["values"]["1.6"]["alike"].startswith("alike: the means 1.75")
    more = erupted + [row("ar4_mp", 1.6, None, height=h) for h in (2.3, 2.4, 2.2, 2.35)]
    assert found(more)["AR-4 beds expand more than AR-1 at the same U/Umf"]["verdict"] == "holds"
    # the same four as runs of "ar4_mp_expansion" (ar4_mp's case cut short after the window, 5 s, from beds of
    # their own) count as AR-4 MP's for the expansion alone: the same verdict and values, and not one of the t95
    # findings sees them (unmixed at 5 s, they would bound AR-4 MP's t95 at 1.6 by 5 s)
    short = erupted + [row("ar4_mp_expansion", 1.6, None, end=5.0, height=h) for h in (2.3, 2.4, 2.2, 2.35)]
    pooled, alone = found(short), found(erupted)
    assert pooled["AR-4 beds expand more than AR-1 at the same U/Umf"] == \
        found(more)["AR-4 beds expand more than AR-1 at the same U/Umf"]
    assert {k: f for k, f in pooled.items() if not k.startswith("AR-4 beds")} == \
        {k: f for k, f in alone.items() if not k.startswith("AR-4 beds")}
    # one velocity told against the claim decides, whatever another leaves within the noise
    lower = erupted + [row("ar1", 2.0, 3.0, height=2.5), row("ar4_mp", 2.0, 3.0, height=2.0)]
    assert found(lower)["AR-4 beds expand more than AR-1 at the same U/Umf"]["verdict"] == "does not hold"
    # a bed whose top stood at the outlet (rods pinned at the roof: the campaign's AR-4 MP at 2.9 Umf, 5.04 x
    # its settled height, the column's) has no height of its own: left out, its velocity open
    more_at = more + [row("ar1", 2.9, 3.1, height=3.09), dict(row("ar4_mp", 2.9, 4.4, height=5.04), bed_at_roof=1.0)]
    roofed = found(more_at)["AR-4 beds expand more than AR-1 at the same U/Umf"]
    assert roofed["verdict"] == "open" and "2.9" not in roofed["values"]
    assert "2.9 Umf: ar4_mp's bed top stood at the outlet (particles pinned at the roof)" in roofed["why"]
    more_at[-1]["bed_at_roof"] = 0.2  # at the outlet only now and then: its height counts
    assert found(more_at)["AR-4 beds expand more than AR-1 at the same U/Umf"]["verdict"] == "holds"
    assert "note" not in roofed  # no run has the dense bed's height
    # the dense bed's expansion (90 % of the centres) goes beside the verdict as a note, not into it: AR-4 MP's
    # spouting beds at 1.6 (the campaign's: tops 1.63 and 2.57, dense beds 1.2 and 1.42 against AR-1's 1.5 and
    # 1.66), the roofed run's left out as in the rule, a velocity where one family lacks it left out
    dense = [dict(r, dense_bed_expansion=d) for r, d in zip(erupted, (1.5, 1.66, 1.2, 1.42))]
    dense += [dict(row("ar1", 2.9, 3.1, height=3.09), dense_bed_expansion=2.4),
              dict(row("ar4_mp", 2.9, 4.4, height=5.04), bed_at_roof=1.0, dense_bed_expansion=4.9),
              dict(row("ar1", 2.0, 3.0, height=2.1), dense_bed_expansion=1.98), row("ar4_mp", 2.0, 3.0, height=2.7)]
    beside = found(dense)["AR-4 beds expand more than AR-1 at the same U/Umf"]
    assert beside["note"].endswith("1.6: AR-4 MP 1.31 (1.2, 1.42) against AR-1 1.58 (1.5, 1.66)")
    assert beside["note"].startswith("the dense bed, the height under 90 % of the particle centres")
    assert {k: v for k, v in beside.items() if k != "note"} == \
        found([{k: v for k, v in r.items() if k != "dense_bed_expansion"} for r in dense])[
            "AR-4 beds expand more than AR-1 at the same U/Umf"]


def _square_or_fail(item, threads):
    if item < 0:
        raise ValueError(f"negative item {item}")
    return {"square": item * item, "threads": threads}


def test_the_sweep_engine_runs_tasks_in_order_and_reports_a_failure_without_stopping_the_others():
    from fvdem.study import map_tasks
    lines = []
    outcomes = map_tasks(_square_or_fail, [3, -1, 4], ["a", "b", "c"], threads=1, workers=1, log=lines.append)
    assert [o["name"] for o in outcomes] == ["a", "b", "c"]
    assert [o["status"] for o in outcomes] == ["finished", "failed", "finished"]
    assert outcomes[0]["value"] == {"square": 9, "threads": 1} and outcomes[2]["value"]["square"] == 16
    assert outcomes[1]["value"] is None and outcomes[1]["error"] == "ValueError: negative item -1"
    assert lines[0] == "3 tasks on LocalCluster(1 workers x 1 numba threads)"
    assert len(lines) == 4 and all("ETA" in line for line in lines[1:])
    with pytest.raises(ValueError, match="distinct"):
        map_tasks(_square_or_fail, [1, 2], ["x", "x"], workers=1)


def test_the_tools_sweeps_run_module_level_functions_the_engine_can_ship():
    """validate_hindered_settling's fractions, speed_accuracy's variants and validate_umf's ramps are
    tasks of fvdem.study.map_tasks: their task functions are module-level (workers import them)."""
    import importlib
    import pickle
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        for module, name in (("validate_hindered_settling", "run_one"), ("speed_accuracy", "measure_task"),
                             ("validate_umf", "ramp")):
            tool = importlib.import_module(module)
            function = getattr(tool, name)
            assert pickle.loads(pickle.dumps(function)) is function
            assert "map_tasks" in Path(tool.__file__).read_text()
            assert "ProcessPoolExecutor" not in Path(tool.__file__).read_text()
    finally:
        sys.path.remove(str(ROOT / "tools"))


def test_only_selects_runs_and_their_beds_and_refuses_a_name_the_study_lacks(tmp_path):
    study = load_study(SMOKE, tmp_path)
    one = select_runs(study, ["ar1_u_over_umf2.9"])
    assert [r.name for r in one.runs] == ["ar1_u_over_umf2.9"] and [b.name for b in one.beds] == ["small"]
    assert select_runs(study, None) is study
    with pytest.raises(CaseError) as err:
        select_runs(study, ["ar1_u_over_umf3"])
    assert "ar1_u_over_umf3" in str(err.value) and "ar1_u_over_umf2.9" in str(err.value)
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(SMOKE), "--out", str(tmp_path / "s"),
                             "--only", "nope"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "Traceback" not in result.stderr and "nope" in result.stderr


def test_a_familys_own_duration_and_a_wrong_one(tmp_path):
    text = SMOKE.read_text().replace('bed = "small"', 'bed = "small"\nduration = 0.05', 1)
    path = tmp_path / "study.toml"
    path.write_text(text.replace('"../cases/', f'"{ROOT / "cases"}/'))
    runs = load_study(path, tmp_path / "out").runs
    assert all(r.duration == 0.05 and r.overrides["time.end"] == 0.05 for r in runs)
    path.write_text(text.replace('"../cases/', f'"{ROOT / "cases"}/').replace("duration = 0.05", 'duration = "long"'))
    with pytest.raises(CaseError) as err:
        load_study(path, tmp_path / "out")
    assert "families.ar1.duration" in str(err.value) and "'long'" in str(err.value)


def test_durations_tables_give_the_runs_they_match_their_own_duration_and_a_wrong_one_is_refused(tmp_path):
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
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
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
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


def test_the_plan_of_the_open_findings_adds_the_replicas_they_ask_less_those_counted_and_on_the_way(tmp_path):
    """``plan_points`` (the report's plan.toml): AR-4 MP at 2 Umf 4.3 s (4.0, 4.6) against AR-1's 4.35 (4.0, 4.7)
    lies within the spread; the finding's plan (``replicas_to_tell``, kept in findings.json as data) asks 12 of
    AR-4 MP and 14 of AR-1 in all. The study has two of AR-1 and three of AR-4 MP there (the third not started):
    the tables raise them to 2 + 12 = 14 and 3 + (12 - 2 - 1) = 12, and appended to the study file they give
    exactly those runs, the earlier ones under their names."""
    from fvdem.reports.mema2020.plan import plan_points
    from fvdem.reports.mema2020.rules import check_findings
    from fvdem.reports.mema2020.spread import replicas_to_tell

    def row(family, t95, replica, status="finished"):
        return {"family": family, "status": status, "gas.u_over_umf": 2.0, "t95": t95, "replica": replica,
                "simulated_seconds": 8.0 if t95 else None}
    rows = [row("ar1", 4.0, 1), row("ar1", 4.7, 2), row("ar4_mp", 4.0, 1), row("ar4_mp", 4.6, 2),
            row("ar4_mp", None, 3, status="pending")]
    finding = check_findings(rows)[0]
    var = [0.18, 0.245]  # the sample variances of AR-4 MP's and AR-1's t95
    plan = replicas_to_tell([(2, var[0], None), (2, var[1], None)], 4.3 - 4.35, 0.435)
    assert plan == [12, 14] and finding["verdict"] == "open"
    assert finding["plans"] == [{"kind": "t95", "core_hours": None, "runs": [
        {"family": "ar4_mp", "u_over_umf": 2.0, "replicas": 12, "now": 2, "cpu_seconds": None},
        {"family": "ar1", "u_over_umf": 2.0, "replicas": 14, "now": 2, "cpu_seconds": None}]}]
    text = plan_points(rows, check_findings(rows), "s")
    assert "12 of ar4_mp at 2 Umf in all (now 2, 1 on the way)" in text
    mp = (f'[families.ar4_mp]\ncase = "{ROOT / "cases" / "demo.toml"}"\nbed = "small"\n'
          'set = {"particles.count" = 150}\n\n')
    study = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/').replace("[axes]", mp + "[axes]")
    study = (study.replace("replicas = 1", "replicas = 2")
             + '\n[[points]]\nfamily = "ar4_mp"\n"gas.u_over_umf" = 2.0\nreplicas = 3\n')
    path = tmp_path / "study.toml"
    path.write_text(study)
    before = {r.name for r in load_study(path, tmp_path / "out").runs}
    path.write_text(study + text)
    after = load_study(path, tmp_path / "out").runs
    at_2 = {f: sum(r.family == f and r.point["gas.u_over_umf"] == 2.0 for r in after) for f in ("ar1", "ar4_mp")}
    assert at_2 == {"ar1": 14, "ar4_mp": 12} and before <= {r.name for r in after}
    # decided (single runs 25 % apart), a finding plans nothing
    assert "plans" not in check_findings([row("ar1", 4.0, 1), row("ar4_mp", 3.0, 1)])[0]


def test_a_plans_replicas_are_of_the_cheapest_family_that_counts_in_the_column_the_study_runs():
    """A t95 finding's replicas of AR-1 at 2 Umf are of ar1_t95 where the study runs it there (they end when they
    mix), at 2.9 of ar1_tall_t95 (the taller column stands for the paper's there), at 1.6 of ar1 itself; the bed
    expansion's of ar1_expansion; a run cut short after the expansion window counts for no t95 finding, nor one
    that ends when it mixes for the expansion; and the runs on their way are counted in the column that
    stands."""
    from fvdem.reports.mema2020.plan import EXPANSION_KIND, T95, _counted_as, _on_the_way, _plan_family
    present = {("ar1", 2.0): 2, ("ar1_t95", 2.0): 8, ("ar1", 2.9): 1, ("ar1_tall", 2.9): 3,
               ("ar1_tall_t95", 2.9): 6, ("ar1", 1.6): 2, ("ar1_expansion", 1.7): 11, ("ar1", 1.7): 2}
    assert [_plan_family("ar1", v, T95, present) for v in (2.0, 2.9, 1.6, 1.7)] == [
        "ar1_t95", "ar1_tall_t95", "ar1", "ar1"]
    assert _plan_family("ar1", 1.7, EXPANSION_KIND, present) == "ar1_expansion"
    assert _plan_family("ar4_mp", 2.0, T95, present) is None
    def families(names, kind):  # the family each run counts as in a finding of ``kind`` (None: not counted)
        counted = {r["gas.u_over_umf"]: r["family"] for r in _counted_as(
            [{"family": f, "gas.u_over_umf": k} for k, f in enumerate(names)], kind)}
        return [counted.get(k) if counted.get(k) == "ar1" else None for k in range(len(names))]
    assert families(("ar1_tall_t95", "ar1_expansion", "ar1_tall", "ar1_t95"), T95) == ["ar1", None, "ar1", "ar1"]
    assert families(("ar1_t95", "ar1_expansion", "ar1"), EXPANSION_KIND) == [None, "ar1", "ar1"]
    rows = [{"family": f, "gas.u_over_umf": 2.9, "status": status, "t95": t95} for f, status, t95 in (
        ("ar1", "pending", None), ("ar1_tall", "running", 2.6), ("ar1_tall", "running", None),
        ("ar1_tall_t95", "pending", None), ("ar1_tall_t95", "finished", 2.5))]
    # the paper's column's run set aside, the mixed one counted
    assert _on_the_way(_counted_as(rows, T95), "ar1", 2.9, T95) == 2


def test_a_lower_priority_tranche_starts_only_once_the_runs_queued_before_it_have_started(tmp_path):
    """``priority`` (a family's, or a [[points]] table's): a run of a lower tier is handed on only once every
    run of the tiers above has been, whatever its replica and even where it fits a deadline and they do not;
    a run in progress counts in the top tier. Without priorities the order is the replicas' (a new family's
    first replica before an earlier family's second). A wrong priority is refused by key."""
    from fvdem.study.runner import _Queue
    from fvdem.study.status import format_status, study_status
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
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
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
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


def _small_run(tmp_path, end):
    bed_case = ROOT / "cases" / "demo.toml"
    out = tmp_path / "study"
    folder = out / "runs" / "demo"
    return out, RunSpec("demo", "demo", str(bed_case), {"time.end": end, "output.vtk": False,
                                                       "output.checkpoint_interval": 0.002,
                                                       "output.timeseries_interval": 0.001,
                                                       "particles.count": 150}, str(folder), None, {}, end)


def test_the_stop_file_checkpoints_a_running_run_and_keeps_queued_runs_from_starting(tmp_path):
    """A run polls its study's STOP file between chunks: it stops with a checkpoint, comes back
    'stopped', does not count as finished, and the next invocation resumes it to the end."""
    out, run = _small_run(tmp_path, 0.02)
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
    study = load_study(SMOKE, out)
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
    from fvdem.study.status import format_status, study_status
    out = tmp_path / "study"
    study = load_study(SMOKE, out)
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
    report(out)  # the table lists it; the findings neither count nor draw it
    rows = {r["name"]: r["status"] for r in json.loads((out / "table.json").read_text())}
    assert rows == {first.name: "pending", second.name: "not planned"}
    page = (out / "findings.md").read_text()
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


def test_runs_with_more_dem_steps_left_start_first(tmp_path):
    study = load_study(ROOT / "studies" / "mema2020_subset.toml", tmp_path)
    priority = {r.name: _priority(r) for r in study.runs}
    # 4.5 s at the paper's 1e-5 s DEM step is more steps than 6 s at the defaults' 5e-5 s
    assert priority["ar1_paper_u_over_umf2.9"] == pytest.approx(4.5 / 1e-5, rel=1e-6)
    assert priority["ar1_u_over_umf2"] == pytest.approx(6.0 / 5e-5, rel=1e-6)


@pytest.mark.slow
def test_ctrl_c_stops_the_study_with_its_runs_checkpointed_and_the_same_command_continues(tmp_path):
    """SIGINT to `fvdem study` while a run is past its first checkpoint: the run checkpoints at its
    next chunk (not at its last scheduled checkpoint), the study exits 130 naming the stopped run,
    and the same command resumes it to the end; `--stop` asks the same from another process."""
    import signal
    import time
    study = _one_run_study(tmp_path, "stop", checkpoint_interval=0.1)
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


def test_void_fraction_binarity_is_one_for_packed_or_empty_cells_and_about_a_third_for_a_uniform_spread():
    import numpy as np

    from fvdem.analysis.mixing import void_fraction_binarity
    rng = np.random.default_rng(1)
    binary = np.where(rng.random(20_000) < 0.3, 1.0, 0.4)
    assert void_fraction_binarity(binary) == pytest.approx(1.0)
    spread = rng.uniform(0.4, 1.0, 200_000)  # var 0.6^2 / 12 over (mean - a)(1 - mean), a its 2nd percentile
    assert void_fraction_binarity(spread) == pytest.approx(0.03 / ((0.7 - 0.412) * 0.3), rel=0.01)
    assert np.isnan(void_fraction_binarity(np.full(10, 0.5))) and np.isnan(void_fraction_binarity([0.5]))


def test_the_terminal_rules_wait_for_every_velocity_from_2_3_umf_the_study_plans():
    """The terminal t95 and "little change above 2.3 Umf" are of every velocity from 2.3 Umf on: while one the
    study plans has no result (not started, or on its way unmixed), both wait for it; a run that ended unmixed
    is a result (the rules then say it is too short)."""
    from fvdem.reports.mema2020 import check_findings

    def row(ratio, t95, status="finished"):
        return {"family": "ar4_mp", "status": status, "gas.u_over_umf": ratio, "t95": t95}

    rows = [row(2.3, 3.79), row(2.6, 3.01), row(2.9, None, "pending")]
    found = {f["finding"]: f for f in check_findings(rows)}
    for claim in ("terminal t95 of ar4_mp about 2.3 s (paper)", "ar4_mp: little change of t95 above about 2.3 Umf"):
        assert found[claim] == {"finding": claim, "verdict": "open",
                                "why": "waits for 2.9 Umf (mixed so far at 2.3, 2.6)"}
    rows[2] = row(2.9, 2.9)
    found = {f["finding"]: f for f in check_findings(rows)}
    terminal = found["terminal t95 of ar4_mp about 2.3 s (paper)"]
    assert terminal["verdict"] == "does not hold" and terminal["values"] == {"2.3": 3.79, "2.6": 3.01, "2.9": 2.9}
    little = found["ar4_mp: little change of t95 above about 2.3 Umf"]
    assert little["verdict"] == "does not hold"  # (3.79 - 2.9) / 3.79: 23 %
    rows[2] = row(2.9, None, "running")  # on its way, not mixed yet: no result, still waited for
    assert {f["finding"]: f for f in check_findings(rows)}[
        "ar4_mp: little change of t95 above about 2.3 Umf"]["why"].startswith("waits for 2.9 Umf")


def test_the_void_fraction_and_paper_settings_findings_and_little_change_above_2_3():
    from fvdem.reports.mema2020 import check_findings

    def row(family, ratio, t95, binarity=None, drop=1.0):
        return {"family": family, "status": "finished", "gas.u_over_umf": ratio, "t95": t95,
                "void_fraction_binarity": binarity, "pressure_drop_over_weight": drop}

    rows = [row("ar1", 2.0, 3.0, 0.62), row("ar4_mp", 2.0, 2.5, 0.41), row("ar1", 2.9, 3.4, 0.70),
            row("ar4_mp", 2.9, 2.4, 0.45), row("ar1_paper", 2.9, 3.1)]
    found = {f["finding"]: f for f in check_findings(rows)}
    binary = found["AR-1 void fractions more binary than AR-4 (Fig. 7)"]
    assert binary["verdict"] == "holds" and binary["values"]["2.9"] == {"ar1": 0.70, "ar4_mp": 0.45}
    paper = found["fvdem's defaults do not change the mixing (AR-1 at the paper's own settings)"]
    assert paper["verdict"] == "holds" and paper["gaps"]["2.9"] == pytest.approx(0.3 / 3.1)  # under 15 %
    assert found["terminal t95 of ar1 about 2.6 s (paper)"]["verdict"] == "does not hold"  # 3.4 s: +31 %
    assert found["terminal t95 of ar4_mp about 2.3 s (paper)"]["verdict"] == "holds"  # 2.4 s
    assert found["ar1: little change of t95 above about 2.3 Umf"]["verdict"] == "open"  # one velocity only
    rows[-1] = row("ar1_paper", 2.9, None)
    rows[3] = row("ar4_mp", 2.9, 2.4, 0.68)  # within 10 % of AR-1's 0.70 without replicas
    found = {f["finding"]: f for f in check_findings(rows)}
    assert found["fvdem's defaults do not change the mixing (AR-1 at the paper's own settings)"]["verdict"] == "open"
    assert "too noisy" in found["AR-1 void fractions more binary than AR-4 (Fig. 7)"]["why"]
    # replicas within their spread (AR-1 0.70 and 0.60 against AR-4 MP 0.65; AR-4's one run takes AR-1's variance)
    spread = rows[:3] + [row("ar1", 2.9, 3.3, 0.60), row("ar4_mp", 2.9, 2.4, 0.65)]
    binary = {f["finding"]: f for f in check_findings(spread)}["AR-1 void fractions more binary than AR-4 (Fig. 7)"]
    assert binary["verdict"] == "open" and "means 0.65 (0.7, 0.6) against 0.65 (0.65)" in binary["why"]
    # ... but a velocity where AR-4 MP is told the more binary decides (the campaign: 0.40 against 0.58 at 1.6
    # Umf, while 2.3 Umf lay within 10 %)
    against = spread + [row("ar1", 1.6, None, 0.40), row("ar4_mp", 1.6, None, 0.58)]
    binary = {f["finding"]: f for f in check_findings(against)}["AR-1 void fractions more binary than AR-4 (Fig. 7)"]
    assert binary["verdict"] == "does not hold" and binary["values"]["1.6"] == {"ar1": 0.40, "ar4_mp": 0.58}
    # fvdem's own check only where the study runs the paper's settings
    assert not any("fvdem's defaults" in f["finding"] for f in check_findings(rows[:-1]))


@pytest.mark.slow
def test_the_progress_view_polls_while_runs_take_longer_than_its_interval(tmp_path):
    """Runs longer than the poll interval: the study keeps waiting and updating its view (Dask's wait
    raises when nothing finished within its timeout; that once ended the study with its runs cancelled)."""
    from fvdem.study import run_study
    lines = []
    result = run_study(load_study(SMOKE, tmp_path / "study"), tmp_path / "study", workers=1, log=lines.append,
                       poll=0.05)
    assert [r["status"] for r in result["runs"]] == ["finished", "finished"]
    assert sum(line.startswith(("[1/2]", "[2/2]")) for line in lines) == 2  # one line per finished run


def test_a_slurm_cluster_table_submits_one_job_per_worker_with_the_runs_threads_booked(tmp_path, monkeypatch):
    """The [cluster] path without a cluster: fake sbatch/squeue/scancel on PATH record what dask-jobqueue
    submits. Each job books the run's numba threads as CPUs (job_cpu) and runs one Dask worker with one
    task slot; the table's options reach the job script; a wrong option or a missing memory is refused
    by key."""
    pytest.importorskip("dask_jobqueue")
    import time
    from fvdem.study import close_client, make_client
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    jobs = tmp_path / "submitted"
    jobs.mkdir()
    # one file per submission: dask-jobqueue submits the workers' jobs concurrently, so a shared log
    # interleaves their scripts
    (bin_dir / "sbatch").write_text(f'#!/bin/sh\ncat "$@" > {jobs}/job.$$.tmp && mv {jobs}/job.$$.tmp {jobs}/job.$$\n'
                                    'echo "Submitted batch job $$"\n')
    (bin_dir / "scancel").write_text(f'#!/bin/sh\necho "scancel $@" >> {tmp_path / "cancelled"}\n')
    (bin_dir / "squeue").write_text("#!/bin/sh\nexit 0\n")
    for tool in bin_dir.iterdir():
        tool.chmod(0o755)
    monkeypatch.setenv("PATH", f"{bin_dir}:{os.environ['PATH']}")
    client, description = make_client({"kind": "slurm", "workers": 2, "memory": "4GB", "walltime": "02:00:00",
                                        "queue": "compute"}, None, None, threads=4)
    try:
        time.sleep(3)  # adaptive: no job while nothing waits
        assert description == "SLURMCluster(up to 2 jobs)" and not list(jobs.glob("job.*[0-9]"))
        waiting = [client.submit(time.sleep, 1, pure=False) for _ in range(3)]  # noqa: F841 (they wait)
        deadline = time.time() + 60
        while len(list(jobs.glob("job.*[0-9]"))) < 2 and time.time() < deadline:
            time.sleep(0.2)
        scripts = [path.read_text() for path in sorted(jobs.glob("job.*[0-9]"))]
        assert len(scripts) == 2  # up to `workers` jobs, however many runs wait
        for script in scripts:
            assert "#SBATCH --cpus-per-task=4" in script and "#SBATCH -p compute" in script
            assert "#SBATCH -t 02:00:00" in script and "--nthreads 1" in script
            assert "distributed.cli.dask_worker" in script or "dask worker" in script or "dask-worker" in script
            # the job exports its end and the margin; its worker retires halfway through the margin
            assert "export FVDEM_JOB_END=$(( $(date +%s) + 7200 ))" in script and "export FVDEM_STOP_MARGIN=300" in script
            assert "--lifetime 7050s" in script
            # Dask's monitoring quieted on the node's worker (QUIET_DASK)
            assert "export DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED=False" in script
            assert "export DASK_DISTRIBUTED__ADMIN__TICK__INTERVAL=1s" in script
    finally:
        close_client(client)
    with pytest.raises(CaseError) as err:
        make_client({"kind": "slurm", "workers": 1}, None, None, threads=1)
    assert "cluster.memory" in str(err.value)
    with pytest.raises(CaseError) as err:
        make_client({"kind": "slurm", "memory": "1GB", "partitionz": "x"}, None, None, threads=1)
    assert "partitionz" in str(err.value)


def test_replicas_start_from_their_own_settled_beds_differ_and_a_resumed_replica_is_itself(tmp_path):
    """Replica k >= 2 of a run that starts from a bed starts from its own bed, settled with insertion seed
    (the bed's + k - 1): the replicas differ from the first step (from one bed they would be bit-for-bit
    copies), and a replica stopped mid-run and resumed ends bit-for-bit where it ends uninterrupted."""
    import numpy as np

    from fvdem.study import prepare_bed
    text = SMOKE.read_text().replace("replicas = 1", "replicas = 2").replace('"../cases/', f'"{ROOT / "cases"}/')
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
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
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
    _fake_run(folder, "ar1", 2.0, 0.5, [0.4, 0.42, 0.98, 1.0])
    done = {"name": folder.name, "family": "ar1", "status": "finished", "folder": str(folder), "t95": None,
            "point": {"gas.u_over_umf": 2.0}, "replica": 1}
    ghost = {"name": "ar1_u_over_umf2_r2", "family": "ar1", "status": "pending", "folder": str(out / "runs" / "r2"),
             "t95": None, "point": {"gas.u_over_umf": 2.0}, "replica": 2}
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [done, ghost]}))
    archive(out, dest)
    assert [r["name"] for r in json.loads((dest / "study.json").read_text())["runs"]] == [done["name"], ghost["name"]]
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [done]}))  # the study file dropped the replica
    archive(out, dest)
    assert [r["name"] for r in json.loads((dest / "study.json").read_text())["runs"]] == [done["name"]]
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": []}))  # nor the run: the archive keeps it
    archive(out, dest)
    assert [r["name"] for r in json.loads((dest / "study.json").read_text())["runs"]] == [done["name"]]


def _fake_run(folder, family, ratio, entropy_rate, voidage):
    """A finished run folder as a study leaves it: case, time series, summary, log, gas snapshots, a state."""
    import meshio
    import numpy as np
    folder.mkdir(parents=True)
    (folder / "case.toml").write_text(f'name = "{family}"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = {ratio}\n')
    t = np.linspace(0.0, 4.0, 401)
    columns = {"time": t, "kinetic_energy": 1e-3 + 0 * t, "mixing_entropy": 1 - np.exp(-entropy_rate * t),
               "pressure_drop_over_weight": 1.0 + 0.2 * np.sin(7 * t), "bed_top": 0.4 + 0.02 * np.sin(3 * t)}
    (folder / "timeseries.csv").write_text(",".join(columns) + "\n" + "".join(
        ",".join(repr(float(c[k])) for c in columns.values()) + "\n" for k in range(len(t))))
    (folder / "summary.json").write_text(json.dumps({"simulated_time": 4.0, "wall_seconds": 100.0, "t95": None,
                                                     "cpu_seconds": 90.0, "peak_memory_mb": 350.0, "threads": 1,
                                                     "bed_pressure_drop_std_second_half": 150.0,
                                                     "bed_weight_per_area": 1000.0, "pressure_drop_over_weight": 1.0,
                                                     "provenance": {"fvdem": "x", "host": "vm", "threads": 1,
                                                                    "cpu": "AMD EPYC (family 26, model 2), 2 CPUs"},
                                                     "timings": {"total": 100.0}}))
    (folder / "run.log").write_text("started\nreached its end\n")
    (folder / "checkpoint.npz").write_bytes(b"not small in a real run")
    x, y, z = np.meshgrid(np.linspace(0, 0.15, 3), np.linspace(0, 0.15, 3), np.linspace(0, 0.6, 5), indexing="ij")
    points = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    index = np.arange(points.shape[0]).reshape(x.shape)
    cells = [[index[i, j, k], index[i + 1, j, k], index[i + 1, j + 1, k], index[i, j + 1, k], index[i, j, k + 1],
              index[i + 1, j, k + 1], index[i + 1, j + 1, k + 1], index[i, j + 1, k + 1]]
             for i in range(2) for j in range(2) for k in range(4)]
    from fvdem.io.vtk import write_pvd
    for snapshot in range(4):
        values = np.asarray(voidage, float)[(np.arange(16) + snapshot) % len(voidage)]
        rising = np.column_stack([np.zeros(16), np.zeros(16), 1.0 + np.arange(16) % 3])
        meshio.write(folder / f"gas_{snapshot:05d}.vtu", meshio.Mesh(points, [("hexahedron", cells)], cell_data={
            "voidage": [values], "superficial_velocity": [rising]}))
    write_pvd(folder / "gas.pvd", [(1.0 * k, f"gas_{k:05d}.vtu") for k in range(4)])


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


def test_an_archive_of_compact_results_rebuilds_the_report_and_findings_without_the_run_folders(tmp_path):
    """fvdem study DIR --archive DEST: time series, summaries, void-fraction records and logs, no states or
    VTU; the report and findings made from DEST alone equal the ones made from the run folders."""
    import shutil

    from fvdem.cli import main
    from fvdem.study import report
    out = tmp_path / "study"
    runs = []
    for family, ratio, rate, voidage in (("ar1", 2.0, 0.5, [0.4, 0.42, 0.98, 1.0]),
                                         ("ar4_mp", 2.0, 1.2, [0.5, 0.6, 0.7, 0.8])):
        folder = out / "runs" / f"{family}_u_over_umf{ratio:g}"
        _fake_run(folder, family, ratio, rate, voidage)
        runs.append({"name": folder.name, "family": family, "status": "finished", "folder": str(folder),
                     "t95": None, "point": {"gas.u_over_umf": ratio}, "replica": 1})
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    (out / "study.toml").write_text('name = "t"\n')
    written = report(out)
    table, findings = (json.loads((out / name).read_text()) for name in ("table.json", "findings.json"))
    assert {r["family"]: r["void_fraction_binarity"] is not None for r in table} == {"ar1": True, "ar4_mp": True}
    assert out / "costs.json" in written and out / "costs.md" in written
    for name in ("costs.json", "costs.md"):  # kept aside: the archive's, made from it alone, must equal them
        (tmp_path / name).write_text((out / name).read_text())
    # the findings as a page to read: where the study stands, one row per finding with its verdict, the figures
    page = (out / "findings.md").read_text()
    assert out / "findings.md" in written and page.startswith("# t: findings\n")
    assert out / "plan.toml" in written and (out / "plan.toml").read_text().startswith("# t: the replicas that would")
    assert f"2 of 2 runs at their end, 0 on the way, 0 not started; {len(findings)} findings: " in page
    counts = {v: sum(f["verdict"] == v for f in findings) for v in ("holds", "does not hold", "open")}
    said = {"holds": "hold", "does not hold": "do not hold", "open": "open"}  # verbs agree with their counts
    assert all(f"{n} {v if n == 1 else said[v]}" in page.splitlines()[2] for v, n in counts.items() if n)
    rows = [line for line in page.splitlines() if line.startswith("| ") and not line.startswith("| finding")]
    assert [row.split(" | ")[:2] for row in rows] == [[f"| {f['finding']}", f["verdict"]] for f in findings]
    assert "![t95](t95.png)" in page and "![fig7_void_fraction](fig7_void_fraction.png)" in page
    # the channel record over 1-4 s (no inlet ramp): the 2 x 2 test grid's columns are all "inside" the
    # column's 10 x 10 gas grid, so inside carries all the gas; spheres have no alignment
    channels = [(r["corner_gas_share"], r["wall_gas_share"], r["rod_alignment_inside"]) for r in table]
    assert channels == [(0.0, 0.0, None)] * 2
    dest = tmp_path / "docs" / "data" / "t"
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    files = [p for p in dest.rglob("*") if p.is_file()]
    assert not [p for p in files if p.suffix in (".vtu", ".npz", ".pvd")]
    assert all((dest / "runs" / r["name"] / "channels.json").exists() for r in runs)
    assert sum(p.stat().st_size for p in files) < 400_000
    # archived before the report kept a record (its channels.json): archived again, the record is made from the
    # run folder, though the run holds no more simulated time than the archive
    kept = dest / "runs" / runs[0]["name"] / "channels.json"
    record = kept.read_text()
    kept.unlink()
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    assert kept.read_text() == record
    # the study raised a run's duration after it ended ([[durations]]): archived again, the archive says so,
    # and its report shows the run with more to run (not as ended)
    index = json.loads((out / "study.json").read_text())
    index["runs"][0]["duration"] = 8.0
    (out / "study.json").write_text(json.dumps(index))
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    raised = {r["name"]: r for r in json.loads((dest / "table.json").read_text())}
    assert raised[runs[0]["name"]]["status"] == "pending" and raised[runs[0]["name"]]["duration"] == 8.0
    # archived before the report kept a column (its time series without bed_top): archived again with it
    archived = dest / "runs" / runs[1]["name"] / "timeseries.csv"
    lines = [line.split(",") for line in archived.read_text().splitlines()]
    drop = lines[0].index("bed_top")
    archived.write_text("".join(",".join(x for k, x in enumerate(line) if k != drop) + "\n" for line in lines))
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    assert "bed_top" in archived.read_text().splitlines()[0]
    assert raised[runs[1]["name"]]["status"] == "finished"
    index["runs"][0].pop("duration")
    (out / "study.json").write_text(json.dumps(index))
    json_index = json.loads((dest / "study.json").read_text())
    json_index["runs"][0].pop("duration")
    (dest / "study.json").write_text(json.dumps(json_index))
    assert main(["study", str(dest), "--report"]) == 0
    shutil.rmtree(out)  # the run folders are gone: the archive alone
    assert main(["study", str(dest), "--report"]) == 0
    again = json.loads((dest / "table.json").read_text())
    def rounded(value):  # the archive keeps 6 significant digits
        if isinstance(value, float):
            return float(f"{value:.4g}")
        if isinstance(value, dict):
            return {k: rounded(v) for k, v in value.items()}
        return [rounded(v) for v in value] if isinstance(value, list) else value
    assert rounded(json.loads((dest / "findings.json").read_text())) == rounded(findings)
    assert rounded(table) == rounded(again)
    assert (dest / "runs" / "ar1_u_over_umf2" / "run.log").exists() and (dest / "fig7_void_fraction_2.png").exists()
    # what the runs cost, per family, point and processor, from the archive alone as from the run folders
    assert (dest / "costs.json").read_text() == (tmp_path / "costs.json").read_text()
    assert (dest / "costs.md").read_text() == (tmp_path / "costs.md").read_text()
    assert [(c["family"], c["runs"], c["cpu_per_simulated_second"]["median"])
            for c in json.loads((dest / "costs.json").read_text())] == [("ar1", 1, 22.5), ("ar4_mp", 1, 22.5)]
    # the results as one file (docs/data/mema2020.json): the table's rows, the findings, what made them
    assert main(["study", str(dest), "--results", str(tmp_path / "results.json")]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    assert results["study"] == "t" and results["findings"] == json.loads((dest / "findings.json").read_text())
    assert [r["name"] for r in results["runs"]] == [r["name"] for r in again] and "folder" not in results["runs"][0]
    assert results["ran"].startswith("2 of 2 runs reached their end, 0 on the way, 0 not started")
    # the processor the runs' CPU seconds were spent on, beside their host
    assert results["machine"]["hosts"] == ["vm (AMD EPYC (family 26, model 2), 2 CPUs, 1 thread(s) a run)"]
    assert results["costs"] == json.loads((dest / "costs.json").read_text())
    assert main(["study", str(tmp_path), "--results", str(tmp_path / "r.json")]) == 2  # not a study folder


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


def test_the_t95_chart_shows_runs_that_mixed_or_ended_not_runs_on_their_way(tmp_path, monkeypatch):
    """``report`` derives each run's status once, and the t95 chart takes the runs that mixed or ended unmixed
    (the end a lower bound of t95), not those with more to run; a run that ended early, mixed
    ``time.stop_after_mixed`` before, has ended (not "pending" short of its duration)."""
    import fvdem.analysis.plots as plots
    from fvdem.study import report
    drawn = []
    monkeypatch.setattr(plots, "plot_t95", lambda folders, path, names=None, references=None, aside=None: drawn.append(
        sorted(Path(f).name for f in folders)) or path)
    out = tmp_path / "study"
    mixed, slow = out / "runs" / "mixed", out / "runs" / "slow"
    _fake_run(mixed, "ar1", 2.0, 1.2, [0.5])  # entropy 0.95 at 2.5 s
    _fake_run(slow, "ar1", 1.6, 0.1, [0.5])  # 0.33 at its end, 4 s
    summary = json.loads((mixed / "summary.json").read_text())
    (mixed / "summary.json").write_text(json.dumps({**summary, "t95": 2.5}))

    def chart(slow_status="finished", **entries):
        runs = [{"name": name, "family": "ar1", "status": status, "folder": str(folder), "t95": t95,
                 "point": {"gas.u_over_umf": ratio}, **entries.get(name, {})}
                for name, folder, ratio, t95, status in (("mixed", mixed, 2.0, 2.5, "finished"),
                                                         ("slow", slow, 1.6, None, slow_status))]
        (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
        drawn.clear()
        report(out)
        table = json.loads((out / "table.json").read_text())
        return drawn[-1] if drawn else [], {r["name"]: r["status"] for r in table}

    assert chart() == (["mixed", "slow"], {"mixed": "finished", "slow": "finished"})
    # its duration raised: more to run
    assert chart(slow={"duration": 8.0}) == (["mixed"], {"mixed": "finished", "slow": "pending"})
    # ended early by time.stop_after_mixed (2.5 s + 1.5 s): ended, short of its duration
    (mixed / "summary.json").write_text(json.dumps({**summary, "t95": 2.5, "ended": "mixed"}))
    assert chart(mixed={"duration": 8.0}) == (["mixed", "slow"], {"mixed": "finished", "slow": "finished"})
    summary = json.loads((slow / "summary.json").read_text())
    (slow / "summary.json").write_text(json.dumps({**summary, "stopped_early": True}))
    assert chart("stopped")[0] == ["mixed"]  # stopped on its way
    (slow / "summary.json").unlink()
    assert chart("pending")[0] == ["mixed"]  # on its way, its first segment


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
    out, run = _small_run(tmp_path / "s", 0.02)
    mixed = replace(run, overrides={**run.overrides, "output.mixing_cells": [1, 1, 1], "time.stop_after_mixed": 0.004})
    first = run_task(mixed, 1)
    assert first["status"] == "finished" and first["ended"] == "mixed"
    assert first["simulated_seconds"] == pytest.approx(0.004)
    assert run_task(mixed, 1)["status"] == "skipped"
    later = run_task(replace(mixed, overrides={**mixed.overrides, "time.stop_after_mixed": 0.008}), 1)
    assert later["status"] == "resumed" and later["simulated_seconds"] == pytest.approx(0.008)


def _study_table(**changes):
    import tomllib
    table = tomllib.loads(SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/'))
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
    path.write_text(SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
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


def test_two_studies_on_one_scheduler_never_share_a_task(tmp_path):
    """Dask keeps the first task of a key: the keys carry the study's name and a digest of its folder."""
    from fvdem.study import task_tag
    full = load_study(ROOT / "studies" / "mema2020.toml", tmp_path / "a")
    subset = load_study(ROOT / "studies" / "mema2020_subset.toml", tmp_path / "b")
    assert {b.name for b in full.beds} & {b.name for b in subset.beds}  # the same bed names: bed-ar1 twice
    assert task_tag(full, tmp_path / "a") != task_tag(subset, tmp_path / "b")
    assert task_tag(full, tmp_path / "a") != task_tag(full, tmp_path / "c")
    assert task_tag(full, tmp_path / "a") == task_tag(full, tmp_path / "x" / ".." / "a")


def test_mutated_study_files_are_refused_by_key_and_never_crash_the_loader():
    """tools/fuzz_cases.py --studies: 300 mutations of the shipped study files (the recorded run: 100,000)."""
    sys.path.insert(0, str(ROOT / "tools"))
    import fuzz_cases
    assert fuzz_cases.main(["--studies", "--count", "300", "--seed", "7", "--json"]) == 0


def test_a_cluster_file_apart_from_the_study_and_a_wrong_one_refused(tmp_path):
    """--cluster FILE: the [cluster] keys on their own (the shipped SLURM and PBS examples are valid); a
    misspelt key is refused with the file, the key and a did-you-mean, before anything runs (exit 2)."""
    from fvdem.study import load_cluster
    for name in ("slurm", "pbs"):
        cluster = load_cluster(ROOT / "studies" / "clusters" / f"{name}.toml")
        assert cluster["kind"] == name and cluster["memory"] == "2GB"
    bad = tmp_path / "bad.toml"
    bad.write_text('[cluster]\nkind = "slurm"\nmemroy = "2GB"\n')
    with pytest.raises(CaseError) as err:
        load_cluster(bad)
    assert "cluster.memroy" in str(err.value) and "did you mean 'memory'" in str(err.value) and str(bad) in str(err.value)
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(SMOKE), "--out", str(tmp_path / "o"),
                             "--cluster", str(bad)], capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "memroy" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "o").exists()


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
    text = SMOKE.read_text().replace("replicas = 1", "replicas = 2").replace('"../cases/', f'"{ROOT / "cases"}/')
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


def test_walltimes_and_durations_in_the_forms_the_schedulers_take():
    from fvdem.study.cluster import _duration_seconds, walltime_seconds
    assert [walltime_seconds(t) for t in ("30", "30:15", "02:00:00", "1-00", "1-02:30", "1-02:30:05", " 01:00:00 ")] == [
        1800, 1815, 7200, 86400, 86400 + 9000, 86400 + 9005, 3600]
    assert walltime_seconds("2h") is None and walltime_seconds("") is None
    assert [_duration_seconds(t) for t in ("5m", "300s", "1h", "00:05:00")] == [300, 300, 3600, 300]
    assert _duration_seconds("soon") is None and _duration_seconds(5) is None


def test_a_run_pauses_before_its_jobs_walltime_and_resumes_bit_for_bit(tmp_path, monkeypatch):
    """Inside a batch job (its end and margin exported by the job script, ``job_deadline``) a run checkpoints
    and comes back ``paused`` before the deadline; resumed in the next job it ends bit-for-bit where it ends
    uninterrupted. A job already past its deadline hands a run back without a step."""
    import time

    import numpy as np

    import fvdem.study.tasks as study_tasks
    from fvdem.study import job_deadline, prepare_bed
    assert job_deadline({}) is None
    assert job_deadline({"FVDEM_JOB_END": "1000", "FVDEM_STOP_MARGIN": "60"}) == 940.0
    assert job_deadline({"FVDEM_JOB_END": "1000"}) == 700.0  # 5 minutes unless the cluster table says
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/').replace("duration = 0.02", "duration = 0.2")
    path = tmp_path / "long.toml"
    path.write_text(text.replace('"time.end" = 0.03', '"time.end" = 0.01'))
    study = load_study(path, tmp_path / "out")
    bed = prepare_bed(study.beds[0], 1)
    whole, cut = study.runs[0], replace(study.runs[0], folder=str(tmp_path / "out" / "runs" / "cut"))
    assert run_task(whole, 1, bed)["status"] == "finished"
    monkeypatch.setattr(study_tasks, "PAUSED_RETURN_DELAY", 0.0)
    monkeypatch.setenv("FVDEM_STOP_MARGIN", "0")
    monkeypatch.setenv("FVDEM_JOB_END", str(time.time() - 1))  # a job at its end: not a step
    result = run_task(cut, 1, bed)
    assert result["status"] == "paused" and result["started"] is False and not Path(cut.folder).exists()
    paused_at = []
    for _ in range(2000):  # jobs of 0.1 s until the run is done: each steps at least one chunk (the deadline is
        # checked after a chunk), so a fast machine pauses it too (0.3 s jobs ended it in two on a Zen 5 EPYC); on a
        # loaded machine a job steps one chunk or two, and the run's 400 CFD steps take a few hundred jobs
        monkeypatch.setenv("FVDEM_JOB_END", str(time.time() + 0.1))
        result = run_task(cut, 1, bed)
        if result["status"] != "paused":
            break
        assert result["started"] is True and (Path(cut.folder) / "checkpoint.npz").exists()
        paused_at.append(result["simulated_seconds"])
    assert result["status"] == "resumed" and len(paused_at) >= 2 and paused_at == sorted(paused_at)
    with np.load(Path(whole.folder) / "final_state.npz") as a, np.load(Path(cut.folder) / "final_state.npz") as b:
        for key in a.files:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


def test_a_study_names_its_report_and_an_unknown_report_is_refused(tmp_path):
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/')
    path = tmp_path / "named.toml"
    path.write_text(text.replace('report = "mema2020"', 'report = "table"'))
    study = load_study(path, tmp_path / "out")
    assert study.report == "table" and {r.report for r in study.runs} == {"table"}
    assert load_study(SMOKE, tmp_path / "named").report == "mema2020"  # the smoke study names the paper's
    path.write_text(text.replace('report = "mema2020"', ''))
    assert load_study(path, tmp_path / "default").report == "table"  # the engine's default: the generic table
    path.write_text(text.replace('report = "mema2020"', 'report = "mema202"'))
    with pytest.raises(CaseError) as refused:
        load_study(path, tmp_path / "out")
    assert "report = 'mema202': a registered report (did you mean 'mema2020'?): bed, mema2020, table" in str(refused.value)


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


@pytest.mark.slow
def test_a_study_lost_with_its_machine_continues_from_its_archive(tmp_path, capsys, monkeypatch):
    """fvdem study STUDY --out NEW --restore ARCHIVE: the runs the archive holds at their end are copied into
    NEW and skipped, with no bed settled for them; a run the archive holds in progress starts again (an
    archive has no checkpoint) from a bed settled again, and ends bit-for-bit as it did on the lost machine;
    a run folder that exists is never replaced; a run whose case changed since is not restored; an archive of
    another study, or a folder that is no archive, is refused (exit 2) before anything runs."""
    from fvdem.cli import main
    from fvdem.study import archive, restore, run_study
    path = tmp_path / "smoke.toml"
    path.write_text(SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/'))
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


def test_with_a_deadline_the_runs_expected_to_end_by_it_start_first(tmp_path, monkeypatch):
    """``until``: a freed slot goes first to the runs expected to end before the deadline (their expected
    simulated seconds left at their family's CPU seconds per simulated second, ``study_status``), in
    ``_priority`` order among themselves, then the others; a slot is not left idle."""
    import shutil
    import time

    import fvdem.provenance
    # read on a processor none of the archive's runs ran on: the rates as measured (on one of theirs the status
    # scales them to it: tests/test_locks.py)
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


def test_a_study_stops_at_its_deadline_with_nothing_lost(tmp_path):
    """A deadline already past when the study starts: it stops before any run starts (each listed stopped, no
    folder written), says so in its result, and the same study without the deadline runs them."""
    import time

    from fvdem.study import run_study
    out = tmp_path / "study"
    lines = []
    result = run_study(load_study(_one_run_study(tmp_path, "until", 0.1), out), out, workers=1,
                       log=lines.append, until=time.time() - 1.0)
    assert result["stopped"] and result["until_reached"] and result["until"]
    assert [r["status"] for r in result["runs"]] == ["stopped"] and not (out / "runs" / "small_u_over_umf2").exists()
    assert any("--until" in line and "reached: stopping" in line for line in lines)
    assert any(line.startswith("stops at ") and "(--until), in 0 h 00 min" in line for line in lines)


def test_a_run_listed_in_progress_whose_summary_shows_its_end_is_reported_ended(tmp_path):
    """The index can lag its runs (a study stopped before it handed a finished run on listed it "stopped"):
    the report goes by the run's summary, at its end and not stopped early, and counts it ended."""
    from fvdem.study import report
    out = tmp_path / "study"
    folder = out / "runs" / "ar1_u_over_umf2"
    _fake_run(folder, "ar1", 2.0, 0.5, [0.4, 0.9])
    entry = {"name": folder.name, "family": "ar1", "status": "stopped", "folder": str(folder), "replica": 1,
             "point": {"gas.u_over_umf": 2.0}, "duration": 4.0}
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [entry]}))
    report(out)
    assert json.loads((out / "table.json").read_text())[0]["status"] == "finished"
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [{**entry, "duration": 8.0}]}))
    report(out)  # a longer duration than its summary reached: still on its way
    assert json.loads((out / "table.json").read_text())[0]["status"] == "stopped"


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
    path.write_text(SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/'))
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
    assert ((dest / "runs" / first / "timeseries.csv").read_text()
            != (dest / "superseded" / first / "timeseries.csv").read_text())
    archive(out, dest)  # again: the archive holds the new definition, nothing more moves
    assert sorted(p.name for p in (dest / "superseded").iterdir()) == sorted([first, second])


def test_a_local_study_cluster_runs_with_dasks_monitoring_quieted_unless_the_user_set_it(monkeypatch):
    """QUIET_DASK: the LocalCluster's workers have their statistical profiler off and the scheduler ticks every
    second (Dask's defaults, 10 ms and 20 ms, cost a study a tenth of a core); a value the user's Dask
    configuration sets is kept."""
    import dask

    from fvdem.study import close_client, make_client
    from fvdem.study.cluster import QUIET_DASK, quiet_dask
    assert quiet_dask() == QUIET_DASK  # the suite runs on Dask's defaults
    client, _ = make_client(None, None, 1, 1)
    try:
        assert set(client.run(lambda: dask.config.get("distributed.worker.profile.enabled")).values()) == {False}
        assert client.cluster.scheduler.periodic_callbacks["tick"].callback_time == 1000.0
    finally:
        close_client(client)
    assert dask.config.get("distributed.worker.profile.enabled") is True  # the process's own config untouched
    with dask.config.set({"distributed.admin.tick.interval": "50ms"}):
        assert quiet_dask() == {k: v for k, v in QUIET_DASK.items() if k != "distributed.admin.tick.interval"}
    # a key set by its DASK_* variable is kept, even at Dask's default value
    monkeypatch.setenv("DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED", "True")
    assert "distributed.worker.profile.enabled" not in quiet_dask()
