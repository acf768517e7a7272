"""The stochastic hydrodynamic force (``coupling.stochastic_force``, fvdem/coupling/stochastic.py): the
process's statistics against an independent fine-step simulation and its formulas, the kinetic theory's
pieces against their own definitions, the reaction on the gas, the mixture's momentum, the mean slip,
a resumed run bit-for-bit, and bad parameters refused."""
import json
import math
from types import SimpleNamespace

import numpy as np
import pytest

import fvdem
from fvdem.case import CaseError, case_from_dict
from fvdem.coupling import stochastic
from fvdem.coupling.stochastic import (MODELS, StochasticForce, collision_frequency, contact_radial_distribution,
                                       force_langevin_amplitude, interval_moments, pseudo_turbulent_energy,
                                       register_stochastic_force, streamwise_anisotropy)

from paths import TOOLS

RHO, MU, D = 1000.0, 1e-3, 1e-3


def _force(count, seed=3, scale=1.0):
    return StochasticForce("force-langevin", count, seed, scale, D, RHO, MU)


def _view(ids, velocity):
    """What the force reads of the DEM's host view: the rows' particle ids and velocities."""
    return SimpleNamespace(ids=np.asarray(ids, np.int64), velocity=velocity)


def _uniform_inputs(n, speed=0.01, voidage=0.7, drag=2e-4, theta=1e-5):
    """Every particle with the same slip (along z), voidage and drag coefficient; velocities +-v along x
    with a granular temperature ``theta`` [m^2/s^2] (v^2 / 3 = theta)."""
    slip = np.tile([0.0, 0.0, speed], (n, 1))
    velocity = np.zeros((n, 3))
    velocity[:, 0] = math.sqrt(3.0 * theta) * np.where(np.arange(n) % 2 == 0, 1.0, -1.0)
    return velocity, slip, np.full(n, voidage), np.full(n, drag)


# --------------------------------------------------------------------------- the process
def _fine_ornstein_uhlenbeck(h, paths, substeps, seed):
    """An independent reference: Euler-Maruyama of d xi = -xi dt/T + sqrt(2/T) dW over one interval of
    h = dt/T in ``substeps`` steps, from a stationary start; returns (start, end, interval mean)."""
    rng = np.random.default_rng(seed)
    x = rng.standard_normal(paths)
    start, step, total = x.copy(), h / substeps, np.zeros(paths)
    for _ in range(substeps):
        new = x - x * step + math.sqrt(2.0 * step) * rng.standard_normal(paths)
        total += 0.5 * (x + new) * step  # trapezoidal integral of the path
        x = new
    return start, x, total / h


@pytest.mark.parametrize("h", [0.05, 0.7, 4.0])
def test_the_exact_interval_law_matches_a_fine_step_simulation(h):
    """End value and interval mean of the unit-variance process over h = dt/T: mean given the start,
    variances and covariance of ``interval_moments`` against 400-substep Euler-Maruyama paths."""
    a, m, sx, cy, sy = interval_moments.py_func(h)
    start, end, mean = _fine_ornstein_uhlenbeck(h, 40000, 400, seed=11)
    slope_end, slope_mean = np.polyfit(start, end, 1)[0], np.polyfit(start, mean, 1)[0]
    assert slope_end == pytest.approx(a, abs=0.01) and slope_mean == pytest.approx(m, abs=0.01)
    noise_end, noise_mean = end - a * start, mean - m * start
    assert np.var(noise_end) == pytest.approx(sx * sx, rel=0.03)
    assert np.var(noise_mean) == pytest.approx(cy * cy + sy * sy, rel=0.03)
    assert np.cov(noise_end, noise_mean)[0, 1] == pytest.approx(sx * cy, rel=0.03)
    # the stationary variance is kept and the interval mean's variance is the integral's
    assert a * a + sx * sx == pytest.approx(1.0, rel=1e-12)
    total = m * m + cy * cy + sy * sy
    assert total == pytest.approx(2.0 * (h - 1.0 + math.exp(-h)) / h ** 2, rel=1e-9)


