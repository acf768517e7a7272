"""The compiled passes of the gas solver (Gauss sums, corrector faces, momentum assembly) against their
sparse-matrix and numpy references."""
import numpy as np
import pytest

from fvdem.gas.mesh import GasMesh
from fvdem.gas.solver import GasSolver


@pytest.mark.parametrize("periodic", [False, True])
def test_gauss_gradient_is_the_sparse_divergence_of_the_face_fluxes(periodic):
    mesh = GasMesh.box((5, 4, 6), (0.0, 0.0, 0.0), (0.05, 0.04, 0.09), periodic=(periodic,) * 3)
    solver = GasSolver(mesh)
    face_p = np.random.default_rng(3).normal(size=mesh.face_count) * 100.0
    got = solver._gauss_gradient(face_p)
    expected = solver._gauss_gradient_reference(face_p)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-13 * np.abs(expected).max())
    if periodic:  # one value per face: the volume-weighted gradients cancel (momentum conserved)
        total = (got * mesh.cell_volumes[:, None]).sum(axis=0)
        assert np.abs(total).max() <= 1e-12 * np.abs(face_p).max() * mesh.face_areas.max()
    else:  # a uniform face pressure has no gradient inside; the wall faces see it
        uniform = solver._gauss_gradient(np.full(mesh.face_count, 7.0))
        np.testing.assert_allclose(uniform, solver._gauss_gradient_reference(np.full(mesh.face_count, 7.0)),
                                   rtol=0, atol=1e-12)


@pytest.mark.parametrize("periodic", [False, True])
def test_predicted_fluxes_are_the_numpy_rhie_chow_fluxes(periodic):
    """The compiled face pass against the numpy reference, on random cell fields with a voidage and
    drag contrast of a bed (k spanning 100x), an old flux and a pressure field."""
    mesh = GasMesh.box((5, 4, 6), (0.0, 0.0, 0.0), (0.05, 0.04, 0.09), periodic=(periodic,) * 3)
    solver = GasSolver(mesh, inlet_velocity=0.0 if periodic else 1.3)
    rng = np.random.default_rng(11)
    n = mesh.cell_count
    d_cell = np.exp(rng.uniform(np.log(1e-7), np.log(1e-5), n))
    k_cell = rng.uniform(0.4, 1.0, n) * d_cell
    c = rng.normal(size=(n, 3))
    solver.pressure = rng.normal(size=n) * 50.0
    old = (rng.normal(size=mesh.face_count), rng.normal(size=(n, 3)))
    got = solver._predicted_fluxes(2e-4, d_cell, k_cell, c, old)
    expected = solver._predicted_fluxes_reference(2e-4, d_cell, k_cell, c, old)
    for a, b in zip(got, expected):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-13 * np.abs(b).max())
    if not periodic:  # the fixed inlet flux and the closed walls
        assert np.all(got[0][solver._inlet] == solver._inlet_flux)
        assert np.all(got[0][solver._walls] == 0.0)


@pytest.mark.parametrize("periodic", [False, True])
def test_face_pressures_are_the_numpy_face_pressures(periodic):
    mesh = GasMesh.box((5, 4, 6), (0.0, 0.0, 0.0), (0.05, 0.04, 0.09), periodic=(periodic,) * 3)
    solver = GasSolver(mesh, inlet_velocity=0.0 if periodic else 1.3)
    rng = np.random.default_rng(12)
    n = mesh.cell_count
    k_cell = np.exp(rng.uniform(np.log(1e-8), np.log(1e-6), n))
    solver.face_flux = rng.normal(size=mesh.face_count) * 1e-4
    c_normal = (rng.normal(size=mesh.face_count), rng.normal(size=mesh.face_count))
    pressure = rng.normal(size=n) * 50.0
    got = solver._face_pressure(pressure, c_normal, k_cell)
    expected = solver._face_pressure_reference(pressure, c_normal, k_cell)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-13 * np.abs(expected).max())


