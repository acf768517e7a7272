"""Discrete operators of the gas equations, assembled from mesh geometry into cached sparse patterns.

Each operator knows, once, where every face or cell contributes in a fixed CSR pattern (a sparse
"scatter" matrix from per-face or per-cell coefficients to the CSR data array). Assembling the
matrix for new coefficients is then one sparse mat-vec and no allocation of structure. The
discretization is FiPy's, and ``tests/unit/test_gas_operators.py`` checks the matrices and right-hand
sides against FiPy's own terms to round-off.

Sign conventions follow FiPy's terms:
- ``diffusion(gamma_face)``: ``M phi = sum_f gamma_f A_f / d_f (phi_N - phi_P)`` (FiPy's
  ``DiffusionTerm(coeff=gamma_face)``; negative diagonal); a Dirichlet face adds
  ``-gamma_f A_f / d_f`` to the diagonal and ``-gamma_f A_f / d_f phi_b`` to the right-hand side.
- ``diagonal(coeff_cell)``: ``M = diag(coeff V)`` (FiPy's ``ImplicitSourceTerm(coeff)`` and, with
  ``coeff = rho / dt``, ``TransientTerm(rho)``; both positive on the diagonal).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from .mesh import GasMesh


def _csr_pattern(rows, cols, n):
    """CSR structure ``(indptr, indices)`` of the n x n pattern holding entries ``(rows, cols)`` and
    each entry's position in its data array (repeated entries share a position)."""
    pattern = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    pattern.sum_duplicates()
    pattern.sort_indices()
    lookup = sp.csr_matrix((np.arange(1, pattern.nnz + 1), pattern.indices, pattern.indptr), shape=(n, n))
    position = np.asarray(lookup[rows, cols]).ravel() - 1
    return pattern.indptr, pattern.indices, position


class StencilPattern:
    """The CSR structure of every cell-face operator on a ``GasMesh``: each cell's diagonal and the
    two couplings of each interior face. Operators built on one shared pattern give data arrays that
    add entry by entry, so a momentum matrix is one array sum and one CSR construction instead of
    sparse additions that re-merge the structure (``GasSolver._momentum_system``)."""

    def __init__(self, mesh: GasMesh):
        self.n = n = mesh.cell_count
        interior = np.nonzero(mesh.interior)[0]
        p, q = mesh.face_cells[interior, 0], mesh.face_cells[interior, 1]
        cells = np.arange(n)
        self.indptr, self.indices, _ = _csr_pattern(np.concatenate([cells, p, q]), np.concatenate([cells, q, p]), n)
        self._lookup = sp.csr_matrix((np.arange(1, len(self.indices) + 1), self.indices, self.indptr), shape=(n, n))
        self.diagonal_positions = self.positions(cells, cells)

    def positions(self, rows, cols):
        """Positions of entries ``(rows, cols)`` in the data array (each must be in the pattern)."""
        position = np.asarray(self._lookup[rows, cols]).ravel() - 1
        if np.any(position < 0):
            raise ValueError("entries outside the cell-face stencil")
        return position

    def matrix(self, data) -> sp.csr_matrix:
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n, self.n))

    def diagonal_data(self, values) -> np.ndarray:
        data = np.zeros(len(self.indices))
        data[self.diagonal_positions] = values
        return data


def _pattern_of(rows, cols, n, pattern):
    """``_csr_pattern`` or, with a shared ``StencilPattern``, its structure and the entries' positions."""
    if pattern is None:
        return _csr_pattern(rows, cols, n)
    return pattern.indptr, pattern.indices, pattern.positions(rows, cols)


class DiffusionOperator:
    """Face-coefficient diffusion on a ``GasMesh`` with optional Dirichlet boundary faces (on its own
    pattern, or on a shared ``StencilPattern``)."""

    def __init__(self, mesh: GasMesh, dirichlet_faces=(), pattern: StencilPattern | None = None):
        self.mesh = mesh
        n = mesh.cell_count
        interior = np.nonzero(mesh.interior)[0]
        dirichlet = np.asarray(sorted(set(int(f) for f in dirichlet_faces)), dtype=np.int64)
        if np.any(mesh.face_cells[dirichlet, 1] >= 0):
            raise ValueError("Dirichlet faces must be boundary faces")
        self.dirichlet_faces = dirichlet
        p, q = mesh.face_cells[interior, 0], mesh.face_cells[interior, 1]
        pb = mesh.face_cells[dirichlet, 0]
        # entries (row, col, face, sign): interior faces give 4 entries, Dirichlet faces 1
        rows = np.concatenate([p, q, p, q, pb])
        cols = np.concatenate([p, q, q, p, pb])
        faces = np.concatenate([interior, interior, interior, interior, dirichlet])
        signs = np.concatenate([-np.ones(2 * len(interior)), np.ones(2 * len(interior)), -np.ones(len(dirichlet))])
        self._indptr, self._indices, position = _pattern_of(rows, cols, n, pattern)
        self._scatter = sp.csr_matrix((signs, (position, faces)), shape=(len(self._indices), mesh.face_count))
        self._geometry = mesh.face_areas / mesh.face_distances
        self._rhs_scatter = sp.csr_matrix((-np.ones(len(dirichlet)), (pb, dirichlet)), shape=(n, mesh.face_count))

    def data(self, gamma_face) -> np.ndarray:
        """The CSR data array of the operator for face coefficients ``gamma_face`` (F,)."""
        return self._scatter @ (np.broadcast_to(gamma_face, self._geometry.shape) * self._geometry)

    def matrix(self, gamma_face) -> sp.csr_matrix:
        """The operator for face coefficients ``gamma_face`` (F,)."""
        n = self.mesh.cell_count
        return sp.csr_matrix((self.data(gamma_face), self._indices, self._indptr), shape=(n, n))

    def rhs(self, gamma_face, boundary_value_face) -> np.ndarray:
        """Right-hand side from Dirichlet values ``boundary_value_face`` (F,; read on Dirichlet faces)."""
        weights = np.broadcast_to(gamma_face, self._geometry.shape) * self._geometry
        return self._rhs_scatter @ (weights * boundary_value_face)