def test_the_interval_law_is_continuous_across_its_series_and_frozen_at_zero():
    below, above = interval_moments.py_func(0.999e-3), interval_moments.py_func(1.001e-3)
    np.testing.assert_allclose(below, above, rtol=2e-3)
    assert interval_moments.py_func(0.0) == (1.0, 1.0, 0.0, 0.0, 0.0)  # Theta = 0: the fluctuation frozen
    a, m, sx, cy, sy = interval_moments.py_func(1e-7)
    assert cy * cy + sy * sy == pytest.approx(2e-7 / 3, rel=1e-6) and sy > 0


def test_the_particles_process_keeps_unit_variance_and_decorrelates_over_the_mean_free_time():
    """20,000 particles, 40 intervals: the state's variance stays 1, its autocorrelation at lag k is
    exp(-k dt / T_F) with T_F the mean free time of the case's phi and Theta, and the held force has the
    level sigma c |W| of ``force_langevin_amplitude``, along and across the slip."""
    n, theta, voidage = 20000, 1e-5, 0.7
    velocity, slip, eps, drag = _uniform_inputs(n, voidage=voidage, theta=theta)
    rate = collision_frequency(1.0 - voidage, D, theta)
    dt = 0.4 / rate  # h = 0.4 per interval
    force = _force(n)
    ids = np.arange(n)
    first = force.xi.copy()
    states, forces = [first], []
    for _ in range(40):
        forces.append(force.force(_view(ids, velocity), slip, eps, drag, dt))
        states.append(force.xi.copy())
    states = np.array(states)
    assert np.var(states[-1]) == pytest.approx(1.0, abs=0.03)
    for lag in (1, 3, 6):
        correlation = np.mean(states[:-lag] * states[lag:]) / np.mean(states ** 2)
        assert correlation == pytest.approx(math.exp(-0.4 * lag), abs=0.02)
    forces = np.array(forces)
    np.testing.assert_allclose(forces.sum(axis=1), 0.0, atol=1e-12 * np.abs(forces).max())  # the mean removed
    speed = 0.01
    re = RHO * D * voidage * speed / MU
    sigma_par, sigma_perp = force_langevin_amplitude(1.0 - voidage, re)
    a, m, sx, cy, sy = interval_moments.py_func(0.4)
    level = m * m + cy * cy + sy * sy  # the interval mean's variance
    magnitude = 2e-4 * speed
    assert np.var(forces[..., 2]) == pytest.approx((magnitude * sigma_par) ** 2 * level, rel=0.03)
    assert np.var(forces[..., :2]) == pytest.approx((magnitude * sigma_perp) ** 2 * level, rel=0.03)
    # the rows follow the particles, not the rows' order: shuffled rows get each particle's own force
    twin, shuffled = _force(n), np.random.default_rng(1).permutation(n)
    held = twin.force(_view(shuffled, velocity), slip, eps, drag, dt)
    reference = _force(n).force(_view(ids, velocity), slip, eps, drag, dt)[shuffled]
    np.testing.assert_allclose(held, reference, rtol=0, atol=1e-12 * np.abs(reference).max())  # the mean's round-off


