"""The compiled Gauss sums of the gas solver against their sparse-matrix reference."""
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
