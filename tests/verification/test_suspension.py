"""Seed 004's periodic suspension: the dimensionless scene, dense packing by compression, the
observables and their statistics, rotational drag, and the momentum balance of the periodic system."""
import math
import sys

import numpy as np
import pytest

import fvdem
from fvdem.analysis.suspension import (orientation_histogram, richardson_zaki_exponent, richardson_zaki_fit,
                                       settling_velocity, steady_window, velocity_fluctuations)
from fvdem.case import CaseError, case_from_dict
from fvdem.coupling.bridge import rotational_drag_torque
from fvdem.dem.packing import compress_periodic

from paths import TOOLS

sys.path.insert(0, str(TOOLS))
import validate_hindered_settling as tool  # noqa: E402


def _scene(**suspension):
    table = {"enabled": True, "aspect_ratio": 2.0, "galileo": 864.0, "solids_fraction": 0.2, "duration": 2.0}
    table.update(suspension)
    return {"name": "suspension", "suspension": table, "output": {"progress": False, "vtk": False}}


# --------------------------------------------------------------------------- the scene's derivation
def test_scene_derives_the_dimensional_case_from_the_dimensionless_inputs():
    case = case_from_dict(_scene())
    d, g = 1e-3, 9.81
    nu = case.gas.viscosity / case.gas.density
    assert g * d ** 3 / nu ** 2 == pytest.approx(864.0, rel=1e-12)
    p = case.particles
    # the spherocylinder has the cylinder's diameter and volume: length l + d/3
    assert p.shape == "spherocylinder" and p.length == pytest.approx(2 * d + d / 3)
    assert p.volume == pytest.approx(math.pi / 4 * d * d * 2 * d, rel=1e-12)
    assert p.density == pytest.approx(2000.0)
    box = np.subtract(case.domain.upper, case.domain.lower)
    np.testing.assert_allclose(box, [9e-3, 9e-3, 18e-3])
    assert all(case.domain.periodic)
    phi = p.count * p.volume / box.prod()
    assert phi == pytest.approx(0.2, abs=0.5 * p.volume / box.prod())
    # mixture weight held by the mean gradient: the whole box is force-balanced
    mixture = phi * 2000.0 + (1 - phi) * 1000.0
    assert case.gas.mean_pressure_gradient[2] == pytest.approx(mixture * g, rel=1e-12)
    assert case.particles.insertion.method == "compress"
    assert case.time.dem_step <= case.collision_time() / 20
    assert case.coupling.rotational_drag == "stokes"
    assert case.coupling.voidage == "trilinear" and case.gas.scheme == "simple"
    assert case.gas.linear_solver == "direct" and case.gas.simple_tolerance == 1e-12


def test_scene_on_the_equivalent_diameter_and_spheres():
    case = case_from_dict(_scene(galileo=None, galileo_equivalent=1296.0))
    p = case.particles
    d_e = (6 * p.volume / math.pi) ** (1 / 3)
    assert d_e == pytest.approx((1.5 * 2e-3 * 1e-6) ** (1 / 3), rel=1e-12)
    nu = case.gas.viscosity / case.gas.density
    assert 9.81 * d_e ** 3 / nu ** 2 == pytest.approx(1296.0, rel=1e-12)
    sphere = case_from_dict({"suspension": {"enabled": True, "particle": "sphere", "galileo": 864.0,
                                            "solids_fraction": 0.3}})
    assert sphere.particles.shape == "sphere" and sphere.particles.diameter == pytest.approx(1e-3)


@pytest.mark.parametrize("change, message", [
    ({"suspension": {"galileo_equivalent": 1296.0}}, "exactly one of galileo"),
    ({"particles": {"count": 10}}, "particles.count = 10: set by [suspension]"),
    ({"domain": {"periodic": [True, True, False]}}, "domain.periodic"),
    ({"suspension": {"aspect_ratio": 0.5}}, "suspension.aspect_ratio = 0.5"),
])
def test_scene_refuses_contradictions(change, message):
    table = _scene()
    for section, values in change.items():
        table.setdefault(section, {}).update(values)
    with pytest.raises(CaseError) as err:
        case_from_dict(table)
    assert message in str(err.value)


# --------------------------------------------------------------------------- packing
@pytest.mark.parametrize("radius, half_length, side", [(0.5e-3, 0.0, 9e-3), (0.5e-3, 1.6667e-3, 14e-3)])
def test_compression_packs_random_suspensions_to_0_48_without_overlap(radius, half_length, side):
    box = np.array([side, side, 2 * side])
    volume = math.pi * radius ** 2 * 2 * half_length + 4 / 3 * math.pi * radius ** 3
    count = round(0.48 * box.prod() / volume)
    p = compress_periodic(count, radius, half_length, 2000.0, box, seed=2)
    assert np.all(p.position >= 0) and np.all(p.position < box)
    from fvdem.dem.system import Box, ContactModel, DEMSystem
    system = DEMSystem(p, Box((0, 0, 0), tuple(box), (True, True, True)), ContactModel(), 1e-6, (0, 0, 0))
    assert system.diagnostics()["max_overlap_over_diameter"] < 0.01
    if half_length > 0:  # isotropic: |cos| of a random axis is uniform, mean 1/2
        assert abs(np.abs(p.axis[:, 2]).mean() - 0.5) < 3 * 0.29 / math.sqrt(count)


