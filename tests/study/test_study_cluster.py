"""Where a study's tasks run (fvdem.study.cluster, runner): a LocalCluster, a worker killed mid-run and replaced,
map_tasks for the tools' sweeps, a [cluster] table or --cluster file for dask-jobqueue (SLURM), walltimes, a run
paused before its job's walltime and resumed bit for bit, two studies on one scheduler."""
import json
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import pytest

from fvdem.case import CaseError
from fvdem.study import load_study, run_task

from paths import TOOLS
from study_runs import ROOT, SMOKE, one_run_study


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


@pytest.mark.slow
def test_a_worker_killed_mid_run_is_replaced_and_the_run_resumes_from_its_checkpoint(tmp_path):
    """SIGKILL the worker process while its run is past a checkpoint: Dask gives the task to a new
    worker, the run resumes from the checkpoint and ends bit-for-bit where an uninterrupted run does."""
    import signal
    import time

    import numpy as np
    import psutil
    study = one_run_study(tmp_path, "kill", checkpoint_interval=0.02)
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
    sys.path.insert(0, str(TOOLS))
    try:
        for module, name in (("validate_hindered_settling", "run_one"), ("speed_accuracy", "measure_task"),
                             ("validate_umf", "ramp")):
            tool = importlib.import_module(module)
            function = getattr(tool, name)
            assert pickle.loads(pickle.dumps(function)) is function
            assert "map_tasks" in Path(tool.__file__).read_text()
            assert "ProcessPoolExecutor" not in Path(tool.__file__).read_text()
    finally:
        sys.path.remove(str(TOOLS))


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


def test_two_studies_on_one_scheduler_never_share_a_task(tmp_path):
    """Dask keeps the first task of a key: the keys carry the study's name and a digest of its folder."""
    from fvdem.study import task_tag
    full = load_study(ROOT / "studies" / "mema2020.toml", tmp_path / "a")
    subset = load_study(ROOT / "studies" / "mema2020_subset.toml", tmp_path / "b")
    assert {b.name for b in full.beds} & {b.name for b in subset.beds}  # the same bed names: bed-ar1 twice
    assert task_tag(full, tmp_path / "a") != task_tag(subset, tmp_path / "b")
    assert task_tag(full, tmp_path / "a") != task_tag(full, tmp_path / "c")
    assert task_tag(full, tmp_path / "a") == task_tag(full, tmp_path / "x" / ".." / "a")


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
