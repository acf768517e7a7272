"""The coupling bridge against independent results: implicit kicks against their closed form, a
terminal velocity against the root of the drag balance, total momentum in a closed periodic box, a
fixed bed's pressure drop against the drag its particles feel and against the closure's prediction,
a held particle, and explicit against semi-implicit coupling beyond the particle response time."""
import numpy as np
import pytest
from scipy.optimize import brentq

import fvdem
from fvdem.case import CaseError, case_from_dict
from fvdem.coupling import closures
from fvdem.coupling.bridge import ExplicitDrag, FixedBed, SemiImplicitDrag, coupling_scheme, particle_response
from fvdem.dem.particles import ParticleArrays, spherocylinder_volume
from fvdem.dem.system import Box, ContactModel, DEMSystem, SimulationError

from paths import ROOT

RHO, MU = 1.2, 1.568e-5


# --------------------------------------------------------------------------- the implicit kick
def _lone_particle(c, u, dt, gravity=(0.0, 0.0, -9.81)):
    particles = ParticleArrays.create(np.array([[0.05, 0.05, 0.05]]), 1e-3, 0.0, 1442.0)
    system = DEMSystem(particles, Box((0, 0, 0), (0.1, 0.1, 0.1), (True, True, True)), ContactModel(normal_stiffness=1.0),
                       dt, gravity)
    particles.drag_coefficient[:] = c
    particles.fluid_velocity[:] = u
    system.implicit_drag = True
    return system


def test_kicks_without_drag_are_bit_identical_to_the_plain_kicks():
    a = _lone_particle(0.0, (1.0, 2.0, 3.0), 1e-4)
    b = _lone_particle(0.0, (1.0, 2.0, 3.0), 1e-4)
    b.implicit_drag = False
    a.particles.velocity[:] = b.particles.velocity[:] = (0.3, -0.1, 0.7)
    a.step(50)
    b.step(50)
    np.testing.assert_array_equal(a.particles.velocity, b.particles.velocity)
    np.testing.assert_array_equal(a.particles.position, b.particles.position)


@pytest.mark.parametrize("step_over_response", [0.01, 1.0, 50.0])
def test_implicit_kicks_follow_their_closed_form_and_record_the_impulse(step_over_response):
    """Velocity after n steps and the recorded drag impulse equal the bridge's prediction
    ``J = m (1 - R)(u - v0) + m a [(1 - R) m / c - dt]`` (what the gas is told), for steps far below
    and far above the response time m / c; the velocity tends to u + m g / c."""
    m = 1442.0 * spherocylinder_volume(1e-3, 0.0)
    dt = 1e-4
    c = step_over_response * m / dt
    u = np.array([0.2, -0.1, 1.5])
    system = _lone_particle(c, u, dt)
    v0 = np.array([0.5, 0.3, -0.4])
    system.particles.velocity[:] = v0
    n = 7
    system.step(n)
    one_minus_r, k = particle_response(np.array([m]), np.array([c]), dt, n)
    g = system.gravity
    predicted = m * one_minus_r[0] * (u - v0) + m * k[0] * g * n * dt
    np.testing.assert_allclose(system.particles.drag_impulse[0], predicted, rtol=1e-10, atol=1e-15 * m)
    np.testing.assert_allclose(system.particles.velocity[0] - v0, (predicted + m * g * n * dt) / m, rtol=1e-10,
                               atol=1e-13)
    system.step(20000 if step_over_response < 1 else 50)
    np.testing.assert_allclose(system.particles.velocity[0], u + m * g / c, rtol=1e-6, atol=1e-9)