def test_the_force_turns_with_the_slip_and_scales_with_the_calibration():
    n = 4000
    velocity, slip, eps, drag = _uniform_inputs(n)
    tilted = np.tile([0.006, 0.0, 0.008], (n, 1))  # the same speed, tilted in the x-z plane
    along = tilted[0] / 0.01
    a = _force(n).force(_view(np.arange(n), velocity), tilted, eps, drag, 1e-3)
    b = _force(n).force(_view(np.arange(n), velocity), slip, eps, drag, 1e-3)
    # the same draws give the same interval means J (less their mean over the particles): read them off the
    # z-slip's force, then project them along and across the tilted slip
    re = RHO * D * 0.7 * 0.01 / MU
    sigma_par, sigma_perp = force_langevin_amplitude(0.3, re)
    magnitude = 2e-4 * 0.01
    j = b / (magnitude * np.array([sigma_perp, sigma_perp, sigma_par]))
    j_along = j @ along
    expected = magnitude * (sigma_perp * (j - j_along[:, None] * along) + sigma_par * j_along[:, None] * along)
    np.testing.assert_allclose(a, expected, rtol=0, atol=1e-9 * np.abs(expected).max())
    assert np.var(a @ along) / np.var(a[:, 1]) == pytest.approx((sigma_par / sigma_perp) ** 2, rel=0.1)
    doubled = _force(n, scale=2.0).force(_view(np.arange(n), velocity), slip, eps, drag, 1e-3)
    np.testing.assert_allclose(doubled, 2.0 * b, rtol=1e-12, atol=1e-22)
    # the along-slip calibration scales the part along the slip alone; 0 leaves the part across it
    across = StochasticForce("force-langevin", n, 3, 1.0, D, RHO, MU, along_scale=0.0).force(
        _view(np.arange(n), velocity), tilted, eps, drag, 1e-3)
    np.testing.assert_allclose(across @ along, 0.0, atol=1e-12 * np.abs(a).max())
    np.testing.assert_allclose(across, a - (a @ along)[:, None] * along, rtol=0, atol=1e-9 * np.abs(a).max())
    still = _force(n).force(_view(np.arange(n), velocity), np.zeros((n, 3)), eps, drag, 1e-3)
    assert not still.any()  # no slip, no drag, no fluctuation


# --------------------------------------------------------------------------- the published pieces
def test_the_level_follows_the_pseudo_turbulence_it_is_built_on():
    """The trace of the stresses is the pseudo-turbulent energy; their difference its anisotropy; both
    vanish for an isolated particle, and the dense, fast limit keeps only 2 phi."""
    for phi, re in ((0.1, 0.5), (0.2, 10.0), (0.3, 50.0), (0.45, 250.0)):
        par, perp = force_langevin_amplitude(phi, re)
        energy, anisotropy = pseudo_turbulent_energy.py_func(phi, re), streamwise_anisotropy.py_func(phi, re)
        assert par ** 2 + 2 * perp ** 2 == pytest.approx(energy, rel=1e-12)
        assert par ** 2 - perp ** 2 == pytest.approx(1.5 * energy * anisotropy, rel=1e-12)
        assert par > perp > 0 and 0 < anisotropy <= 0.523
    assert force_langevin_amplitude(0.0, 10.0) == (0.0, 0.0)
    assert pseudo_turbulent_energy.py_func(0.3, 1e12) == pytest.approx(0.6, rel=1e-12)
    assert streamwise_anisotropy.py_func(0.0, 1e6) == pytest.approx(0.523, rel=1e-12)


def test_the_time_scale_is_the_kinetic_theory_mean_free_time():
    """The collision frequency against its definitions: Carnahan-Starling's g_0 from its equation of state
    Z = 1 + 4 phi g_0, and the dilute collision rate n pi d^2 <|v_1 - v_2|> of Maxwellian particles,
    the mean relative speed sampled here."""
    for phi in (0.05, 0.2, 0.4):
        z = (1 + phi + phi ** 2 - phi ** 3) / (1 - phi) ** 3
        assert contact_radial_distribution.py_func(phi) == pytest.approx((z - 1) / (4 * phi), rel=1e-12)
    theta, phi = 2e-4, 0.01
    rng = np.random.default_rng(5)
    relative = np.linalg.norm(rng.normal(0, math.sqrt(theta), (400000, 3)) - rng.normal(0, math.sqrt(theta),
                                                                                         (400000, 3)), axis=1)
    number = phi / (math.pi / 6 * D ** 3)
    dilute = number * math.pi * D ** 2 * relative.mean()
    assert collision_frequency(phi, D, theta) / contact_radial_distribution.py_func(phi) == pytest.approx(
        dilute, rel=0.005)
    assert collision_frequency(0.3, D, 0.0) == 0.0  # particles at rest: T_F infinite


