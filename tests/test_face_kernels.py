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