# --------------------------------------------------------------------------- helpers for cases
def _periodic_single_particle(diameter, end, cfd_step, dem_step, **coupling):
    """One sphere in a periodic gas box whose weight is carried by a body force (gas at rest)."""
    size = 0.004 if diameter < 1e-4 else 0.02
    return case_from_dict({
        "domain": {"upper": [size, size, size], "periodic": [True, True, True]},
        "particles": {"count": 1, "diameter": diameter, "insertion": {"seed": 2}},
        "contact": {"normal_stiffness": 1e-9},  # a lone particle: no contact ever happens
        "gas": {"enabled": True, "cells": [4, 4, 4], "cfd_step": cfd_step, "body_force": [0.0, 0.0, RHO * 9.81]},
        "coupling": coupling,
        "time": {"dem_step": dem_step, "end": end},
        "output": {"progress": False, "timeseries_interval": cfd_step}})


def _terminal_slip(diameter, voidage=1.0):
    m = 1442.0 * np.pi / 6 * diameter ** 3

    def balance(s):
        return closures.single_particle_drag_coefficient(np.array([[0, 0, s]]), voidage, diameter, RHO, MU)[0] * s - m * 9.81
    return brentq(balance, 1e-9, 100.0, xtol=1e-14)


def test_single_particle_reaches_the_terminal_velocity_of_its_drag_balance():
    """A 0.2 mm sphere falling through quiescent gas (one-way coupling: the gas stays at rest)
    reaches the root of m g = F_D(v_t) (Hoelzer-Sommerfeld at eps = 1) within 0.5 %."""
    d = 2e-4
    sim = fvdem.Simulation(_periodic_single_particle(d, 1.5, 1e-3, 1e-4, two_way=False))
    sim.run()
    from fvdem.coupling.voidage import voidage
    from fvdem.coupling.interpolation import ParticleGridMap
    eps = voidage(sim.particles, sim.gas.mesh, "divided")[0]
    eps_p = ParticleGridMap(sim.gas.mesh, sim.particles).gather(eps)[0]  # 1 - 3e-5: the particle's own volume
    v_t = _terminal_slip(d, eps_p)
    assert np.abs(sim.gas.solver.velocity).max() == 0.0
    assert -sim.particles.velocity[0, 2] == pytest.approx(v_t, rel=5e-3)
    assert -sim.particles.velocity[0, 2] == pytest.approx(v_t, rel=1e-5)  # converged far beyond the bound
    assert np.abs(sim.particles.velocity[0, :2]).max() < 1e-9 * v_t


def test_two_way_slip_reaches_the_terminal_slip():
    """Two-way: the gas is dragged along, but the slip still settles at the drag-balance root (the
    root at the particle's interpolated voidage)."""
    d = 2e-4
    sim = fvdem.Simulation(_periodic_single_particle(d, 1.5, 1e-3, 1e-4, voidage="trilinear"))
    sim.run()
    bridge = sim.bridge
    from fvdem.coupling.interpolation import ParticleGridMap
    grid_map = ParticleGridMap(sim.gas.mesh, sim.particles)
    eps_p = grid_map.gather(sim.gas.solver.voidage)[0]
    slip = grid_map.gather(sim.gas.solver.flux_velocity())[0] - sim.particles.velocity[0]
    assert sim.gas.solver.velocity[:, 2].min() < -1e-4  # the gas does move with the particle
    assert slip[2] == pytest.approx(_terminal_slip(d, eps_p), rel=5e-3)
    assert bridge.last["drag_force"][2] == pytest.approx(sim.particles.mass[0] * 9.81, rel=5e-3)


