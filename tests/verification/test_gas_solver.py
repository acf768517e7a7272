"""The SIMPLE gas solver against independent references: an implicit-Euler transient, plug flow,
mass conservation with a changing voidage, and the Ergun pressure drop of a fixed porous zone."""
import numpy as np
import pytest

from fvdem.gas.mesh import GasMesh
from fvdem.gas.solver import GasProperties, GasSolver

from conftest import step_drifting_bed

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_periodic_box_with_body_force_and_drag_follows_implicit_euler_to_f_over_beta():
    """Uniform beta and force f in a periodic box: u_n = (f/beta)(1 - r^n), r = 1/(1 + beta dt/(rho eps))."""
    mesh = GasMesh.box((4, 4, 8), (0, 0, 0), (0.04, 0.04, 0.08), (True, True, True))
    solver = GasSolver(mesh, gravity=(0, 0, 0))
    beta, force, dt, rho = 50.0, 10.0, 1e-2, solver.gas.density
    solver.voidage[:] = solver.voidage_old[:] = 0.6
    solver.beta[:] = beta
    solver.source[:, 2] = force
    r = 1.0 / (1.0 + beta * dt / (rho * 0.6))
    for n in range(1, 6):
        solver.step(dt)
        np.testing.assert_allclose(solver.velocity[:, 2], force / beta * (1 - r ** n), rtol=1e-7)
    for _ in range(60):
        solver.step(dt)
    np.testing.assert_allclose(solver.velocity[:, 2], force / beta, rtol=1e-7)
    assert np.abs(solver.velocity[:, :2]).max() < 1e-12
    assert np.abs(solver.face_flux[mesh.unused]).max() == 0.0


def empty_column(walls):
    mesh = GasMesh.box((5, 5, 20), (0, 0, 0), (0.075, 0.075, 0.3))
    solver = GasSolver(mesh, inlet_velocity=0.5, walls=walls, gravity=(0, 0, 0))
    for _ in range(40):  # the start-up transient decays below 1e-6 within ~30 steps
        info = solver.step(1e-2)
    return mesh, solver, info


def test_empty_column_reaches_plug_flow_and_conserves_mass():
    mesh, solver, info = empty_column("free-slip")
    assert info["continuity_residual"] < 1e-7
    inflow = -solver.face_flux[mesh.boundary_faces["z-"]].sum()
    outflow = solver.face_flux[mesh.boundary_faces["z+"]].sum()
    assert outflow == pytest.approx(inflow, rel=1e-12)
    assert inflow == pytest.approx(0.5 * 0.075 ** 2, rel=1e-12)
    np.testing.assert_allclose(solver.velocity[:, 2], 0.5, rtol=1e-5)


def test_no_slip_column_conserves_mass_and_slows_the_gas_at_the_walls():
    mesh, solver, info = empty_column("no-slip")
    inflow = -solver.face_flux[mesh.boundary_faces["z-"]].sum()
    outflow = solver.face_flux[mesh.boundary_faces["z+"]].sum()
    assert outflow == pytest.approx(inflow, rel=1e-9)
    # every horizontal slice carries the inflow
    z = mesh.cell_centers[:, 2]
    top = mesh.face_cells[:, 0]
    for height in (0.09, 0.21):  # face planes; the owner (lower) cell's centre is half a cell below
        faces = np.nonzero(mesh.interior & (np.abs(mesh.face_normals[:, 2]) == 1) &
                           (np.abs(z[top] - (height - 0.0075)) < 1e-9))[0]
        assert len(faces) == 25
        assert solver.face_flux[faces].sum() == pytest.approx(inflow, rel=1e-8)
    x = mesh.cell_centers[:, 0]
    centre = np.abs(x - 0.0375) < 1e-9
    edge = np.abs(x - 0.0075) < 1e-9
    assert solver.velocity[centre & (z > 0.2), 2].mean() > solver.velocity[edge & (z > 0.2), 2].mean()