def diagonal(mesh: GasMesh, coeff_cell) -> sp.dia_matrix:
    """``diag(coeff V)``: FiPy's ``ImplicitSourceTerm(coeff)`` (and ``TransientTerm`` with coeff/dt)."""
    values = np.broadcast_to(coeff_cell, mesh.cell_volumes.shape) * mesh.cell_volumes
    return sp.diags(values, format="csr")


class UpwindConvectionOperator:
    """First-order upwind convection ``div(F phi)`` from face volume fluxes ``F = (u . n) A`` [m^3/s]
    (n from a face's first cell to its second; outward on the boundary).

    Interior faces carry ``F phi_upwind`` out of the first cell into the second. Boundary faces are
    closed unless listed: ``inflow_faces`` bring ``F phi_b`` in (Dirichlet value on the right-hand
    side), ``outflow_faces`` carry ``F phi_P`` out (the top of a column; FiPy's convection term leaves
    unconstrained boundary faces closed, so an outflow must be added explicitly).
    """

    def __init__(self, mesh: GasMesh, inflow_faces=(), outflow_faces=(), pattern: StencilPattern | None = None):
        self.mesh = mesh
        n = mesh.cell_count
        interior = np.nonzero(mesh.interior)[0]
        p, q = mesh.face_cells[interior, 0], mesh.face_cells[interior, 1]
        self.inflow_faces = np.asarray(sorted(set(int(f) for f in inflow_faces)), dtype=np.int64)
        self.outflow_faces = np.asarray(sorted(set(int(f) for f in outflow_faces)), dtype=np.int64)
        po = mesh.face_cells[self.outflow_faces, 0]
        # entries: (P,P,+F+), (P,N,+F-), (N,N,-F-), (N,P,-F+), outflow (P,P,+F)
        rows = np.concatenate([p, p, q, q, po])
        cols = np.concatenate([p, q, q, p, po])
        self._indptr, self._indices, position = _pattern_of(rows, cols, n, pattern)
        nnz = len(self._indices)
        m = len(interior)
        k = len(self.outflow_faces)
        f_all = mesh.face_count
        self._scatter_plus = sp.csr_matrix(
            (np.concatenate([np.ones(m), -np.ones(m), np.ones(k)]),
             (np.concatenate([position[:m], position[3 * m:4 * m], position[4 * m:]]),
              np.concatenate([interior, interior, self.outflow_faces]))), shape=(nnz, f_all))
        self._scatter_minus = sp.csr_matrix(
            (np.concatenate([np.ones(m), -np.ones(m), np.ones(k)]),
             (np.concatenate([position[m:2 * m], position[2 * m:3 * m], position[4 * m:]]),
              np.concatenate([interior, interior, self.outflow_faces]))), shape=(nnz, f_all))
        pi = mesh.face_cells[self.inflow_faces, 0]
        self._rhs_scatter = sp.csr_matrix((-np.ones(len(pi)), (pi, self.inflow_faces)), shape=(n, f_all))

    def data(self, face_flux) -> np.ndarray:
        """The CSR data array of the operator for face volume fluxes ``face_flux`` (F,)."""
        return self._scatter_plus @ np.maximum(face_flux, 0.0) + self._scatter_minus @ np.minimum(face_flux, 0.0)

    def matrix(self, face_flux) -> sp.csr_matrix:
        """The operator for face volume fluxes ``face_flux`` (F,) [m^3/s] (or mass fluxes)."""
        n = self.mesh.cell_count
        return sp.csr_matrix((self.data(face_flux), self._indices, self._indptr), shape=(n, n))

    def rhs(self, face_flux, boundary_value_face) -> np.ndarray:
        """Right-hand side of the inflow faces: ``-F phi_b`` (F < 0 flows in)."""
        return self._rhs_scatter @ (face_flux * boundary_value_face)