# --------------------------------------------------------------------------- momentum conservation
def test_total_momentum_in_a_closed_periodic_box_changes_by_the_external_forces_only():
    """Periodic gas + 40 colliding particles, two-way semi-implicit drag, pressure-gradient force,
    trilinear voidage: per CFD step the momentum of gas plus particles changes by gravity and the
    gas body force only, to round-off."""
    case = case_from_dict({
        "domain": {"upper": [0.04, 0.04, 0.08], "periodic": [True, True, True]},
        "particles": {"count": 40, "diameter": "2 mm", "insertion": {"seed": 5}},
        "contact": {"normal_stiffness": 50.0},
        "gas": {"enabled": True, "cells": [4, 4, 8], "cfd_step": 2e-4, "body_force": [0.0, 0.0, 3.0],
                "scheme": "simple", "linear_solver": "direct"},
        "coupling": {"voidage": "trilinear"},
        "time": {"dem_step": 2e-5, "end": 1.0},
        "output": {"progress": False}})
    sim = fvdem.Simulation(case)
    sim.gas.solver.tolerance = 1e-13
    rng = np.random.default_rng(3)
    sim.particles.velocity[:] = rng.normal(0.0, 0.3, (40, 3))
    s, p, mesh = sim.gas.solver, sim.particles, sim.gas.mesh

    def momentum():
        # the gas's momentum includes what the bridge returns to it over the next step
        return (sim.particles.mass[:, None] * sim.particles.velocity).sum(axis=0) + \
            (RHO * s.voidage[:, None] * mesh.cell_volumes[:, None] * s.velocity).sum(axis=0) + \
            sim.gas.returned_momentum.sum(axis=0)

    dt = case.gas.cfd_step
    g = np.array(case.domain.gravity)
    errors, exchanged = [], []
    for _ in range(40):
        before = momentum()
        particles_before = (sim.particles.mass[:, None] * sim.particles.velocity).sum(axis=0)
        sim.run(dt)
        external = (p.mass.sum() * g + (np.array([0, 0, 3.0]) * mesh.cell_volumes.sum())
                    + RHO * g * (s.voidage * mesh.cell_volumes).sum()) * dt
        errors.append(momentum() - before - external)
        # what the particles received from the gas this step (contacts sum to zero)
        exchanged.append((sim.particles.mass[:, None] * sim.particles.velocity).sum(axis=0) - particles_before
                         - p.mass.sum() * g * dt)
    errors, exchanged = np.abs(errors), np.abs(exchanged)
    print(f"\nlargest exchange {exchanged.max():.3e} N s, largest imbalance {errors.max():.3e} N s")
    assert exchanged.max() > 1e-3 * p.mass.sum() * 9.81 * dt  # momentum does flow between the phases
    assert errors.max() < 1e-9 * exchanged.max()


def test_force_balanced_periodic_suspension_keeps_its_momentum_to_round_off():
    """Seed 004's set-up in miniature: a periodic liquid-particle box held up by a mean pressure
    gradient equal to the mixture weight (G = rho_mix g on both phases): the external forces sum to
    zero, so the total momentum must not change while the particles settle against the liquid."""
    rho_l, rho_p, n, d = 1000.0, 2000.0, 40, 2e-3
    size = (0.02, 0.02, 0.04)
    phi = n * np.pi / 6 * d ** 3 / np.prod(size)
    mixture = phi * rho_p + (1 - phi) * rho_l
    case = case_from_dict({
        "domain": {"upper": list(size), "periodic": [True, True, True]},
        "particles": {"count": n, "diameter": d, "density": rho_p, "insertion": {"seed": 8}},
        "contact": {"normal_stiffness": 50.0},
        "gas": {"enabled": True, "cells": [4, 4, 8], "cfd_step": 2e-4, "density": rho_l, "viscosity": 1e-3,
                "mean_pressure_gradient": [0.0, 0.0, mixture * 9.81], "scheme": "simple", "linear_solver": "direct"},
        "coupling": {"voidage": "trilinear"},
        "time": {"dem_step": 2e-5, "end": 1.0},
        "output": {"progress": False}})
    sim = fvdem.Simulation(case)
    sim.gas.solver.tolerance = 1e-13
    s, mesh = sim.gas.solver, sim.gas.mesh

    def momentum():
        p = sim.particles
        return (p.mass[:, None] * p.velocity).sum(axis=0) + \
            (rho_l * s.voidage[:, None] * mesh.cell_volumes[:, None] * s.velocity).sum(axis=0) + \
            sim.gas.returned_momentum.sum(axis=0)

    start = momentum()
    sim.run(40 * 2e-4)
    settling = -np.mean(sim.particles.velocity[:, 2])
    scale = sim.particles.mass.sum() * settling
    assert settling > 1e-4  # the particles do settle through the liquid
    np.testing.assert_allclose(momentum(), start, atol=1e-9 * scale)


