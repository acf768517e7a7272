"""The compiled Jacobi-BiCGStab of the gas momentum solves against a direct solve."""
import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fvdem.gas.krylov import bicgstab_jacobi
from fvdem.gas.mesh import GasMesh
from fvdem.gas.solver import GasSolver


def momentum_matrix():
    """A momentum matrix of the bed grid with a bed-like drag region and a convecting flux."""
    mesh = GasMesh.box((10, 10, 70), (0.0, 0.0, 0.0), (0.15, 0.15, 1.05))
    solver = GasSolver(mesh, inlet_velocity=3.0, scheme="piso", linear_solver="iterative")
    z = mesh.cell_centers[:, 2]
    beta = np.where(z < 0.3, 2e4, 0.0)
    rng = np.random.default_rng(4)
    flux = 1.2 * rng.normal(size=mesh.face_count) * mesh.face_areas
    gamma = np.full(mesh.face_count, 1.8e-5)
    a, b = solver._momentum_system(2, 1.2 * 0.5 / 5e-4 + beta, flux, gamma, np.zeros(mesh.face_count))
    return sp.csr_matrix(a), b + rng.normal(size=len(b))


def test_bicgstab_meets_its_tolerance_and_the_direct_solution():
    a, b = momentum_matrix()
    x = np.zeros(len(b))
    info, iterations = bicgstab_jacobi(a.indptr, a.indices, a.data, b, x, 1e-10, 1000)
    assert info == 0 and 0 < iterations < 100
    assert np.linalg.norm(b - a @ x) <= 1e-10 * np.linalg.norm(b)
    direct = spla.spsolve(a.tocsc(), b)
    assert np.abs(x - direct).max() <= 1e-8 * np.abs(direct).max()


def test_bicgstab_warm_start_and_failures_are_reported():
    a, b = momentum_matrix()
    exact = spla.spsolve(a.tocsc(), b)
    x = exact.copy()
    assert bicgstab_jacobi(a.indptr, a.indices, a.data, b, x, 1e-8, 1000) == (0, 0)  # already converged
    x = np.zeros(len(b))
    assert bicgstab_jacobi(a.indptr, a.indices, a.data, b, x, 1e-14, 1)[0] == 1  # iteration limit
    singular = sp.csr_matrix(np.array([[0.0, 1.0], [1.0, 2.0]]))
    assert bicgstab_jacobi(singular.indptr, singular.indices, singular.data, np.ones(2), np.zeros(2), 1e-8, 10)[0] == -1
