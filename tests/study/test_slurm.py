"""Studies on a real SLURM (issue 32): a one-node SLURM started on this machine (munge, slurmctld, slurmd,
its own ports and folders), with dask-jobqueue's SLURMCluster submitting real sbatch jobs. Skipped, saying
why, where slurm-wlm and munge are not installed (``apt-get install slurm-wlm munge``; ``.ci/run`` does) or
the suite does not run as root (slurmd must). A SLURM already running on the machine is left alone: this
one listens on ports of its own and is stopped after the module."""
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from paths import ROOT

SMOKE = ROOT / "studies" / "smoke.toml"
FVDEM = [sys.executable, "-m", "fvdem"]
DAEMONS = ("munged", "slurmctld", "slurmd", "sbatch", "squeue", "sinfo", "scancel")


def _wait(condition, seconds, what):
    deadline = time.time() + seconds
    while time.time() < deadline:
        if condition():
            return
        time.sleep(0.5)
    raise AssertionError(f"timed out after {seconds} s waiting for {what}")


def _munge_works() -> bool:
    try:
        token = subprocess.run(["munge", "-n"], capture_output=True, timeout=10)
        return token.returncode == 0 and subprocess.run(["unmunge"], input=token.stdout, capture_output=True,
                                                        timeout=10).returncode == 0
    except (OSError, subprocess.TimeoutExpired):
        return False