@pytest.mark.parametrize("periodic", [False, True])
def test_corrected_fluxes_are_the_numpy_correction(periodic):
    """The fluxes after a pressure correction: ``phi - k_f A (p'_N - p'_P) / d`` (the outlet's p' = 0),
    the fixed fluxes of walls and inlet kept, bit for bit as the numpy form with ``_face_difference``."""
    from fvdem.gas.face_kernels import corrected_fluxes
    mesh = GasMesh.box((5, 4, 6), (0.0, 0.0, 0.0), (0.05, 0.04, 0.09), periodic=(periodic,) * 3)
    solver = GasSolver(mesh, inlet_velocity=0.0 if periodic else 1.3)
    rng = np.random.default_rng(13)
    flux = rng.normal(size=mesh.face_count) * 1e-4
    k_face = np.exp(rng.uniform(np.log(1e-8), np.log(1e-6), mesh.face_count))
    correction = rng.normal(size=mesh.cell_count) * 20.0
    numpy_correction = -k_face * mesh.face_areas * solver._face_difference(correction)
    numpy_correction[solver._closed] = 0.0
    numpy_correction[solver._inlet] = 0.0
    got = corrected_fluxes(solver._face_kind, solver._face_first, solver._face_second, mesh.face_areas,
                           mesh.face_distances, k_face, flux, correction)
    assert np.array_equal(got, flux + numpy_correction)


@pytest.mark.parametrize("walls, periodic", [("no-slip", False), ("free-slip", False), ("no-slip", True)])
def test_momentum_systems_are_the_cached_operator_systems(walls, periodic):
    """The compiled assembly of the three momentum systems against the sparse scatter operators, entry
    by entry, on random fluxes (both signs), a drag region, Dirichlet inlet values and an explicit
    right-hand side: the Dirichlet faces (inlet, and the walls of the components they hold) are the
    only entries that differ between components."""
    mesh = GasMesh.box((5, 4, 6), (0.0, 0.0, 0.0), (0.05, 0.04, 0.09), periodic=(periodic,) * 3)
    solver = GasSolver(mesh, inlet_velocity=0.0 if periodic else 1.3, walls=walls)
    rng = np.random.default_rng(5)
    n, nf = mesh.cell_count, mesh.face_count
    implicit = 1.2 * rng.uniform(0.4, 1.0, n) / 5e-4 + rng.uniform(0.0, 3e4, n)
    mass_flux = 1.2 * rng.normal(size=nf) * mesh.face_areas
    gamma = 1.568e-5 * rng.uniform(0.4, 1.0, nf)
    boundary = rng.normal(size=(nf, 3))
    explicit = rng.normal(size=(n, 3)) * 1e3
    data, rhs, diagonal = solver._momentum_tables.assemble(mesh.cell_volumes, implicit, mass_flux,
                                                           gamma * solver._face_geometry, boundary, explicit)
    for c in range(3):
        a, b = solver._momentum_system(c, implicit, mass_flux, gamma, boundary[:, c])
        a = a.toarray()
        got = solver._stencil.matrix(data[c]).toarray()
        np.testing.assert_allclose(got, a, rtol=0, atol=1e-12 * np.abs(a).max())
        np.testing.assert_allclose(diagonal[:, c], np.diag(a), rtol=0, atol=1e-12 * np.abs(a).max())
        expected = b + explicit[:, c] * mesh.cell_volumes
        np.testing.assert_allclose(rhs[:, c], expected, rtol=0, atol=1e-12 * np.abs(expected).max())
    if not periodic and walls == "free-slip":  # an x wall holds u_x only: its conductance on u_x's diagonal
        faces = mesh.boundary_faces["x-"]
        y_walls = np.concatenate([mesh.face_cells[mesh.boundary_faces[s], 0] for s in ("y-", "y+")])
        keep = ~np.isin(mesh.face_cells[faces, 0], y_walls)
        faces = faces[keep]
        position = solver._momentum_tables.diagonal[mesh.face_cells[faces, 0]]
        np.testing.assert_allclose(data[0][position] - data[1][position], (gamma * solver._face_geometry)[faces],
                                   rtol=1e-9)
        np.testing.assert_array_equal(data[1][position], data[2][position])
