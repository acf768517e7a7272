"""The command line's edges: a closed reader, thread counts, --version, help for every option, warnings
as one line, and what a run folder records about what made it (issue 33)."""
import argparse
import json
import subprocess
import sys

import pytest

from fvdem.cli import cores, make_parser

from paths import ROOT


def fvdem(*args, **kwargs):
    return subprocess.run([sys.executable, "-m", "fvdem", *map(str, args)], capture_output=True, text=True,
                          timeout=300, **kwargs)


@pytest.mark.parametrize("args", [["schema"], ["laws", "--json"], ["schema", "--docs"]])
def test_a_reader_that_goes_away_ends_the_command_quietly(args):
    """``fvdem schema | head``: the reader is gone before fvdem writes; exit 0, nothing on stderr."""
    proc = subprocess.Popen([sys.executable, "-m", "fvdem", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()
    _, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 0 and stderr == b"", stderr.decode()


@pytest.mark.parametrize("value", ["-1", "0", str(cores() + 1), "two"])
def test_a_thread_count_outside_the_machine_is_refused_with_the_range(value, tmp_path):
    result = fvdem("run", ROOT / "cases" / "demo.toml", "--out", tmp_path / "run", "--threads", value)
    assert result.returncode == 2 and "Traceback" not in result.stderr
    assert f"1-{cores()}" in result.stderr and not (tmp_path / "run").exists()
    study = fvdem("study", ROOT / "studies" / "smoke.toml", "--out", tmp_path / "s", "--threads-per-worker", "0")
    assert study.returncode == 2 and "at least 1" in study.stderr and not (tmp_path / "s").exists()


def test_more_threads_than_the_cores_other_work_leaves_free_are_warned_with_the_count_to_use(monkeypatch):
    """`fvdem run` warns when its numba threads exceed the free cores (the 1-minute load average against the
    CPUs it may use): each parallel loop's threads wait for each other, 3 x slower than one thread."""
    from fvdem import cli
    monkeypatch.setattr(cli, "cores", lambda: 4)
    load = {"now": 3.0}
    monkeypatch.setattr(cli.os, "getloadavg", lambda: (load["now"], 0.0, 0.0))
    message = cli.busy_cores(2)
    assert "load average 3.0 on 4 cores" in message and message.endswith("--threads 1")
    assert cli.busy_cores(1) is None  # one thread waits for no other
    load["now"] = 2.0
    assert cli.busy_cores(4).endswith("--threads 2") and cli.busy_cores(2) is None
    load["now"] = 0.3
    assert cli.busy_cores(4) is None  # an idle machine


def test_version_names_the_release_and_the_commit():
    from fvdem import __version__
    result = fvdem("--version")
    assert result.returncode == 0 and result.stdout.startswith(f"fvdem {__version__}")
    if (ROOT / ".git").exists():
        assert "commit " in result.stdout


def test_the_version_is_the_newest_release_in_the_changelog():
    import re

    from fvdem import __version__
    releases = re.findall(r"^## \[(\d+\.\d+\.\d+)\]", (ROOT / "CHANGELOG.md").read_text(), re.M)
    assert releases and releases[0] == __version__


def test_every_option_and_argument_has_help():
    missing = []

    def walk(parser, path):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, f"{path} {name}")
            elif not action.help:
                missing.append(f"{path} {'/'.join(action.option_strings) or action.dest}")
    walk(make_parser(), "fvdem")
    assert not missing, missing


def test_a_run_records_what_made_it_and_logs_progress_warnings_and_timings(tmp_path):
    """summary.json's provenance, case.toml's header, and run.log: provenance, progress lines, each warning
    on one line, the end and the timing table; on resume the log is appended to."""
    out = tmp_path / "run"
    # 3 Umf with a CFD step of 3e-3 s: the inlet's Courant number is 0.95, the bed's above 1, a warning
    sets = ["particles.count=400", "time.end=0.03", "gas.cfd_step=3e-3", "gas.u_over_umf=3", "output.vtk=false",
            "output.timeseries_interval=3e-3"]
    result = fvdem("run", ROOT / "cases" / "demo.toml", "--out", out, "--threads", "1", "--no-progress",
                   *[a for s in sets for a in ("--set", s)])
    assert result.returncode == 0, result.stderr
    summary = json.loads((out / "summary.json").read_text())
    made = summary["provenance"]
    from fvdem import __version__
    assert made["fvdem"] == __version__ and made["threads"] == 1 and made["host"] and made["date"].startswith("20")
    assert {"numba", "numpy", "fipy", "python", "commit", "cpu"} <= set(made)
    header = (out / "case.toml").read_text().splitlines()[1]
    assert header.startswith(f"# made by fvdem {__version__}") and "1 thread(s)" in header
    log = (out / "run.log").read_text().splitlines()
    assert "started: demo" in log[0] and f"fvdem {__version__}" in log[0]
    if made["cpu"]:  # the processor its CPU seconds were spent on, beside the host
        assert f"({made['cpu']}), 1 thread(s)" in log[0] and f"({made['cpu']}), 1 thread(s)" in header
    assert sum("progress" in line for line in log) >= 8
    assert any("reached its end at t = 0.03" in line for line in log)
    assert any("Loop time of" in line for line in log) and any("contact_forces" in line for line in log)
    warned = [line for line in log if "warning (RuntimeWarning)" in line]
    assert len(warned) == 1 and "Courant number" in warned[0] and "reduce gas.cfd_step" in warned[0]
    # on standard error: one line per warning, not Python's file:line and source line
    assert "fvdem: warning (RuntimeWarning)" in result.stderr and "simulation.py:" not in result.stderr
    final = json.loads(next(line for line in result.stdout.splitlines() if line.startswith("{")))
    assert "t95" in final and "pressure_drop_over_weight" in final
    resumed = fvdem("run", ROOT / "cases" / "demo.toml", "--out", out, "--resume", "--threads", "1", "--no-progress",
                    *[a for s in sets[:1] + ["time.end=0.04"] + sets[2:] for a in ("--set", s)])
    assert resumed.returncode == 0, resumed.stderr
    log = (out / "run.log").read_text()
    assert log.count("started: demo") == 1 and "resumed at t = 0.03 s: demo" in log


def test_the_processor_a_run_records_is_read_from_cpuinfo(tmp_path, monkeypatch):
    """provenance's ``cpu``: the first processor's model name, family and model, and the CPUs the process may
    use; without a cpuinfo, ``platform.processor()``; None when nothing names one. ``describe`` puts it beside
    the host, and leaves it out for a record made before fvdem recorded it."""
    import os
    import platform

    from fvdem.provenance import cpu_model, describe
    read = cpu_model.__wrapped__  # not the cached reading of this machine's
    cpuinfo = tmp_path / "cpuinfo"
    block = "processor\t: {0}\nvendor_id\t: AuthenticAMD\ncpu family\t: 26\nmodel\t\t: 2\nmodel name\t: {1}\n\n"
    cpuinfo.write_text(block.format(0, "AMD EPYC 9B45") + block.format(1, "another"))
    monkeypatch.setattr(os, "sched_getaffinity", lambda pid: {0, 1}, raising=False)
    assert read(str(cpuinfo)) == "AMD EPYC 9B45 (family 26, model 2), 2 CPUs"
    cpuinfo.write_text("processor\t: 0\nmodel name\t: ARMv8 Processor\n")  # no family: the name alone
    assert read(str(cpuinfo)) == "ARMv8 Processor, 2 CPUs"
    monkeypatch.setattr(platform, "processor", lambda: "arm")
    assert read(str(tmp_path / "none")) == "arm, 2 CPUs"
    monkeypatch.setattr(platform, "processor", lambda: "")
    assert read(str(tmp_path / "none")) is None
    made = {"fvdem": "0.2.0", "commit": "abc", "date": "2026-12-06", "host": "vm", "threads": 1, "python": "3.11",
            "numpy": "2", "numba": "0.6", "fipy": "4"}
    assert " on vm, 1 thread(s); " in describe(made)
    assert " on vm (AMD EPYC (family 26, model 2), 2 CPUs), 1 thread(s); " in describe(
        {**made, "cpu": "AMD EPYC (family 26, model 2), 2 CPUs"})