@pytest.fixture(scope="module")
def slurm(tmp_path_factory):
    """A one-node SLURM on localhost for this module: ``SLURM_CONF`` points sbatch, squeue and the rest at
    it. Yields the folder holding its configuration and logs."""
    missing = [d for d in DAEMONS if shutil.which(d) is None]
    if missing:
        pytest.skip(f"no SLURM to test against ({', '.join(missing)} not found): apt-get install slurm-wlm munge")
    if os.geteuid() != 0:
        pytest.skip("a one-node SLURM needs root to start slurmd (the suite runs as root in CI, .ci/run)")
    root = tmp_path_factory.mktemp("slurm")
    host = socket.gethostname().split(".")[0]
    memory = int(int(Path("/proc/meminfo").read_text().split()[1]) / 1024 * 0.8)
    for sub in ("state", "spool"):
        (root / sub).mkdir()
    conf = root / "slurm.conf"
    conf.write_text(f"""ClusterName=fvdemtest
SlurmctldHost={host}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
SlurmctldPort=16917
SlurmdPort=16918
StateSaveLocation={root / 'state'}
SlurmdSpoolDir={root / 'spool'}
SlurmctldPidFile={root / 'slurmctld.pid'}
SlurmdPidFile={root / 'slurmd.pid'}
SlurmctldLogFile={root / 'slurmctld.log'}
SlurmdLogFile={root / 'slurmd.log'}
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
NodeName={host} CPUs={os.cpu_count()} RealMemory={memory} State=UNKNOWN
PartitionName=fvdemtest Nodes={host} Default=YES MaxTime=INFINITE State=UP
""")
    started_munge = None
    if not _munge_works():
        key = Path("/etc/munge/munge.key")
        if not key.exists():
            subprocess.run(["mungekey", "--create", "--keyfile", str(key)], check=True, capture_output=True)
        Path("/run/munge").mkdir(parents=True, exist_ok=True)
        started_munge = subprocess.Popen(["munged", "--foreground", "--force"], stdout=subprocess.DEVNULL,
                                         stderr=subprocess.DEVNULL)
        _wait(_munge_works, 20, "munged")
    previous = os.environ.get("SLURM_CONF")
    os.environ["SLURM_CONF"] = str(conf)
    daemons = [subprocess.Popen([d, "-D", "-f", str(conf)], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
               for d in ("slurmctld", "slurmd")]
    try:
        def idle():
            out = subprocess.run(["sinfo", "-h", "-o", "%T"], capture_output=True, text=True)
            return out.returncode == 0 and out.stdout.strip().startswith("idle")
        _wait(idle, 60, f"the node to come up (logs in {root})")
        yield root
    finally:
        subprocess.run(["scancel", "--partition", "fvdemtest"], capture_output=True)
        for daemon in reversed(daemons):
            daemon.send_signal(signal.SIGTERM)
            try:
                daemon.wait(20)
            except subprocess.TimeoutExpired:
                daemon.kill()
        if started_munge is not None:
            started_munge.terminate()
            started_munge.wait(10)
        if previous is None:
            os.environ.pop("SLURM_CONF", None)
        else:
            os.environ["SLURM_CONF"] = previous


def _cluster_file(path: Path, **options) -> Path:
    lines = ['kind = "slurm"', 'memory = "2GB"', f'log_directory = "{path.parent / "dask-logs"}"']
    lines += [f"{k} = {json.dumps(v)}" for k, v in options.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def _long_smoke(tmp_path: Path, duration: float) -> Path:
    """The smoke study with ``duration`` simulated seconds per run (2.6-5.5 s of wall time per
    simulated second on one core) and absolute case paths."""
    text = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/').replace("duration = 0.02", f"duration = {duration}")
    path = tmp_path / "long.toml"
    path.write_text(text.replace('"time.end" = 0.03', '"time.end" = 0.01'))
    return path


@pytest.mark.slow
def test_the_smoke_study_runs_through_sbatch_jobs_and_finishes(slurm, tmp_path):
    cluster = _cluster_file(tmp_path / "slurm.toml", workers=2, walltime="00:10:00")
    result = subprocess.run([*FVDEM, "study", str(SMOKE), "--out", str(tmp_path / "out"), "--cluster", str(cluster),
                             "--json"], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    summary = json.loads(result.stdout.strip().splitlines()[-1])
    assert summary["scheduler"] == "SLURMCluster(up to 2 jobs)"
    assert [r["status"] for r in summary["runs"]] == ["finished", "finished"]
    assert list((tmp_path / "dask-logs").glob("*.err"))  # the workers' job logs: they ran as SLURM jobs


@pytest.mark.slow
def test_a_run_longer_than_its_jobs_walltime_pauses_is_resubmitted_and_ends_bit_for_bit(slurm, tmp_path):
    """Jobs of 1 minute that stop their run 50 s before the walltime: the run checkpoints, pauses, goes back
    into the queue, resumes in the next job (the study retires the old job's worker and adaptive scaling
    starts a new job), however many it takes, and ends bit-for-bit where the same run ends uninterrupted.
    Each job leaves the run 10 s less the worker's start (2-3 s): at 2.6 s of wall time per simulated s of the
    small bed on one core (a Zen 5 core, the fastest measured; 5-5.5 on a Zen 1 or 3) that is at most about
    3 simulated s, so the run of 8 s needs three jobs or more there, two on a machine twice as fast, and six
    or more (about 2 minutes) on the slow ones. (A run of 3 s ended within its first job on CI's Zen 5.)
    Dask's lost-worker-timeout (15 s, how long a gone worker's job is still counted before a new one is
    started) is shortened to 1 s for the test; a retired worker does not come back."""
    from fvdem.study import load_study, prepare_bed, run_task
    study_file = _long_smoke(tmp_path, 8.0)
    cluster = _cluster_file(tmp_path / "slurm.toml", workers=1, walltime="00:01:00", stop_before_walltime="50s")
    environ = {**os.environ, "DASK_DISTRIBUTED__DEPLOY__LOST_WORKER_TIMEOUT": "1s"}
    started = time.time()
    result = subprocess.run([*FVDEM, "study", str(study_file), "--out", str(tmp_path / "out"), "--cluster", str(cluster),
                             "--only", "ar1_u_over_umf2", "--json"], capture_output=True, text=True, timeout=600,
                            cwd=tmp_path, env=environ)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "before its job's walltime; resubmitted" in result.stdout + result.stderr
    folder = tmp_path / "out" / "runs" / "ar1_u_over_umf2"
    log = (folder / "run.log").read_text()
    resumes = log.count("resumed at t = ")
    assert resumes >= 1, log[-2000:]
    # one resumption per job: each paused run's worker was retired, none took the run back past its deadline
    jobs = len(list((tmp_path / "dask-logs").glob("*.err")))
    assert resumes == jobs - 1, (resumes, jobs, log[-2000:])
    print(f"{jobs} jobs, {time.time() - started:.0f} s")
    # the same run uninterrupted, here
    study = load_study(study_file, tmp_path / "whole")
    bed = prepare_bed(study.beds[0], 1)
    whole = next(r for r in study.runs if r.name == "ar1_u_over_umf2")
    assert run_task(whole, 1, bed)["status"] == "finished"
    with np.load(Path(whole.folder) / "final_state.npz") as a, np.load(folder / "final_state.npz") as b:
        for key in a.files:
            np.testing.assert_array_equal(a[key], b[key], err_msg=key)


@pytest.mark.slow
def test_stop_ends_runs_inside_slurm_jobs_with_their_checkpoints(slurm, tmp_path):
    study_file = _long_smoke(tmp_path, 20.0)
    cluster = _cluster_file(tmp_path / "slurm.toml", workers=2, walltime="00:10:00")
    out = tmp_path / "out"
    study = subprocess.Popen([*FVDEM, "study", str(study_file), "--out", str(out), "--cluster", str(cluster)],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=tmp_path)
    try:
        checkpoints = [out / "runs" / name / "checkpoint.npz" for name in ("ar1_u_over_umf2", "ar1_u_over_umf2.9")]
        _wait(lambda: all(c.exists() for c in checkpoints), 240, "both runs' first checkpoints")
        assert subprocess.run([*FVDEM, "study", str(out), "--stop"], capture_output=True, timeout=60).returncode == 0
        output, _ = study.communicate(timeout=180)
    finally:
        if study.poll() is None:
            study.kill()
    assert study.returncode == 130, output[-3000:]
    for checkpoint in checkpoints:
        summary = json.loads((checkpoint.parent / "summary.json").read_text())
        assert summary["stopped_early"] and 0.0 < summary["simulated_time"] < 20.0
    _wait(lambda: not subprocess.run(["squeue", "-h"], capture_output=True, text=True).stdout.strip(), 60,
          "the jobs to leave the queue")
