"""The per-phase timing table (issue 16, point 1): every phase a run has is timed, the phases add up
to no more than the run's wall time, and a resumed run continues the table."""
import subprocess
import sys

import pytest

import fvdem
import fvdem.timing as timing
from fvdem.case import case_from_dict
from fvdem.timing import PHASES

COUPLED = {"particles": {"count": 150, "diameter": "5 mm", "insertion": {"upper": [0.04, 0.04, 0.06]}},
           "domain": {"upper": [0.04, 0.04, 0.2]}, "gas": {"enabled": True, "cells": [2, 2, 10],
                                                          "inlet_velocity": 2.0},
           "time": {"end": 0.01}, "output": {"progress": False, "timeseries_interval": 0.002,
                                              "checkpoint_interval": 0.005, "snapshot_interval": 0.005}}


def test_a_coupled_run_times_every_phase_and_they_add_up(tmp_path):
    summary = fvdem.Simulation(case_from_dict(COUPLED), tmp_path / "run").run()
    t = summary["timings"]
    assert set(t) == set(PHASES) | {"other", "total"}
    for phase in ("contact_forces", "integration", "voidage_mapping", "closures", "deposition", "gas_momentum",
                  "gas_pressure", "gas_other", "output"):
        assert t[phase] > 0.0, phase
    assert sum(t[p] for p in PHASES) <= t["total"] * (1 + 1e-9) and t["other"] >= 0.0
    assert t["total"] == summary["wall_seconds"]


def test_a_particle_only_run_has_no_gas_or_coupling_time():
    table = {k: v for k, v in COUPLED.items() if k != "gas"}
    t = fvdem.Simulation(case_from_dict(table)).run()["timings"]
    assert t["integration"] > 0 and t["contact_forces"] > 0
    assert all(t[p] == 0.0 for p in ("voidage_mapping", "closures", "deposition", "gas_momentum", "gas_pressure",
                                      "gas_other"))


def test_a_resumed_run_continues_the_table(tmp_path):
    out = tmp_path / "run"
    first = fvdem.Simulation(case_from_dict(COUPLED, overrides={"time.end": 0.005}), out).run()["timings"]
    resumed = fvdem.Simulation(case_from_dict(COUPLED), out, resume=True).run()["timings"]
    for phase in ("integration", "gas_pressure", "closures", "total"):
        assert resumed[phase] > first[phase], phase


def test_fvdem_run_prints_the_table(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text('[particles]\ncount = 50\ndiameter = "5 mm"\n[domain]\nupper = [0.03, 0.03, 0.1]\n'
                    '[time]\nend = 0.002\n[output]\nprogress = false\n')
    result = subprocess.run([sys.executable, "-m", "fvdem", "run", str(path), "--out", str(tmp_path / "out")],
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert "Loop time of" in result.stdout and "contact_forces" in result.stdout and "%total" in result.stdout


def test_a_phase_counts_its_own_time_less_what_was_recorded_inside_it(monkeypatch):
    """``with timings.phase(name)``: a phase opened inside another, or seconds added inside it (the DEM's own
    timing), are not the outer phase's; an unknown phase is refused by name."""
    clock = iter([0.0, 1.0, 4.0, 10.0])  # closures opens, deposition opens and closes, closures closes
    monkeypatch.setattr(timing, "perf_counter", lambda: next(clock))
    t = timing.Timings()
    with t.phase("closures"):
        with t.phase("deposition"):
            t.add("integration", 0.5)  # recorded by a part that times itself
    assert t.seconds["integration"] == 0.5 and t.seconds["deposition"] == 2.5 and t.seconds["closures"] == 7.0
    assert sum(t.seconds.values()) == 10.0
    with pytest.raises(KeyError, match="no timing phase 'gas'"):
        t.phase("gas")
