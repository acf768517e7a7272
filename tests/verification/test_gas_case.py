"""A gas-only case with a fixed bed runs from a case file: Ergun pressure gradient, gas VTU, resume."""
import json
import subprocess
import sys

import meshio
import numpy as np
import pytest

import fvdem

from paths import ROOT

SMALL = {"gas.cells": [4, 4, 35], "time.end": 0.03, "output.progress": False}


def test_fixed_bed_case_reproduces_ergun_and_writes_gas_vtu(tmp_path):
    out = tmp_path / "run"
    overrides = [f"--set={k}={json.dumps(v)}".replace("false", "false") for k, v in SMALL.items()]
    result = subprocess.run([sys.executable, "-m", "fvdem.cli", "run", str(ROOT / "cases" / "fixed_bed_gas.toml"),
                             "--out", str(out), *overrides], capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["porous_zone_pressure_gradient"] == pytest.approx(summary["expected_pressure_gradient"], rel=0.01)
    assert (out / "gas.pvd").exists()
    grid = meshio.read(out / "gas_00001.vtu")
    assert grid.cells[0].type == "hexahedron" and len(grid.cells[0].data) == 4 * 4 * 35
    voidage = grid.cell_data["voidage"][0]
    assert set(np.round(np.unique(voidage), 6)) == {0.45, 1.0}
    superficial = grid.cell_data["superficial_velocity"][0][:, 2]
    assert np.median(superficial) == pytest.approx(1.0, rel=1e-3)
    assert not (out / "final_state.npz").exists()  # no particles in this case
    report = subprocess.run([sys.executable, "-m", "fvdem.cli", "report", str(out)], capture_output=True, text=True,
                            timeout=300)
    assert report.returncode == 0, report.stderr
    assert (out / "timeseries.png").exists() and (out / "gas_profile.png").exists()


def test_gas_case_resumes_bit_for_bit(tmp_path):
    path = ROOT / "cases" / "fixed_bed_gas.toml"
    straight = fvdem.Simulation(fvdem.load_case(path, SMALL), tmp_path / "a")
    straight.run()
    fvdem.Simulation(fvdem.load_case(path, {**SMALL, "time.end": 0.015}), tmp_path / "b").run()
    resumed = fvdem.Simulation(fvdem.load_case(path, SMALL), tmp_path / "b", resume=True)
    resumed.run()
    np.testing.assert_array_equal(straight.gas.solver.velocity, resumed.gas.solver.velocity)
    np.testing.assert_array_equal(straight.gas.solver.pressure, resumed.gas.solver.pressure)


def test_periodic_gas_box_accelerates_under_its_body_force():
    """Fully periodic box, no particles, no walls: body force and gravity accelerate the gas uniformly,
    u = (f / rho + g) t (a periodic pressure cannot hold up the gas's weight; exact under implicit
    Euler)."""
    from fvdem.case import case_from_dict
    case = case_from_dict({
        "domain": {"upper": [0.04, 0.04, 0.08], "periodic": [True, True, True]},
        "particles": {"count": 0},
        "gas": {"enabled": True, "cells": [4, 4, 8], "body_force": [0.0, 0.0, 1.2], "cfd_step": 1e-3},
        "time": {"end": 0.01}, "output": {"progress": False}})
    sim = fvdem.Simulation(case)
    sim.run()
    u = sim.gas.solver.velocity
    np.testing.assert_allclose(u[:, 2], (1.2 / 1.2 - 9.81) * 0.01, rtol=1e-9)
    assert np.abs(u[:, :2]).max() < 1e-12


def test_particles_and_gas_in_one_case_write_both_and_step_in_ratio(tmp_path):
    """Particles and gas together with the coupling switched off: a gas step every cfd/dem DEM steps,
    and particle and gas snapshots side by side."""
    from fvdem.case import case_from_dict
    case = case_from_dict({
        "domain": {"upper": [0.06, 0.06, 0.15]},
        "particles": {"count": 60, "insertion": {"upper": [0.06, 0.06, 0.1]}},
        "gas": {"enabled": True, "cells": [4, 4, 10], "inlet_velocity": 0.2, "cfd_step": 1e-4},
        "coupling": {"enabled": False},
        "time": {"end": 0.002, "dem_step": 1e-5},
        "output": {"progress": False, "snapshot_interval": 0.001, "timeseries_interval": 0.0005,
                   "checkpoint_interval": 0.001}})
    sim = fvdem.Simulation(case, tmp_path / "out")
    sim.run()
    assert sim.step_count == 200 and sim.gas.step_count == 20
    assert (tmp_path / "out" / "particles.pvd").exists() and (tmp_path / "out" / "gas.pvd").exists()
    inflow = -sim.gas.solver.face_flux[sim.gas.mesh.boundary_faces["z-"]].sum()
    assert inflow == pytest.approx(0.2 * 0.06 ** 2, rel=1e-12)