def test_continuity_includes_the_voidage_change():
    """Particles entering a zone (voidage falling) push gas out: outflow - inflow = -sum(d eps/dt V)."""
    mesh = GasMesh.box((4, 4, 10), (0, 0, 0), (0.06, 0.06, 0.15))
    solver = GasSolver(mesh, inlet_velocity=0.3, walls="free-slip", gravity=(0, 0, 0))
    dt = 1e-3
    zone = np.abs(mesh.cell_centers[:, 2] - 0.06) < 0.02
    solver.voidage_old[:] = 1.0
    solver.voidage[:] = 1.0
    solver.voidage[zone] = 0.98
    solver.step(dt)
    inflow = -solver.face_flux[mesh.boundary_faces["z-"]].sum()
    outflow = solver.face_flux[mesh.boundary_faces["z+"]].sum()
    displaced = ((solver.voidage_old - solver.voidage) * mesh.cell_volumes).sum() / dt
    assert outflow - inflow == pytest.approx(displaced, rel=1e-7)


def test_fixed_porous_zone_reproduces_the_ergun_pressure_drop():
    gas = GasProperties()
    mesh = GasMesh.box((5, 5, 40), (0, 0, 0), (0.075, 0.075, 0.6))
    velocity, voidage, diameter = 0.5, 0.45, 5.3e-3
    solver = GasSolver(mesh, gas, inlet_velocity=velocity, walls="free-slip", gravity=(0, 0, 0))
    z = mesh.cell_centers[:, 2]
    zone = (z > 0.15) & (z < 0.45)
    solver.voidage[zone] = voidage
    solver.voidage_old[:] = solver.voidage
    solids = 1 - voidage
    # Ergun written as an interphase coefficient on the interstitial velocity (Gidaspow's dense branch)
    solver.beta[zone] = (150 * solids ** 2 * gas.viscosity / (voidage * diameter ** 2)
                         + 1.75 * solids * gas.density * (velocity / voidage) / diameter)
    for _ in range(20):
        solver.step(0.05)
    column = (np.abs(mesh.cell_centers[:, 0] - 0.0375) < 1e-9) & (np.abs(mesh.cell_centers[:, 1] - 0.0375) < 1e-9)
    order = np.argsort(z[column])
    zc, pc = z[column][order], solver.pressure[column][order]
    inside = (zc > 0.22) & (zc < 0.38)  # away from the voidage jumps at 0.15 and 0.45 m
    slope = -np.polyfit(zc[inside], pc[inside], 1)[0]
    ergun = (150 * solids ** 2 * gas.viscosity * velocity / (voidage ** 3 * diameter ** 2)
             + 1.75 * solids * gas.density * velocity ** 2 / (voidage ** 3 * diameter))
    assert slope == pytest.approx(ergun, rel=0.01)
    # no checkerboard: the pressure is linear inside the zone (second differences vanish relative
    # to the drop per cell; a checkerboard would alternate at order one)
    second = np.diff(pc[inside], 2)
    assert np.abs(second).max() < 1e-5 * ergun * 0.015


def duct_pressure_gradient(cells):
    """Fully developed laminar flow in a square duct (side a, no-slip walls, Re = 1), grid cells x
    cells across: mean axial pressure gradient over the developed second half [Pa/m]."""
    a, length, velocity = 0.02, 0.08, 0.05
    gas = GasProperties(density=1.0, viscosity=1e-3)
    mesh = GasMesh.box((cells, cells, 16), (0, 0, 0), (a, a, length))
    solver = GasSolver(mesh, gas, inlet_velocity=velocity, walls="no-slip", gravity=(0, 0, 0))
    for _ in range(12):
        solver.step(0.05)
    z = mesh.cell_centers[:, 2]
    planes = np.unique(z[(z > 0.5 * length) & (z < 0.9 * length)])
    mean_p = [solver.pressure[np.abs(z - plane) < 1e-12].mean() for plane in planes]
    exact = 28.454 * gas.viscosity * velocity / a ** 2  # Poiseuille number f Re = 56.91 (square duct)
    return -np.polyfit(planes, mean_p, 1)[0], exact


@pytest.mark.slow
def test_square_duct_pressure_gradient_converges_at_second_order_to_the_series_solution():
    coarse, exact = duct_pressure_gradient(6)
    fine, _ = duct_pressure_gradient(12)
    error_coarse, error_fine = coarse / exact - 1, fine / exact - 1
    order = np.log(error_coarse / error_fine) / np.log(2.0)
    print(f"\nsquare duct dp/dz error: 6 cells {error_coarse:+.4f}, 12 cells {error_fine:+.4f}, order {order:.2f}")
    assert 1.7 < order < 2.3
    extrapolated = fine + (fine - coarse) / 3.0  # Richardson, second order, ratio 2
    assert extrapolated == pytest.approx(exact, rel=0.01)


