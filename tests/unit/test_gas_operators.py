"""The cached-pattern operators equal FiPy's term matrices (FiPy defines the discretization)."""
import fipy as fp
import numpy as np
import pytest
import scipy.sparse as sp

from fvdem.gas.mesh import GasMesh
from fvdem.gas.operators import DiffusionOperator, StencilPattern, UpwindConvectionOperator, diagonal


def fipy_matrix_and_rhs(term, var):
    term.cacheMatrix()
    term.cacheRHSvector()
    term.sweep(var=var)
    return sp.csr_matrix(term.matrix.matrix), np.asarray(term.RHSvector)


GRIDS = {
    "small walled": ((4, 3, 5), (0.0, 0.0, 0.0), (0.06, 0.045, 0.075), (False, False, False)),
    "bed 10x10x70": ((10, 10, 70), (0.0, 0.0, 0.0), (0.15, 0.15, 1.05), (False, False, False)),
    "periodic box": ((4, 4, 8), (0.0, 0.0, 0.0), (0.04, 0.04, 0.08), (True, True, True)),
}


@pytest.mark.parametrize("name", GRIDS)
def test_mesh_adapter_geometry(name):
    shape, lower, upper, periodic = GRIDS[name]
    mesh = GasMesh.box(shape, lower, upper, periodic)
    assert mesh.cell_count == np.prod(shape)
    assert mesh.cell_volumes.sum() == pytest.approx(np.prod(np.subtract(upper, lower)))
    if not any(periodic):
        # every cell is closed: the outward area vectors of its faces sum to zero
        closure = np.zeros((mesh.cell_count, 3))
        area_vectors = mesh.face_areas[:, None] * mesh.face_normals
        np.add.at(closure, mesh.face_cells[:, 0], area_vectors)
        inner = mesh.interior
        np.add.at(closure, mesh.face_cells[inner, 1], -area_vectors[inner])
        assert np.abs(closure).max() < 1e-12
    else:
        # every cell is joined to six neighbours (one copy of each periodic face joins the end cells)
        links = np.bincount(mesh.face_cells[mesh.interior].ravel(), minlength=mesh.cell_count)
        assert (links == 6).all()
    for side, normal in zip(("x-", "x+", "y-", "y+", "z-", "z+"), np.repeat(np.eye(3), 2, axis=0) *
                            np.tile([-1, 1], 3)[:, None]):
        faces = mesh.boundary_faces[side]
        if all(periodic):
            assert len(faces) == 0
        else:
            np.testing.assert_allclose(mesh.face_normals[faces], np.tile(normal, (len(faces), 1)), atol=1e-12)


@pytest.mark.parametrize("name", GRIDS)
def test_diffusion_operator_equals_fipy(name):
    shape, lower, upper, periodic = GRIDS[name]
    mesh = GasMesh.box(shape, lower, upper, periodic)
    rng = np.random.default_rng(1)
    gamma = rng.uniform(0.5, 2.0, mesh.face_count) * 1.8e-5
    dirichlet = {} if all(periodic) else {"z+": 101325.0, "x-": 7.0}
    phi = fp.CellVariable(mesh=mesh.fipy_mesh, value=0.0)
    boundary_value = np.zeros(mesh.face_count)
    faces = []
    for side, value in dirichlet.items():
        f = mesh.boundary_faces[side]
        mask = np.zeros(mesh.face_count, bool)
        mask[f] = True
        phi.constrain(value, where=mask)
        boundary_value[f] = value
        faces.extend(f)
    reference, reference_rhs = fipy_matrix_and_rhs(fp.DiffusionTerm(coeff=fp.FaceVariable(mesh=mesh.fipy_mesh,
                                                                                          value=gamma)), phi)
    op = DiffusionOperator(mesh, faces)
    fast = op.matrix(gamma)
    scale = abs(reference).max()
    assert abs(fast - reference).max() <= 1e-13 * scale
    np.testing.assert_allclose(op.rhs(gamma, boundary_value), reference_rhs,
                               atol=1e-13 * max(1.0, np.abs(reference_rhs).max()))
    # a new coefficient reuses the cached pattern
    gamma2 = rng.uniform(0.5, 2.0, mesh.face_count)
    reference2, _ = fipy_matrix_and_rhs(fp.DiffusionTerm(coeff=fp.FaceVariable(mesh=mesh.fipy_mesh, value=gamma2)),
                                        phi)
    assert abs(op.matrix(gamma2) - reference2).max() <= 1e-13 * abs(reference2).max()


def test_transient_and_implicit_source_equal_fipy():
    mesh = GasMesh.box((5, 4, 6), (0, 0, 0), (0.05, 0.04, 0.06))
    rng = np.random.default_rng(2)
    coeff = rng.uniform(0.1, 1.0, mesh.cell_count)
    phi = fp.CellVariable(mesh=mesh.fipy_mesh, value=rng.normal(size=mesh.cell_count))
    source, _ = fipy_matrix_and_rhs(fp.ImplicitSourceTerm(coeff=fp.CellVariable(mesh=mesh.fipy_mesh, value=coeff)),
                                    phi)
    assert abs(diagonal(mesh, coeff) - source).max() <= 1e-14 * abs(source).max()
    dt = 1e-4
    transient_term = fp.TransientTerm(coeff=fp.CellVariable(mesh=mesh.fipy_mesh, value=coeff))
    transient_term.cacheMatrix()
    transient_term.sweep(var=phi, dt=dt)
    transient = sp.csr_matrix(transient_term.matrix.matrix)
    assert abs(diagonal(mesh, coeff / dt) - transient).max() <= 1e-14 * abs(transient).max()


