"""The gas momentum predictor's three linear systems, assembled in one compiled pass.

Each velocity component's system is ``diag(a V) + div(m u) - div(gamma grad u)`` (``a = rho eps / dt +
beta``, ``m`` the face mass fluxes, first-order upwind; FiPy's discretization, ``operators.py``) with the
component's Dirichlet faces (inlet, walls) and the outlet's outflow, and the right-hand side
``(rho eps_old u_old / dt + S + rho eps g - eps grad p) V`` plus the boundary values. The three systems
share every entry but the Dirichlet faces' diagonal terms, so the shared part is built once and copied.

The entries land in the CSR data array of the solver's shared ``StencilPattern`` at positions computed
once (``MomentumTables``); the cached-operator form (``GasSolver._momentum_system``, sparse scatter
products) is the reference the tests compare this with to round-off.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit


@dataclass(frozen=True)
class MomentumTables:
    """Where each face and cell contributes in the shared CSR pattern (all int64 arrays).

    ``interior``: interior faces, with the positions of their entries ``(P, P)``, ``(P, N)``,
    ``(N, N)``, ``(N, P)``; ``outflow``/``outflow_position``: outlet faces and their cell's diagonal;
    ``inflow``/``inflow_cell``: inlet faces and their cell; ``dirichlet``, ``dirichlet_cell``,
    ``dirichlet_position``, ``dirichlet_component``: one row per (face, component) with a fixed value;
    ``diagonal``: each cell's diagonal position; ``nnz``: the data array's length."""

    interior: np.ndarray
    pp: np.ndarray
    pn: np.ndarray
    nn: np.ndarray
    np_: np.ndarray
    outflow: np.ndarray
    outflow_position: np.ndarray
    inflow: np.ndarray
    inflow_cell: np.ndarray
    dirichlet: np.ndarray
    dirichlet_cell: np.ndarray
    dirichlet_position: np.ndarray
    dirichlet_component: np.ndarray
    diagonal: np.ndarray
    nnz: int

    @classmethod
    def build(cls, mesh, pattern, inflow_faces, outflow_faces, dirichlet_faces_per_component):
        """Tables for ``mesh`` on the ``StencilPattern`` ``pattern``; ``dirichlet_faces_per_component``:
        three arrays of boundary faces with a fixed velocity component."""
        as_int = lambda a: np.ascontiguousarray(a, dtype=np.int64)  # noqa: E731
        interior = np.nonzero(mesh.interior)[0]
        p, q = mesh.face_cells[interior, 0], mesh.face_cells[interior, 1]
        inflow, outflow = as_int(inflow_faces), as_int(outflow_faces)
        cells = np.arange(mesh.cell_count)
        diagonal = pattern.positions(cells, cells)
        faces = [as_int(f) for f in dirichlet_faces_per_component]
        dirichlet = np.concatenate(faces)
        component = np.concatenate([np.full(len(f), c) for c, f in enumerate(faces)])
        dirichlet_cell = mesh.face_cells[dirichlet, 0]
        return cls(as_int(interior), as_int(pattern.positions(p, p)), as_int(pattern.positions(p, q)),
                   as_int(pattern.positions(q, q)), as_int(pattern.positions(q, p)), outflow,
                   as_int(diagonal[mesh.face_cells[outflow, 0]]), inflow, as_int(mesh.face_cells[inflow, 0]),
                   as_int(dirichlet), as_int(dirichlet_cell), as_int(diagonal[dirichlet_cell]), as_int(component),
                   as_int(diagonal), len(pattern.indices))

    def assemble(self, volumes, implicit, mass_flux, conductance, boundary_value, explicit_density):
        """``(data (3, nnz), rhs (C, 3), diagonal (C, 3))``: see ``momentum_systems``."""
        return momentum_systems(self.nnz, self.diagonal, self.interior, self.pp, self.pn, self.nn, self.np_,
                                self.outflow, self.outflow_position, self.inflow, self.inflow_cell,
                                self.dirichlet, self.dirichlet_cell, self.dirichlet_position,
                                self.dirichlet_component, volumes, implicit, mass_flux, conductance,
                                boundary_value, explicit_density)


@njit(cache=True)
def momentum_systems(nnz, diagonal, interior, pp, pn, nn, np_, outflow, outflow_position, inflow, inflow_cell,
                     dirichlet, dirichlet_cell, dirichlet_position, dirichlet_component, volumes, implicit,
                     mass_flux, conductance, boundary_value, explicit_density):
    """The three momentum systems on the shared CSR pattern.

    ``implicit`` (C,) [kg/(m^3 s)]: ``rho eps / dt + beta``; ``mass_flux`` (F,) [kg/s]: ``rho phi``;
    ``conductance`` (F,) [kg/s]: ``gamma_f A_f / d_f`` (``gamma = mu eps_f``); ``boundary_value``
    (F, 3) [m/s]: the fixed velocity on Dirichlet and inflow faces; ``explicit_density`` (C, 3)
    [N/m^3]: the explicit right-hand side per unit volume. Returns ``(data, rhs, diagonal)``: the CSR
    data of each component's matrix (3, nnz), the right-hand sides (C, 3) and the diagonals (C, 3)."""
    n = len(volumes)
    base = np.zeros(nnz)
    for c in range(n):
        base[diagonal[c]] += implicit[c] * volumes[c]
    for i in range(len(interior)):
        f = interior[i]
        plus = max(mass_flux[f], 0.0)
        minus = min(mass_flux[f], 0.0)
        g = conductance[f]
        base[pp[i]] += plus + g
        base[np_[i]] -= plus + g
        base[pn[i]] += minus - g
        base[nn[i]] += g - minus
    for i in range(len(outflow)):
        base[outflow_position[i]] += mass_flux[outflow[i]]
    data = np.empty((3, nnz))
    for component in range(3):
        data[component, :] = base
    rhs = np.empty((n, 3))
    for c in range(n):
        for component in range(3):
            rhs[c, component] = explicit_density[c, component] * volumes[c]
    for k in range(len(dirichlet)):
        f, component = dirichlet[k], dirichlet_component[k]
        data[component, dirichlet_position[k]] += conductance[f]
        rhs[dirichlet_cell[k], component] += conductance[f] * boundary_value[f, component]
    for i in range(len(inflow)):
        f = inflow[i]
        for component in range(3):
            rhs[inflow_cell[i], component] -= mass_flux[f] * boundary_value[f, component]
    diag = np.empty((n, 3))
    for c in range(n):
        for component in range(3):
            diag[c, component] = data[component, diagonal[c]]
    return data, rhs, diag