# --------------------------------------------------------------------------- in the coupled model
def _suspension(duration=1.0, model="force-langevin", **suspension):
    table = {"enabled": True, "aspect_ratio": 2.0, "galileo_equivalent": 1296.0, "solids_fraction": 0.29,
             "duration": duration}
    table.update(suspension)
    return {"name": "stochastic", "suspension": table,
            "coupling": {"drag": "tang", "stochastic_force": model, "stochastic_seed": 7},
            "output": {"progress": False, "vtk": False}}


def test_the_gas_receives_the_reaction_of_every_particles_fluctuation():
    """One coupling interval from the same state with and without the model: the gas's exchange source
    differs by -sum w F'' / V_cell (Eq. 8) cell by cell, with the interval's deposition weights, and the
    particles hold -V_p grad p + V_p G + F'' over the interval; summed over the box, nothing changes (the
    mean drag is the closure's)."""
    from fvdem.coupling.interpolation import ParticleGridMap
    runs = {}
    for model in ("force-langevin", "none"):
        case = case_from_dict(_suspension(model=model))
        sim = fvdem.Simulation(case, progress=False)
        sim.particles.velocity[:] = np.random.default_rng(2).normal(0.0, 5e-3, sim.particles.velocity.shape)
        weights = ParticleGridMap(sim.gas.mesh, sim.particles, "trilinear", case.coupling.satellites)
        ids = sim.particles.ids.copy()
        sim.model.bridge.advance()
        runs[model] = sim
    on, off = runs["force-langevin"], runs["none"]
    fluctuation = on.model.bridge.last["stochastic_force"]  # rows in the order of the interval's start
    assert np.abs(fluctuation).max() > 0
    # no bias of the mean drag: the fluctuations sum to zero, so the gas's total exchange and the particles'
    # total force are those without the model, to round-off
    scale = np.abs(fluctuation).max() * len(fluctuation)
    np.testing.assert_allclose(fluctuation.sum(axis=0), 0.0, atol=1e-12 * scale)
    volumes = on.gas.mesh.cell_volumes[:, None]
    np.testing.assert_allclose(((on.gas.exchange_source - off.gas.exchange_source) * volumes).sum(axis=0), 0.0,
                               atol=1e-12 * scale)
    mesh = on.gas.mesh
    reaction = -weights.scatter(fluctuation) / mesh.cell_volumes[:, None]
    np.testing.assert_allclose(on.gas.exchange_source - off.gas.exchange_source, reaction, rtol=0,
                               atol=1e-9 * np.abs(reaction).max())
    assert np.abs(reaction).max() > 1e-3 * np.abs(on.gas.exchange_source).max()
    volume = on.case.particles.volume
    held = (-volume * weights.gather(on.gas.pressure_gradient()) + volume * np.asarray(on.case.gas.mean_pressure_gradient)
            + fluctuation)
    p = on.particles
    by_id = np.empty_like(p.external_force)
    by_id[p.ids] = p.external_force
    np.testing.assert_allclose(by_id[ids], held, rtol=0, atol=1e-12 * np.abs(held).max())


def test_group_means_are_removed_and_the_variance_kept():
    """``remove_group_means``: each group's rows sum to zero afterwards; the rescaling sqrt(n / (n - 1))
    keeps unit-variance independent rows at unit variance (the estimator's law: E[(x - mean)^2] = (n - 1)/n);
    a lone row is zeroed."""
    rng = np.random.default_rng(11)
    groups = np.repeat(np.arange(4000), 5)
    groups = np.concatenate([groups, [4000]])  # one group of a single row
    force = rng.standard_normal((len(groups), 3))
    stochastic.remove_group_means(force, groups)
    sums = np.stack([np.bincount(groups, weights=force[:, k]) for k in range(3)], axis=1)
    np.testing.assert_allclose(sums, 0.0, atol=1e-12)
    np.testing.assert_array_equal(force[-1], 0.0)
    variance = force[:-1].var()
    assert abs(variance - 1.0) < 5 * math.sqrt(2.0 / force[:-1].size)  # 5 standard errors of a variance