# --------------------------------------------------------------------------- observables
def test_settling_velocity_is_the_zero_volume_flux_frame_velocity():
    eps = np.array([0.7, 0.9, 0.8, 0.6])
    vol = np.array([1.0, 2.0, 1.0, 1.0])
    fluid = np.zeros((4, 3))
    fluid[:, 2] = 0.3
    particles = np.zeros((5, 3))
    particles[:, 2] = -0.1
    us, phi = settling_velocity(eps, vol, fluid, particles)
    phi_expected = 1 - (eps * vol).sum() / vol.sum()
    assert phi == pytest.approx(phi_expected)
    assert us == pytest.approx((1 - phi_expected) * 0.4)
    # Galilean invariance: the same in any frame
    assert settling_velocity(eps, vol, fluid + 1.0, particles + 1.0)[0] == pytest.approx(us)


def test_fluctuations_and_orientations_of_known_samples():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(200000, 3)) * [0.2, 0.2, 0.5] + [0, 0, -1]
    sz, sh = velocity_fluctuations(v)
    assert sz == pytest.approx(0.5, rel=0.01) and sh == pytest.approx(0.2, rel=0.01)
    axis = rng.normal(size=(200000, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    density, edges = orientation_histogram(axis)
    centres = 0.5 * (edges[1:] + edges[:-1])
    np.testing.assert_allclose(density, np.sin(centres), atol=0.03)


def test_steady_window_drops_the_transient_and_reports_an_honest_error():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 10, 2000)
    series = 20.0 - 8.0 * np.exp(-t / 0.5) + rng.normal(0, 0.5, len(t))
    w = steady_window(t, series)
    assert 1.0 < w["start"] < 5.0
    assert abs(w["mean"] - 20.0) < 4 * w["standard_error"]
    assert w["standard_error"] == pytest.approx(0.5 / math.sqrt(w["samples"]), rel=0.6)


def test_richardson_zaki_fit_recovers_the_exponent():
    phi = np.array([0.1, 0.2, 0.29, 0.4, 0.48])
    fit = richardson_zaki_fit(phi, 30.0 * (1 - phi) ** 3.2)
    assert fit["re_inf"] == pytest.approx(30.0) and fit["n_exponent"] == pytest.approx(3.2) and fit["r2"] == 1.0
    assert richardson_zaki_exponent(1.0) == pytest.approx(4.45)


# --------------------------------------------------------------------------- rotational drag
def test_rotational_drag_decays_a_spin_exactly_at_any_step():
    inertia, coefficient = np.array([2e-12]), 1e-11  # tau = 0.2 s
    for dt in (0.01, 1.0):  # 1/20 and 5 x the rotational response time
        omega = np.array([[0.0, 3.0, 0.0]])
        for _ in range(4):
            torque = rotational_drag_torque(omega, inertia, coefficient, dt)
            omega = omega + torque * dt / inertia[:, None]
        np.testing.assert_allclose(omega[0, 1], 3.0 * math.exp(-4 * dt / 0.2), rtol=1e-12)


# --------------------------------------------------------------------------- the periodic system
def test_short_periodic_suspension_balances_momentum_and_settles():
    case = case_from_dict(_scene(duration=3.0, solids_fraction=0.29))
    sim = fvdem.Simulation(case, progress=False)
    momenta, scales = [], []
    for _ in range(30):
        sim.run(case.time.end / 30)
        diag = sim.diagnostics()
        momenta.append(diag["mixture_momentum_z"])
        p = sim.particles
        scales.append(float((p.mass * np.abs(p.velocity[:, 2])).sum()))
    # force-balanced and periodic: the total momentum stays at its initial zero to round-off
    # (the scene's direct solves and SIMPLE converged to 1e-12; measured 4e-14)
    assert max(abs(m) for m in momenta) < 1e-12 * max(scales)
    assert abs(np.mean(momenta)) < 1e-12 * max(scales)
    summary = sim.summary()["suspension"]
    assert summary["slip_reynolds"] > 0 and summary["window_start"] < 0.8 * case.time.end
    assert summary["slip_reynolds_standard_error"] < 0.05 * summary["slip_reynolds"]
    # hindered: slower than the single particle's terminal velocity under the same closure
    assert summary["slip_reynolds"] < tool.terminal_reynolds(_scene())


def test_the_sweeps_output_folder_is_made_before_its_runs(tmp_path, monkeypatch):
    """A missing --out folder used to fail when the chart was written, after the whole sweep."""
    import fvdem.study
    seen = {}

    def no_runs(*args, **kwargs):
        seen["folder"] = (tmp_path / "new" / "sweep").is_dir()
        raise SystemExit(0)
    monkeypatch.setattr(fvdem.study, "map_tasks", no_runs)
    with pytest.raises(SystemExit):
        tool.main(["--quick", "--out", str(tmp_path / "new" / "sweep")])
    assert seen["folder"]