# --------------------------------------------------------------------------- fixed bed and held particle
def _fixed_bed_case(tmp_path, positions, diameter, inlet, cells, upper, cfd_step=0.02, **coupling):
    particles = ParticleArrays.create(np.asarray(positions, float), 0.5 * diameter, 0.0, 1442.0)
    state = tmp_path / "bed.npz"
    np.savez(state, **particles.as_dict())
    return case_from_dict({
        "domain": {"upper": upper},
        "particles": {"count": len(positions), "diameter": diameter, "fixed": True, "initial_state": str(state),
                      "colour": "single"},
        "gas": {"enabled": True, "cells": cells, "cfd_step": cfd_step, "inlet_velocity": inlet, "walls": "free-slip",
                "scheme": "simple", "linear_solver": "direct"},
        "coupling": {"voidage": "trilinear", **coupling},
        "time": {"end": 1.0},
        "output": {"progress": False}})


def _lattice(cell, layers, per_cell=2, columns=4, bottom=2):
    """Spheres on a cubic lattice, ``per_cell`` per cell edge, filling ``layers`` cell layers from
    cell layer ``bottom`` up."""
    offsets = (np.arange(columns * per_cell) + 0.5) * cell / per_cell
    z = bottom * cell + (np.arange(layers * per_cell) + 0.5) * cell / per_cell
    return np.array([(x, y, zz) for zz in z for y in offsets for x in offsets])


def test_fixed_bed_pressure_drop_equals_the_force_on_its_particles(tmp_path):
    """Gas through a fixed lattice bed (eps = 0.476 in its core) at 0.5 m/s: pressure drop x area
    equals the total force the particles feel (drag + pressure-gradient force) plus the gas weight
    and the momentum and viscous fluxes through inlet and outlet, to round-off."""
    cell, d, u_in = 0.01, 0.005, 0.5
    case = _fixed_bed_case(tmp_path, _lattice(cell, 6), d, u_in, [4, 4, 12], [0.04, 0.04, 0.12])
    sim = fvdem.Simulation(case)
    sim.gas.solver.tolerance = 1e-11
    sim.run(1.0)
    s, mesh = sim.gas.solver, sim.gas.mesh
    area = 0.04 * 0.04
    # inlet face pressure (as the solver's gradient takes it) minus the outlet's 0
    drop = s.inlet_pressure()
    gas_weight = RHO * 9.81 * (s.voidage * mesh.cell_volumes).sum()
    outlet, inlet = mesh.boundary_faces["z+"], mesh.boundary_faces["z-"]
    momentum_out = RHO * (s.face_flux[outlet] * s.velocity[mesh.face_cells[outlet, 0], 2]).sum() \
        - RHO * u_in * area * u_in / s.voidage[mesh.face_cells[inlet, 0]].mean()
    inlet_cells = mesh.face_cells[inlet, 0]  # viscous stress on the inlet face (Dirichlet U / eps)
    viscous_in = (MU * s.voidage[inlet_cells] * mesh.face_areas[inlet] * (u_in / s.voidage[inlet_cells]
                  - s.velocity[inlet_cells, 2]) / mesh.face_distances[inlet]).sum()
    particle_force = sim.bridge.last["drag_force"][2] + sim.bridge.last["pressure_force"][2]
    assert particle_force > 0.9 * drop * area
    assert drop * area + viscous_in == pytest.approx(particle_force + gas_weight + momentum_out, rel=1e-8)