@pytest.mark.parametrize("name", ["small walled", "periodic box"])
def test_upwind_convection_equals_fipy(name):
    shape, lower, upper, periodic = GRIDS[name]
    mesh = GasMesh.box(shape, lower, upper, periodic)
    rng = np.random.default_rng(3)
    velocity = rng.normal(size=(3, mesh.face_count))
    flux = np.einsum("fi,if->f", mesh.face_normals, velocity) * mesh.face_areas
    phi = fp.CellVariable(mesh=mesh.fipy_mesh, value=0.0)
    inflow = []
    boundary_value = np.zeros(mesh.face_count)
    if not all(periodic):
        bottom = mesh.boundary_faces["z-"]
        velocity[:, bottom] = [[0.0], [0.0], [1.5]]  # into the domain through z = 0
        flux = np.einsum("fi,if->f", mesh.face_normals, velocity) * mesh.face_areas
        mask = np.zeros(mesh.face_count, bool)
        mask[bottom] = True
        phi.constrain(2.0, where=mask)
        boundary_value[bottom] = 2.0
        inflow = bottom
        # FiPy's convection term carries nothing through unconstrained boundary faces
        closed = np.nonzero(~mesh.interior)[0]
        closed = closed[~np.isin(closed, bottom)]
        velocity[:, closed] = 0.0
        flux[closed] = 0.0
    # FiPy's sweep also solves: a dominant implicit source (known diagonal) keeps the system regular
    term = (fp.UpwindConvectionTerm(coeff=fp.FaceVariable(mesh=mesh.fipy_mesh, rank=1, value=velocity))
            + fp.ImplicitSourceTerm(coeff=1e3))
    reference, reference_rhs = fipy_matrix_and_rhs(term, phi)
    op = UpwindConvectionOperator(mesh, inflow_faces=inflow)
    fast = op.matrix(flux) + diagonal(mesh, 1e3)
    assert abs(fast - reference).max() <= 1e-12 * abs(reference).max()
    np.testing.assert_allclose(op.rhs(flux, boundary_value), reference_rhs, atol=1e-12 * np.abs(flux).max())


def test_upwind_convection_conserves_and_outflow_closes_the_balance():
    """Columns sum to the net boundary outflow: with a uniform plug flow through the column (in at
    z-, out at z+) a uniform phi is steady (div(F phi) = 0 after the inflow right-hand side)."""
    mesh = GasMesh.box((3, 3, 6), (0, 0, 0), (0.045, 0.045, 0.09))
    flux = mesh.face_normals[:, 2] * mesh.face_areas * 0.7  # u = 0.7 m/s upward everywhere
    walls = np.concatenate([mesh.boundary_faces[s] for s in ("x-", "x+", "y-", "y+")])
    flux[walls] = 0.0
    op = UpwindConvectionOperator(mesh, inflow_faces=mesh.boundary_faces["z-"],
                                  outflow_faces=mesh.boundary_faces["z+"])
    phi_b = np.full(mesh.face_count, 3.0)
    residual = op.matrix(flux) @ np.full(mesh.cell_count, 3.0) - op.rhs(flux, phi_b)
    assert np.abs(residual).max() <= 1e-14 * np.abs(flux).max() * 3.0


@pytest.mark.parametrize("name", GRIDS)
def test_shared_stencil_gives_the_same_momentum_matrix(name):
    """Operators on one ``StencilPattern`` add data arrays entry by entry: the momentum matrix built
    that way equals the sparse sum of the operators on their own patterns, exactly."""
    shape, lower, upper, periodic = GRIDS[name]
    mesh = GasMesh.box(shape, lower, upper, periodic)
    rng = np.random.default_rng(2)
    gamma = rng.uniform(1e-5, 2e-5, mesh.face_count)
    flux = rng.normal(size=mesh.face_count) * mesh.face_areas
    implicit = rng.uniform(1.0, 5.0, mesh.cell_count)
    boundary = np.nonzero(~mesh.interior)[0]
    dirichlet, outflow = boundary[::2], boundary[1::3]
    stencil = StencilPattern(mesh)
    alone = (diagonal(mesh, implicit) + UpwindConvectionOperator(mesh, outflow_faces=outflow).matrix(flux)
             - DiffusionOperator(mesh, dirichlet).matrix(gamma))
    shared = stencil.matrix(stencil.diagonal_data(implicit * mesh.cell_volumes)
                            + UpwindConvectionOperator(mesh, outflow_faces=outflow, pattern=stencil).data(flux)
                            - DiffusionOperator(mesh, dirichlet, stencil).data(gamma))
    assert abs(shared - alone).max() == 0.0