def test_host_cells_follow_the_grid_wrapping_periodic_axes_and_clipping_walls():
    from fvdem.gas.mesh import GasMesh
    periodic = GasMesh.box((3, 3, 6), (0.0, 0.0, 0.0), (0.3, 0.3, 0.6), (True, True, True))
    points = np.array([[0.05, 0.05, 0.05], [0.15, 0.25, 0.55], [-0.05, 0.31, 0.61]])
    cells = stochastic.host_cells(points, periodic)
    # FiPy's order, x fastest; the third point wraps to cell (2, 0, 0)
    assert cells.tolist() == [0, 1 + 3 * (2 + 3 * 5), 2]
    np.testing.assert_allclose(periodic.cell_centers[cells[:2]], [[0.05, 0.05, 0.05], [0.15, 0.25, 0.55]])
    walled = GasMesh.box((2, 2, 4), (0.0, 0.0, 0.0), (0.2, 0.2, 0.4))
    assert stochastic.host_cells(np.array([[-0.01, 0.21, 0.45]]), walled).tolist() == [0 + 2 * (1 + 2 * 3)]


def test_a_cell_zero_mean_leaves_each_cells_particles_and_gas_no_net_fluctuation():
    """``stochastic_zero_mean = "cell"``: the fluctuations of the particles whose centres share a cell sum to
    zero (so the cell's particles as a whole feel none), and the gas's reaction, deposited with the
    interval's trilinear weights, sums to zero over the box and is far smaller than with the box-wide
    mean: it is only the deposition's spread of zero-sum forces."""
    from fvdem.coupling.interpolation import ParticleGridMap
    reactions = {}
    for zero_mean in ("box", "cell"):
        table = _suspension()
        table["coupling"]["stochastic_zero_mean"] = zero_mean
        case = case_from_dict(table)
        sim = fvdem.Simulation(case, progress=False)
        sim.particles.velocity[:] = np.random.default_rng(2).normal(0.0, 5e-3, sim.particles.velocity.shape)
        weights = ParticleGridMap(sim.gas.mesh, sim.particles, "trilinear", case.coupling.satellites)
        cells = stochastic.host_cells(sim.particles.position, sim.gas.mesh)
        sim.model.bridge.advance()
        fluctuation = sim.model.bridge.last["stochastic_force"]
        scale = np.abs(fluctuation).max()
        sums = np.stack([np.bincount(cells, weights=fluctuation[:, k], minlength=sim.gas.mesh.cell_count)
                         for k in range(3)], axis=1)
        if zero_mean == "cell":
            np.testing.assert_allclose(sums, 0.0, atol=1e-12 * scale * len(fluctuation))
        else:
            assert np.abs(sums).max() > 0.5 * scale  # a box-wide mean leaves each cell a net force
        reactions[zero_mean] = weights.scatter(fluctuation)
        np.testing.assert_allclose(reactions[zero_mean].sum(axis=0), 0.0, atol=1e-12 * scale * len(fluctuation))
    cell, box = (np.sqrt((reactions[k] ** 2).sum()) for k in ("cell", "box"))
    assert cell < 0.6 * box


def test_a_suspension_with_the_stochastic_force_keeps_the_mixture_momentum_and_moves_sideways():
    """Derksen's force-balanced box with the model: the mixture's momentum stays at zero to round-off
    while the particles move sideways far more than without it."""
    spreads = {}
    for model in ("force-langevin", "none"):
        case = case_from_dict(_suspension(duration=0.4, model=model))
        sim = fvdem.Simulation(case, progress=False)
        momenta, scales = [], []
        for _ in range(8):
            sim.run(case.time.end / 8)
            momenta.append(sim.diagnostics()["mixture_momentum_z"])
            scales.append(float((sim.particles.mass * np.abs(sim.particles.velocity[:, 2])).sum()))
        assert max(abs(m) for m in momenta) < 1e-12 * max(scales)
        spreads[model] = float(np.std(sim.particles.velocity[:, :2]))
    assert spreads["force-langevin"] > 3 * spreads["none"]