def test_uniform_fixed_bed_pressure_gradient_is_the_closure_prediction(tmp_path):
    """A lattice bed filling the whole column (eps = 0.476 everywhere) at 0.5 m/s: the pressure
    gradient equals the closure's n F_D(U / eps, eps) / eps + rho g (Hoelzer-Sommerfeld + Di Felice);
    its ratio to Ergun is printed (Di Felice only approximates Ergun)."""
    cell, d, u_in = 0.01, 0.005, 0.5
    case = _fixed_bed_case(tmp_path, _lattice(cell, 8, bottom=0), d, u_in, [4, 4, 8], [0.04, 0.04, 0.08])
    sim = fvdem.Simulation(case)
    sim.gas.solver.tolerance = 1e-11
    sim.run(1.0)
    s, gas = sim.gas.solver, sim.gas
    eps = 1.0 - 8 * np.pi / 6 * d ** 3 / cell ** 3
    assert np.ptp(s.voidage) < 1e-12 and s.voidage[0] == pytest.approx(eps, rel=1e-12)
    np.testing.assert_allclose(s.flux_velocity()[:, 2], u_in / eps, rtol=1e-9)
    gradient = (gas.plane_pressure(0.025) - gas.plane_pressure(0.055)) / 0.03
    drag = closures.single_particle_drag(np.array([[0.0, 0.0, u_in / eps]]), eps, d, RHO, MU)[0, 2]
    number_density = (1 - eps) / (np.pi / 6 * d ** 3)
    predicted = number_density * drag / eps + RHO * 9.81
    assert gradient == pytest.approx(predicted, rel=1e-6)
    ergun = 150 * (1 - eps) ** 2 * MU * u_in / (eps ** 3 * d ** 2) + 1.75 * (1 - eps) * RHO * u_in ** 2 / (eps ** 3 * d)
    print(f"\nfixed bed eps={eps:.3f} U={u_in}: closure {predicted - RHO * 9.81:.1f} Pa/m, measured "
          f"{gradient - RHO * 9.81:.1f} Pa/m, Ergun {ergun:.1f} Pa/m (closure/Ergun = {(predicted - RHO * 9.81) / ergun:.3f})")
    assert 0.5 < (gradient - RHO * 9.81) / ergun < 1.5


def test_uniform_fixed_bed_with_gidaspow_drag_has_ergun_pressure_gradient(tmp_path):
    """The same lattice bed with coupling.drag = 'gidaspow': model A's fixed-bed gradient n F_D / eps is
    Ergun's equation exactly (an independent result: Ergun 1952), plus the gas head."""
    cell, d, u_in = 0.01, 0.005, 0.5
    case = _fixed_bed_case(tmp_path, _lattice(cell, 8, bottom=0), d, u_in, [4, 4, 8], [0.04, 0.04, 0.08],
                           drag="gidaspow")
    sim = fvdem.Simulation(case)
    sim.gas.solver.tolerance = 1e-11
    sim.run(1.0)
    eps = 1.0 - 8 * np.pi / 6 * d ** 3 / cell ** 3
    gradient = (sim.gas.plane_pressure(0.025) - sim.gas.plane_pressure(0.055)) / 0.03
    ergun = 150 * (1 - eps) ** 2 * MU * u_in / (eps ** 3 * d ** 2) + 1.75 * (1 - eps) * RHO * u_in ** 2 / (eps ** 3 * d)
    assert gradient == pytest.approx(ergun + RHO * 9.81, rel=1e-6)


def test_held_particle_feels_exactly_the_closure_drag(tmp_path):
    """One sphere held in an upward gas flow: the force the bridge exchanges is the closure's drag at
    the interpolated gas velocity and voidage."""
    d, u_in = 0.005, 1.0
    case = _fixed_bed_case(tmp_path, [[0.02, 0.02, 0.05]], d, u_in, [4, 4, 10], [0.04, 0.04, 0.1])
    sim = fvdem.Simulation(case)
    sim.run(0.8)  # the exchange uses the gas velocity before and after a step: equal once steady (1e-10 by 0.8 s)
    from fvdem.coupling.interpolation import ParticleGridMap
    grid_map = ParticleGridMap(sim.gas.mesh, sim.particles)
    u_p = grid_map.gather(sim.gas.solver.flux_velocity())
    eps_p = grid_map.gather(sim.gas.solver.voidage)
    expected = closures.single_particle_drag(u_p, eps_p, d, RHO, MU)[0]
    np.testing.assert_allclose(sim.bridge.last["drag_force"], expected, rtol=1e-9, atol=1e-15)
    assert expected[2] > 0 and abs(expected[0]) < 1e-6 * expected[2]