@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("scheme", ["simple", "piso"])
def test_fast_path_equals_the_plain_fipy_reference_path(periodic, scheme):
    """Same time steps with systems rebuilt from plain FiPy terms and solved directly: same answer to
    solver tolerance (PISO's fast path also uses the warm-started Krylov solvers)."""
    results = []
    for assembly in ("cached", "fipy"):
        options = dict(assembly=assembly, scheme=scheme)
        if assembly == "cached" and scheme == "piso":
            options.update(linear_solver="iterative", linear_tolerance=1e-12)
        if periodic:
            mesh = GasMesh.box((3, 3, 6), (0, 0, 0), (0.045, 0.045, 0.09), (True, True, True))
            solver = GasSolver(mesh, gravity=(0, 0, 0), **options)
            solver.source[:, 2] = 5.0
            solver.source[:, 0] = 2.0 * np.sin(2 * np.pi * mesh.cell_centers[:, 2] / 0.09)
        else:
            mesh = GasMesh.box((3, 3, 6), (0, 0, 0), (0.045, 0.045, 0.09))
            solver = GasSolver(mesh, inlet_velocity=0.4, walls="no-slip", **options)
        rng = np.random.default_rng(4)
        solver.voidage[:] = solver.voidage_old[:] = rng.uniform(0.5, 1.0, mesh.cell_count)
        solver.beta[:] = rng.uniform(0.0, 300.0, mesh.cell_count)
        for _ in range(3):
            info = solver.step(5e-3)
        assert info["continuity_residual"] < 1e-6
        results.append((solver.velocity.copy(), solver.pressure.copy(), solver.face_flux.copy()))
    (u1, p1, f1), (u2, p2, f2) = results
    np.testing.assert_allclose(u1, u2, rtol=0, atol=1e-9 * np.abs(u1).max())
    np.testing.assert_allclose(p1, p2, rtol=0, atol=1e-9 * max(np.abs(p1).max(), 1e-12))
    np.testing.assert_allclose(f1, f2, rtol=0, atol=1e-9 * np.abs(f1).max())


def test_pressure_preconditioner_is_refactored_when_a_steps_iterations_pass_the_running_average():
    """The renewal rule: refactor once this step's CG iterations exceed (factorization cost + iterations
    since the factorization) / steps since it; counts only, so reproducible."""
    from fvdem.gas.solver import FACTOR_COST_ITERATIONS
    mesh = GasMesh.box((3, 3, 4), (0.0, 0.0, 0.0), (0.03, 0.03, 0.04))
    solver = GasSolver(mesh, inlet_velocity=0.1, scheme="piso", linear_solver="iterative")
    solver._pressure_lu = object()  # a factorization exists
    for since, before, this_step, due in ((5, 60, 30, True), (5, 60, 10, False), (1, 0, 500, False)):
        solver._steps_since_factor, solver._iterations_since_factor = since, before
        solver._step_iterations = this_step
        solver._plan_refactor()
        assert solver._refactor_due is due
        assert solver._iterations_since_factor == before + this_step
    assert (FACTOR_COST_ITERATIONS + 90) / 5 < 30  # the first case's arithmetic


def test_renewal_rule_refactors_a_drifting_preconditioner_and_cuts_its_cg_iterations():
    mesh = GasMesh.box((6, 6, 24), (0.0, 0.0, 0.0), (0.09, 0.09, 0.36))

    def run(rule):
        solver = GasSolver(mesh, inlet_velocity=2.0, scheme="piso", linear_solver="iterative", linear_tolerance=1e-8,
                           pressure_preconditioner="factorization")
        if not rule:
            solver._plan_refactor = lambda: None
        total = 0
        for k in range(60):
            step_drifting_bed(solver, k)
            total += solver._step_iterations
        return total, solver.factorizations

    plain, factors_plain = run(False)
    renewed, factors_renewed = run(True)
    assert factors_renewed > factors_plain
    from fvdem.gas.solver import FACTOR_COST_ITERATIONS
    assert renewed + FACTOR_COST_ITERATIONS * factors_renewed < plain + FACTOR_COST_ITERATIONS * factors_plain