def test_a_suspension_with_the_stochastic_force_resumes_bit_for_bit(tmp_path):
    table = _suspension(duration=0.6)
    table["output"].update(checkpoint_interval=0.01, timeseries_interval=0.002, snapshot_interval=1.0)
    straight = fvdem.Simulation(case_from_dict(table), tmp_path / "a")
    straight.run()
    half = case_from_dict(table)
    stop = 0.45 * half.time.end
    fvdem.Simulation(case_from_dict(table, overrides={"time.end": stop}), tmp_path / "b").run()
    resumed = fvdem.Simulation(case_from_dict(table), tmp_path / "b", resume=True)
    resumed.run()
    for name in ("position", "velocity", "angular_velocity", "external_force"):
        np.testing.assert_array_equal(getattr(straight.particles, name), getattr(resumed.particles, name), name)
    np.testing.assert_array_equal(straight.model.bridge.stochastic.xi, resumed.model.bridge.stochastic.xi)
    np.testing.assert_array_equal(straight.gas.solver.velocity, resumed.gas.solver.velocity)
    assert (tmp_path / "a" / "timeseries.csv").read_text() == (tmp_path / "b" / "timeseries.csv").read_text()


def test_the_generator_state_round_trips_exactly():
    force = _force(10, seed=123)
    force.generator.standard_normal(7)
    twin = _force(10, seed=9)
    twin.restore(force.state())
    np.testing.assert_array_equal(twin.generator.standard_normal(50), force.generator.standard_normal(50))
    with pytest.raises(ValueError, match="stochastic.xi holds 10 particles; the case has 3"):
        _force(3).restore(force.state())


# --------------------------------------------------------------------------- bad input
@pytest.mark.parametrize("coupling, message", [
    ({"stochastic_force": "langevin"}, "coupling.stochastic_force"),
    ({"stochastic_force": "force-langevin", "stochastic_scale": 0.0}, "coupling.stochastic_scale"),
    ({"stochastic_force": "force-langevin", "stochastic_scale": 20.0}, "coupling.stochastic_scale"),
    ({"stochastic_force": "force-langevin", "stochastic_seed": -1}, "coupling.stochastic_seed"),
    ({"stochastic_force": "force-langevin", "stochastic_along_scale": -0.5}, "coupling.stochastic_along_scale"),
    ({"stochastic_force": "force-langevin", "drag": "none"}, "coupling.drag = 'none'"),
    ({"stochastic_force": "force-langevin", "stochastic_zero_mean": "particle"}, "coupling.stochastic_zero_mean"),
])
def test_bad_stochastic_parameters_are_refused(coupling, message):
    table = _suspension()
    table["coupling"].update(coupling)
    with pytest.raises(CaseError) as err:
        case_from_dict(table)
    assert message in str(err.value)


def test_an_unknown_model_name_gets_the_registered_ones_and_fixed_particles_are_refused():
    table = _suspension()
    table["coupling"]["stochastic_force"] = "force-langevn"
    with pytest.raises(CaseError, match="force-langevin"):
        case_from_dict(table)
    fixed = {"domain": {"upper": [0.02, 0.02, 0.04]}, "gas": {"enabled": True, "cells": [2, 2, 4]},
             "particles": {"count": 5, "diameter": "2 mm", "fixed": True},
             "coupling": {"stochastic_force": "force-langevin"}, "output": {"progress": False}}
    with pytest.raises(CaseError, match="fixed particles do not move"):
        case_from_dict(fixed)


def test_a_model_must_be_compiled_for_the_signatures_and_is_listed():
    with pytest.raises(TypeError, match="AMPLITUDE"):
        register_stochastic_force("broken", collision_frequency, collision_frequency, summary="wrong signature")
    assert "broken" not in MODELS
    from fvdem.cli import registered
    listed = registered("stochastic_force")["stochastic_force"]
    assert set(listed) == set(stochastic.stochastic_force_names()) >= {"none", "force-langevin"}
    assert "Lattanzi" in listed["force-langevin"]["reference"]