# --------------------------------------------------------------------------- stability
def _response_time(d):
    v_t = _terminal_slip(d)
    m = 1442.0 * np.pi / 6 * d ** 3
    return m / closures.single_particle_drag_coefficient(np.array([[0, 0, v_t]]), 1.0, d, RHO, MU)[0], v_t


def test_explicit_drag_diverges_where_semi_implicit_stays_stable():
    """CFD step = 5 particle response times (a 20 um sphere): explicit coupling (force held over the
    step) oscillates with growing amplitude; fvdem refuses it with the cause; the semi-implicit
    scheme reaches the terminal velocity."""
    d = 2e-5
    tau, v_t = _response_time(d)
    dt = 5 * tau
    explicit = fvdem.Simulation(_periodic_single_particle(d, 40 * dt, dt, dt / 5, two_way=False,
                                                          drag_treatment="explicit"))
    explicit.bridge.check_explicit_stability = lambda c, m: None  # watch it fail
    speeds = []
    for _ in range(12):
        explicit.run(dt)
        speeds.append(abs(explicit.particles.velocity[0, 2]))
    assert speeds[-1] > 1e3 * v_t and speeds[-1] > 10 * speeds[-3]

    guarded = fvdem.Simulation(_periodic_single_particle(d, 40 * dt, dt, dt / 5, two_way=False,
                                                         drag_treatment="explicit"))
    with pytest.raises(SimulationError, match="explicit drag is unstable.*exceeds 2 x the particle response time"):
        guarded.run()

    implicit = fvdem.Simulation(_periodic_single_particle(d, 40 * dt, dt, dt / 5, two_way=False))
    implicit.run()
    assert -implicit.particles.velocity[0, 2] == pytest.approx(v_t, rel=1e-3)


def test_explicit_drag_below_the_bound_is_stable_and_agrees():
    d = 2e-5
    tau, v_t = _response_time(d)
    dt = 0.5 * tau
    sim = fvdem.Simulation(_periodic_single_particle(d, 60 * dt, dt, dt / 5, two_way=False, drag_treatment="explicit"))
    sim.run()
    assert -sim.particles.velocity[0, 2] == pytest.approx(v_t, rel=1e-3)


# --------------------------------------------------------------------------- case checks
@pytest.mark.parametrize("coupling, shape, message", [
    ({"lift": "zastawny"}, "sphere", "coupling.lift = 'zastawny': a sphere has no"),
    ({"torque": "sanjeevi-padding"}, "sphere", "coupling.torque"),
    ({"drag": "sanjeevi-padding"}, "sphere", "fitted for aspect-ratio-4"),
    ({"drag": "sanjeevi-padding"}, "ar2", "fitted for aspect ratio 4"),
    ({"drag_treatment": "implicit"}, "sphere", "coupling.drag_treatment"),
])
def test_case_refuses_closures_that_do_not_fit_the_particles(coupling, shape, message):
    particles = {"count": 10, "diameter": "3 mm"}
    if shape == "ar2":
        particles.update(shape="spherocylinder", length="6 mm")
    with pytest.raises(CaseError, match=message):
        case_from_dict({"particles": particles, "gas": {"enabled": True}, "coupling": coupling})


def test_fixed_particles_need_the_gas():
    with pytest.raises(CaseError, match="particles.fixed = true"):
        case_from_dict({"particles": {"count": 10, "fixed": True}})


def test_coupled_run_resumes_bit_for_bit(tmp_path):
    table = {
        "domain": {"upper": [0.04, 0.04, 0.12]},
        "particles": {"count": 150, "diameter": "5.3 mm", "insertion": {"upper": [0.04, 0.04, 0.06], "seed": 4}},
        "gas": {"enabled": True, "cells": [4, 4, 12], "inlet_velocity": 1.2, "cfd_step": 1e-4},
        "time": {"end": 0.006},
        "output": {"progress": False, "snapshot_interval": 0.003, "checkpoint_interval": 0.003,
                   "timeseries_interval": 0.001}}
    straight = fvdem.Simulation(case_from_dict(table), tmp_path / "a")
    straight.run()
    half = {**table, "time": {"end": 0.003}}
    fvdem.Simulation(case_from_dict(half), tmp_path / "b").run()
    resumed = fvdem.Simulation(case_from_dict(table), tmp_path / "b", resume=True)
    resumed.run()
    np.testing.assert_array_equal(straight.particles.position, resumed.particles.position)
    np.testing.assert_array_equal(straight.particles.velocity, resumed.particles.velocity)
    np.testing.assert_array_equal(straight.gas.solver.velocity, resumed.gas.solver.velocity)
    np.testing.assert_array_equal(straight.gas.solver.pressure, resumed.gas.solver.pressure)
    assert straight.summary()["pressure_drop_over_weight"] == resumed.summary()["pressure_drop_over_weight"]


@pytest.mark.parametrize("closures", ["zastawny", "sanjeevi-padding"])
def test_rod_bed_with_lift_and_torque_runs_and_reports(tmp_path, closures):
    """AR-4 rods with lift and torque (SP and MP closures) in a small fluidized column: the run stays
    finite, the particles turn under the hydrodynamic torque, and the report draws orientation and
    void-fraction plots."""
    from fvdem.analysis.plots import report
    table = {
        "domain": {"upper": [0.045, 0.045, 0.15]},
        "particles": {"shape": "spherocylinder", "count": 200, "diameter": "3 mm", "length": "12 mm",
                      "insertion": {"upper": [0.045, 0.045, 0.1], "seed": 2}},
        "gas": {"enabled": True, "cells": [3, 3, 10], "inlet_velocity": 2.5, "cfd_step": 1e-4},
        "coupling": {"drag": "sanjeevi-padding" if closures == "sanjeevi-padding" else "hoelzer-sommerfeld",
                     "lift": closures, "torque": closures},
        "time": {"end": 0.01},
        "output": {"progress": False, "snapshot_interval": 0.005, "timeseries_interval": 0.001}}
    sim = fvdem.Simulation(case_from_dict(table), tmp_path / "run")
    sim.run()
    p = sim.particles
    assert np.all(np.isfinite(p.velocity)) and np.all(np.isfinite(p.angular_velocity))
    assert np.abs(p.external_torque).max() > 0.0
    names = {path.name for path in report(tmp_path / "run")}
    assert {"orientation.png", "void_fraction.png", "mixing.png", "timeseries.png"} <= names


def test_a_one_way_coupled_run_writes_its_folder_from_the_first_sample(tmp_path):
    """One-way coupling (``coupling.two_way = false``) with an output folder: the first sample, taken before
    any step, reports the over-packed cells like a two-way run (it raised KeyError before the voidage was
    mapped at construction in both modes)."""
    from fvdem.case import load_case
    case = load_case(ROOT / "cases" / "coupled_small.toml",
                     {"coupling.two_way": False, "particles.count": 300, "output.progress": False,
                      "output.vtk": False})
    sim = fvdem.Simulation(case, tmp_path / "run", progress=False)
    summary = sim.run(0.005)
    rows = (tmp_path / "run" / "timeseries.csv").read_text().splitlines()
    header = rows[0].split(",")
    assert summary["simulated_time"] == pytest.approx(0.005) and len(rows) >= 3
    assert "over_packed_cells" in header
    assert float(rows[1].split(",")[header.index("over_packed_cells")]) == 0.0


def test_the_coupling_scheme_is_chosen_once_from_the_drag_treatment_and_fixed_particles():
    assert isinstance(coupling_scheme("semi-implicit", False), SemiImplicitDrag)
    assert isinstance(coupling_scheme("semi-implicit", True), FixedBed)
    assert coupling_scheme("explicit", False).moving and not coupling_scheme("explicit", True).moving
    assert isinstance(coupling_scheme("explicit", True), ExplicitDrag)