@pytest.mark.slow
def test_the_stochastic_force_leaves_the_mean_slip_within_its_spread():
    """The fluctuation has zero mean over the particles, so it does not bias the mean drag: with its part
    across the slip (``stochastic_along_scale = 0``) the suspension's mean slip Reynolds number lies within
    three combined batch-means standard errors of the one without it, while the horizontal fluctuations
    grow several-fold (l/d = 2, <phi> = 0.29, Ga_e = 1296, Tang's drag, 6 viscous times). The part along
    the slip drives the resolved concentration waves and with them the mean slip (+9 % here over 20 viscous
    times, docs/validation-suspension.md); that is the resolved flow's response, not a bias of the force."""
    results = {}
    for model in ("force-langevin", "none"):
        table = _suspension(duration=6.0, model=model)
        table["coupling"]["stochastic_along_scale"] = 0.0
        results[model] = fvdem.Simulation(case_from_dict(table), progress=False).run()["suspension"]
    on, off = results["force-langevin"], results["none"]
    spread = math.hypot(on["slip_reynolds_standard_error"], off["slip_reynolds_standard_error"])
    print(f"\nRe with {on['slip_reynolds']:.3f} +- {on['slip_reynolds_standard_error']:.3f}, without "
          f"{off['slip_reynolds']:.3f} +- {off['slip_reynolds_standard_error']:.3f}; sigma_h/u_s "
          f"{on['velocity_fluctuation_horizontal_over_settling']:.3f} against "
          f"{off['velocity_fluctuation_horizontal_over_settling']:.3f}")
    assert abs(on["slip_reynolds"] - off["slip_reynolds"]) < 3.0 * spread
    assert on["velocity_fluctuation_horizontal_over_settling"] > 3 * off["velocity_fluctuation_horizontal_over_settling"]


def test_the_sweeps_fluctuations_are_charted_from_saved_outputs(tmp_path, capsys):
    """``validate_hindered_settling.py --fluctuations``: saved sweeps with and without the force on one chart,
    replicas (other seeds, same step) averaged in its table, an output at another step replacing a point."""
    import sys
    from pathlib import Path
    sys.path.insert(0, str(TOOLS))
    import validate_hindered_settling as tool
    outputs = []
    for k, (model, horizontal, re, divisor) in enumerate((("none", 0.08, 5.0, 1), ("none", 0.08, 4.0, 3),
                                                          ("force-langevin", 0.3, 6.0, 3),
                                                          ("force-langevin", 0.6, 4.0, 3))):
        sweep = {"aspect_ratio": 4.0, "drag": "tang", "stochastic_force": model, "stochastic_scale": 2.0,
                 "stochastic_along_scale": 0.0, "cfd_divisor": divisor,
                 "fluctuations_by_phi": {"0.4": {"vertical": 0.9, "horizontal": horizontal}},
                 "re_by_phi": {"0.4": re}}
        path = tmp_path / f"{k}.txt"
        path.write_text("a progress line\n" + json.dumps(sweep) + "\n")
        outputs.append(str(path))
    tool.main(["--fluctuations", *outputs, "--out", str(tmp_path)])
    chart = Path(capsys.readouterr().out.strip())
    assert chart == tmp_path / "hindered_fluctuations.png" and chart.stat().st_size > 10000
    rows = {row.split("|")[3].strip(): [c.strip() for c in row.split("|")[1:-1]]
            for row in (tmp_path / "hindered_fluctuations.md").read_text().splitlines()[2:]}
    # the no-force point at x 1 replaced by the one at x 1/3; the two forced runs are replicas
    assert rows["no stochastic force"][3:6] == ["x 1/3", "1", "4.00"]
    forced = rows["force-langevin x 2, along-slip x 0"]
    assert forced[4] == "2" and forced[5] == "5.00 ± 1.41" and forced[6] == "+25.0 %"
    assert forced[8] == "0.45 ± 0.21" and forced[9] == "2.25 ± 1.06 (1.50-3.00)"
