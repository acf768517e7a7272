"""Volume-averaged gas flow ("model A", docs/equations.md §2) with a collocated SIMPLE pressure-velocity coupling.

Equations (gas density rho constant, interstitial velocity u, voidage eps):

    d(eps)/dt + div(eps u) = 0
    rho d(eps u)/dt + div(rho eps u u) = -eps grad p + div(mu eps grad u) - beta u + S + rho eps g

``beta`` [kg/(m^3 s)] is the implicit interphase coefficient and ``S`` [N/m^3] the explicit source per
cell that the coupling bridge fills (the Eq. 8 sink written semi-implicitly as ``beta (v_p - u)``
gives ``S = beta v_p``). Discretization: FiPy's finite volumes (``operators``), first-order upwind
convection of momentum, implicit Euler in time.

Coupling (SIMPLE or PISO with a drag-aware Rhie-Chow momentum interpolation): with ``a_P`` the
momentum diagonal, ``D = eps V / a_P`` and ``k = eps D``, cell velocities obey
``eps u = eps u_hat - k grad p``. Each half cell between a cell centre and a face is a resistance
``1 / k`` (``beta`` sits in ``a_P``), so the face flux is that of two resistances in series,
``phi_f = A_f [(w c_P + (1 - w) c_N) . n + (time-step correction) - k_f (p_N - p_P) / d_f]`` with
``c = eps u_hat``, ``k_f`` the harmonic mean of ``k_P, k_N`` and ``w = k_N / (k_P + k_N)``; and the cell
pressure gradient is the Gauss sum of the face pressures both half cells reach at their own gradient
(``_face_pressure``), so that the cell velocity equals the mean of its faces' fluxes per axis. Plain
arithmetic face means (the textbook Rhie-Chow) let a dense cell next to a loose one carry up to
``(1 + k_loose / k_dense) / 2`` times the velocity continuity allows (tenfold in fluidized beds) and
underestimate the pressure drop of a heterogeneous bed. The pressure correction ``p'`` solves
``div(k_f grad p') = sum_f phi*_f + (eps - eps_old) V / dt`` so that the corrected fluxes satisfy
the continuity equation including the voidage change; SIMPLE's outer iterations repeat momentum and
correction until both the continuity residual (relative to the largest face flux) and the relative
velocity change of an iteration are below ``tolerance``.

Boundaries of a walled column: walls (no-slip or free-slip), a uniform inlet of superficial velocity
``U`` on ``z-`` (distributor), a fixed pressure outlet ``p = 0`` on ``z+``. A fully periodic box
has none; its pressure is fixed to zero mean (a body force drives the flow, through ``S``).
"""
from __future__ import annotations

from dataclasses import dataclass
from time import perf_counter

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .mesh import GasMesh, fipy_momentum_system, fipy_pressure_system
from ..timing import Timings
from . import multigrid
from . import face_kernels
from .face_kernels import corrected_fluxes, face_pressures, gauss_gradient, predicted_fluxes
from .krylov import bicgstab_jacobi
from .momentum_kernels import MomentumTables
from .operators import DiffusionOperator, StencilPattern, UpwindConvectionOperator


# under-relaxation of the predictor's deferred gradient correction (see ``gradient_correction``): the
# face pressures depend on ``eps u_hat``, so taking their gradient in full from the previous iteration
# feeds the neighbour coupling back with gain ``h / (1 - h)`` (``h`` = off-diagonal / diagonal of the
# momentum matrix) and diverges for ``h > 1/2`` (a 12 x 12 square duct in SIMPLE); half of the change
# per correction is stable for gains below 3
# cost of one pressure-preconditioner factorization in CG iterations it replaces (10 x 10 x 70 grid:
# the factorization 28 ms, a CG iteration with its LU solve 0.7 ms; measured 2026-12-01)
FACTOR_COST_ITERATIONS = 40
GRADIENT_RELAXATION = 0.5


@dataclass(frozen=True)
class GasProperties:
    density: float = 1.2          # kg/m^3
    viscosity: float = 1.568e-5   # Pa s


class GasSolver:
    """Gas velocity, pressure and face fluxes on a ``GasMesh`` (state as numpy arrays).

    ``velocity`` (C, 3) [m/s] interstitial; ``pressure`` (C,) [Pa] (relative to the outlet);
    ``face_flux`` (F,) [m^3/s] gas volume flux ``eps u . n A``; ``voidage`` (C,) and
    ``voidage_old`` (C,); ``beta`` (C,) [kg/(m^3 s)]; ``source`` (C, 3) [N/m^3].

    ``assembly="cached"`` builds the linear systems from the cached-pattern operators (fast);
    ``assembly="fipy"`` rebuilds them from plain FiPy terms every iteration (the reference path,
    kept to test the fast one against).
    """

    def __init__(self, mesh: GasMesh, gas: GasProperties = GasProperties(), gravity=(0.0, 0.0, -9.81),
                 inlet_velocity: float = 0.0, walls: str = "no-slip", relax_velocity: float = 0.7,
                 relax_pressure: float = 0.3, tolerance: float = 1e-8, max_iterations: int = 200,
                 assembly: str = "cached", scheme: str = "simple", correctors: int = 2,
                 linear_solver: str = "direct", linear_tolerance: float = 1e-10,
                 pressure_preconditioner: str = "multigrid", corrector_tolerance: float | None = None):
        self.timings = Timings()  # momentum and pressure phases (a Model shares one)
        self.mesh = mesh
        self.gas = gas
        self.gravity = np.asarray(gravity, float)
        self.inlet_velocity = float(inlet_velocity)
        self.relax_velocity = relax_velocity
        self.relax_pressure = relax_pressure
        self.tolerance = tolerance
        self.max_iterations = max_iterations
        if assembly not in ("cached", "fipy"):
            raise ValueError(f"assembly = {assembly!r}: expected 'cached' or 'fipy'")
        self.assembly = assembly
        if scheme not in ("simple", "piso"):
            raise ValueError(f"scheme = {scheme!r}: expected 'simple' or 'piso'")
        if linear_solver not in ("direct", "iterative"):
            raise ValueError(f"linear_solver = {linear_solver!r}: expected 'direct' or 'iterative'")
        if pressure_preconditioner not in ("multigrid", "factorization"):
            raise ValueError(f"pressure_preconditioner = {pressure_preconditioner!r}: expected 'multigrid' or "
                             "'factorization'")
        self.scheme, self.correctors = scheme, int(correctors)
        self.linear_solver, self.linear_tolerance = linear_solver, float(linear_tolerance)
        # relative tolerance of the pressure solves of every PISO corrector but the last (OpenFOAM's
        # ``p`` relTol against ``pFinal``): the next corrector starts from their error, so only the
        # last one needs ``linear_tolerance``; None: every corrector at ``linear_tolerance``
        self.corrector_tolerance = None if corrector_tolerance is None else float(corrector_tolerance)
        n, f = mesh.cell_count, mesh.face_count
        self.periodic = all(mesh.periodic)
        self.velocity = np.zeros((n, 3))
        self.pressure = np.zeros(n)
        self.face_flux = np.zeros(f)
        # face pressure [Pa] of the last pressure correction, drag-aware (see ``_face_pressure``); the
        # cell pressure gradient is its Gauss sum. None until the first correction (then the linear
        # interpolation of the cell pressures, extrapolated to the inlet, stands in)
        self.face_pressure = None
        # deferred correction of the momentum predictor's pressure gradient [Pa/m] (C, 3): the
        # drag-aware gradient of the last correction less the linear-interpolation one, relaxed. At
        # convergence (SIMPLE) the predictor and the recovered velocity use the same single-valued
        # face pressures, so the discrete momentum balance closes and the mixture momentum of a
        # periodic box is conserved to round-off
        self.gradient_correction = np.zeros((n, 3))
        self._face_gradient = None  # Gauss gradient of face_pressure, from the last correction
        self.voidage = np.ones(n)
        self.voidage_old = np.ones(n)
        self.beta = np.zeros(n)
        self.source = np.zeros((n, 3))
        self.iterations = 0
        self.direct_fallbacks = 0  # iterative solves that fell back to a direct solve
        self.factorizations = 0  # pressure-preconditioner factorizations
        self.refactor_interval = 200  # at most this many steps between factorizations
        self._iterations_since_factor = 0  # CG iterations preconditioned by the current factorization
        self._step_iterations = 0  # CG iterations of the current step
        self._refactor_due = False
        self._pressure_lu = None
        self._pressure_factor_matrix = None
        self._steps_since_factor = 0
        b = mesh.boundary_faces
        self._inlet = b["z-"]
        self._outlet = b["z+"]
        wall_sides = {"x-": 0, "x+": 0, "y-": 1, "y+": 1}
        self._walls = np.concatenate([b[s] for s in wall_sides]) if not self.periodic else np.zeros(0, int)
        # Dirichlet velocity faces per component: inlet always; walls: all components (no-slip) or the
        # normal component only (free-slip)
        self._velocity_dirichlet = []
        for c in range(3):
            faces = [self._inlet]
            for side, axis in wall_sides.items():
                if walls == "no-slip" or axis == c:
                    faces.append(b[side])
            self._velocity_dirichlet.append(np.concatenate(faces) if not self.periodic else np.zeros(0, int))
        # the momentum operators share one pattern: a momentum matrix is then one data-array sum
        self._stencil = StencilPattern(mesh)
        self._viscous = [DiffusionOperator(mesh, faces, self._stencil) for faces in self._velocity_dirichlet]
        self._convection = UpwindConvectionOperator(mesh, inflow_faces=self._inlet, outflow_faces=self._outlet,
                                                    pattern=self._stencil)
        # the compiled assembly of the three momentum systems on the same pattern (the operators above
        # are its reference, and the assembly of the 'direct' checks)
        self._momentum_tables = MomentumTables.build(mesh, self._stencil, self._inlet, self._outlet,
                                                     self._velocity_dirichlet)
        self._face_geometry = mesh.face_areas / mesh.face_distances
        self._pressure_laplacian = DiffusionOperator(mesh, self._outlet)
        self._interior = np.nonzero(mesh.interior)[0]
        self._p = mesh.face_cells[self._interior, 0]
        self._q = mesh.face_cells[self._interior, 1]
        self._boundary_cell = mesh.face_cells[:, 0]
        # structured grid: every face normal is +-1 along one axis, so a vector's normal component at
        # a face is one of its components times a sign (exactly what the dot product gives)
        self._face_axis = np.argmax(np.abs(mesh.face_normals), axis=1)
        self._face_sign = mesh.face_normals[np.arange(mesh.face_count), self._face_axis]
        self._interior_axis = self._face_axis[self._interior]
        self._interior_sign = self._face_sign[self._interior]
        n, nf = mesh.cell_count, mesh.face_count
        boundary = np.nonzero(~mesh.interior)[0]
        self._interpolation = sp.csr_matrix(
            (np.concatenate([np.full(2 * len(self._interior), 0.5), np.ones(len(boundary))]),
             (np.concatenate([self._interior, self._interior, boundary]),
              np.concatenate([self._p, self._q, mesh.face_cells[boundary, 0]]))), shape=(nf, n))
        self._divergence = sp.csr_matrix(
            (np.concatenate([np.ones(nf), -np.ones(len(self._interior))]),
             (np.concatenate([self._boundary_cell, self._q]), np.concatenate([np.arange(nf), self._interior]))),
            shape=(n, nf))
        # cell superficial velocity reconstructed from the face fluxes: per axis, the mean of the
        # two face velocities phi n_d / A (what a staggered grid holds)
        rows, cols, vals = [], [], []
        for side in (0, 1):
            cells = mesh.face_cells[:, side]
            ok = cells >= 0
            for d in range(3):
                w = 0.5 * mesh.face_normals[:, d] / mesh.face_areas
                keep = ok & (w != 0)
                rows.append(3 * cells[keep] + d)
                cols.append(np.nonzero(keep)[0])
                vals.append(w[keep])
        self._reconstruction = sp.csr_matrix((np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
                                             shape=(3 * n, nf))
        self._area_normal = mesh.face_areas[:, None] * mesh.face_normals
        self._closed = np.concatenate([self._walls, np.nonzero(mesh.unused)[0]])  # faces with no flux
        self._area_normal[mesh.unused] = 0.0
        # the compiled Gauss sums' face tables
        self._face_first = np.ascontiguousarray(mesh.face_cells[:, 0], dtype=np.int64)
        self._face_second = np.ascontiguousarray(mesh.face_cells[:, 1], dtype=np.int64)
        self._face_axis_int = self._face_axis.astype(np.int64)
        self._signed_area = np.where(mesh.unused, 0.0, mesh.face_areas * self._face_sign)
        self._face_kind = np.where(mesh.interior, face_kernels.INTERIOR, face_kernels.CLOSED).astype(np.int64)
        self._face_kind[self._inlet] = face_kernels.INLET
        self._face_kind[self._outlet] = face_kernels.OUTLET
        self._face_kind[mesh.unused] = face_kernels.UNUSED
        # inlet boundary values (velocity): U / eps at the inlet face, set in step()
        self._inlet_flux = -self.inlet_velocity * mesh.face_areas[self._inlet]
        self._inlet_cells = mesh.face_cells[self._inlet, 0]
        layer = mesh.shape[0] * mesh.shape[1]
        self._inlet_above = self._inlet_cells + layer if len(self._inlet) and mesh.shape[2] > 1 else None
        self.face_flux[self._inlet] = self._inlet_flux
        self._multigrid = None  # the pressure correction's multigrid stencil map (walled grids, iterative solves)
        if (pressure_preconditioner == "multigrid" and linear_solver == "iterative" and assembly == "cached"
                and not any(mesh.periodic)):
            low = np.minimum(self._p, self._q)
            high = np.maximum(self._p, self._q)
            nx, ny, _ = mesh.shape
            stride = np.array([1, nx, nx * ny])[self._interior_axis]
            if np.all(high - low == stride):  # cells numbered x fastest: the grid's 7-point stencil
                self._multigrid = (self._interior.astype(np.int64), low.astype(np.int64), high.astype(np.int64),
                                   self._interior_axis.astype(np.int64), self._outlet.astype(np.int64),
                                   mesh.face_cells[self._outlet, 0].astype(np.int64))

    # ------------------------------------------------------------------ helpers
    def set_inlet_velocity(self, velocity: float) -> None:
        """Change the superficial inlet velocity [m/s] from the next step on (e.g. a velocity ramp)."""
        self.inlet_velocity = float(velocity)
        self._inlet_flux = -self.inlet_velocity * self.mesh.face_areas[self._inlet]

    def flux_velocity(self):
        """Interstitial velocity (C, 3) [m/s] reconstructed from the face fluxes: per axis the mean of
        the two faces' ``phi n / A``, divided by the voidage. Unlike the cell-centred momentum
        velocity it satisfies continuity cell by cell and stays exact across a voidage jump (the
        velocity a staggered grid gives the particles; DPMFoam reconstructs it likewise)."""
        return (self._reconstruction @ self.face_flux).reshape(-1, 3) / self.voidage[:, None]

    def _face_average(self, cell_values):
        """Arithmetic face average (uniform grid: linear interpolation); boundary faces take the cell
        value (one sparse mat-vec with the precomputed interpolation matrix)."""
        return self._interpolation @ cell_values

    def pressure_gradient(self):
        """Cell pressure gradient (C, 3) [Pa/m] of the current state: the Gauss sum of the drag-aware
        face pressures of the last correction, the gradient the cell velocity and the particles'
        pressure-gradient force are consistent with."""
        return self._gauss_gradient(self._current_face_pressure(self.pressure))

    def inlet_pressure(self) -> float:
        """Mean pressure [Pa] on the inlet faces (the distributor), as the cell gradients take it."""
        return float(self._current_face_pressure(self.pressure)[self._inlet].mean())

    def _current_face_pressure(self, pressure):
        if self.face_pressure is not None:
            return self.face_pressure
        return self._linear_face_pressure(pressure)

    def _linear_face_pressure(self, pressure):
        face_p = self._face_average(pressure)  # before the first correction: linear interpolation
        face_p[self._outlet] = 0.0
        if self._inlet_above is not None:  # linear extrapolation to the inlet
            face_p[self._inlet] = 1.5 * pressure[self._inlet_cells] - 0.5 * pressure[self._inlet_above]
        return face_p

    def _gauss_gradient(self, face_p):
        """Gauss gradient (C, 3) [Pa/m] of face pressures ``face_p`` (F,). A single value per face,
        so the gradients of a periodic box sum to zero (the mixture's momentum is conserved).
        Compiled (``face_kernels.gauss_gradient``); ``_gauss_gradient_reference`` is the sparse form."""
        return gauss_gradient(np.asarray(face_p, float), self._face_first, self._face_second, self._face_axis_int,
                              self._signed_area, self.mesh.cell_volumes)

    def _gauss_gradient_reference(self, face_p):
        """``_gauss_gradient`` as a sparse divergence of the face fluxes (the tests' reference)."""
        flux = face_p[:, None] * self._area_normal
        return (self._divergence @ flux) / self.mesh.cell_volumes[:, None]

    def _face_weights(self, k_cell):
        """Drag-aware interpolation weights of interior faces: the weight of the first cell
        ``w = k_N / (k_P + k_N)`` and the face coefficient ``k_f = 2 k_P k_N / (k_P + k_N)`` (harmonic
        mean), from the cell coefficients ``k = eps D = eps^2 V / a_P`` [m^3 s/kg] of
        ``eps u = eps u_hat - k grad p``.

        In one dimension, with the pressure linear in each half cell at the cell's own gradient, the
        flux through a face is exactly ``A [(w c_P + (1 - w) c_N) . n - k_f (p_N - p_P) / d]``
        (``c = eps u_hat``): the two half cells are resistances ``1 / k`` in series. Where the
        interphase coefficient ``beta`` (inside ``a_P``) jumps from cell to cell, arithmetic means of
        ``D`` and ``eps u_hat`` instead smear the resistance over the face, the total pressure drop
        of a heterogeneous bed comes out low, and the cell velocity of a dense cell (next to a looser
        one) breaks continuity by up to ``(1 + k_P / k_N) / 2`` (tenfold in a fluidized bed)."""
        kp, kq = k_cell[self._p], k_cell[self._q]
        total = kp + kq
        return kq / total, 2.0 * kp * kq / total

    def _face_interpolate(self, cell_values, weight):
        """Interior faces: ``w x_P + (1 - w) x_N``; boundary faces: the cell value."""
        out = cell_values[self._boundary_cell].copy()
        w = weight if cell_values.ndim == 1 else weight[:, None]
        out[self._interior] = w * cell_values[self._p] + (1.0 - w) * cell_values[self._q]
        return out

    def _normal_component(self, cell_vectors, cells):
        """``v[cells] . n`` per face (F,) for cell vectors (C, 3): one component times the sign."""
        return cell_vectors[cells, self._face_axis] * self._face_sign

    def _face_interpolate_normal(self, first, second, weight):
        """``(w v_P + (1 - w) v_N) . n`` per face from the normal components at the first cell
        (every face) and the second (interior faces); boundary faces: the first cell's."""
        out = first.copy()
        out[self._interior] = weight * first[self._interior] + (1.0 - weight) * second[self._interior]
        return out

    def _face_pressure(self, pressure, c_normal, k_cell):
        """Face pressures (F,) [Pa] consistent with the fluxes: on each interior face the value both
        half cells reach at their own gradient, ``p_f = (k_P p_P + k_N p_N + (d / 2)(c_P - c_N) . n)
        / (k_P + k_N)``; on the inlet and the walls ``p_P + d_b (c_P . n - phi / A) / k_P`` (``phi``
        the fixed flux); ``p = 0`` on the outlet. With these, the Gauss gradient gives every cell the
        velocity ``eps u = eps u_hat - k grad p`` that equals, per axis, the mean superficial velocity
        of its two faces (the flux-reconstructed velocity) wherever the fluxes are
        ``c_f - k_f dp / d``: exactly so in every cell when ``dt`` is large against ``rho eps / beta``,
        up to the (small) time-step correction of the fluxes otherwise. Compiled
        (``face_kernels.face_pressures``); ``_face_pressure_reference`` is the numpy form."""
        return face_pressures(self._face_kind, self._face_first, self._face_second, self.mesh.face_areas,
                              self.mesh.face_distances, k_cell, np.asarray(pressure, float), c_normal[0], c_normal[1],
                              self.face_flux)

    def _face_pressure_reference(self, pressure, c_normal, k_cell):
        """``_face_pressure`` in numpy (the tests' reference)."""
        mesh = self.mesh
        out = np.zeros(mesh.face_count)
        i = self._interior
        kp, kq = k_cell[self._p], k_cell[self._q]
        half = 0.5 * mesh.face_distances[i]
        out[i] = (kp * pressure[self._p] + kq * pressure[self._q]
                  + half * (c_normal[0][i] - c_normal[1][i])) / (kp + kq)
        for faces in (self._inlet, self._walls):
            if len(faces):
                cells = self._boundary_cell[faces]
                out[faces] = pressure[cells] + mesh.face_distances[faces] * (
                    c_normal[0][faces] - self.face_flux[faces] / mesh.face_areas[faces]) / k_cell[cells]
        out[self._outlet] = 0.0
        return out

    def _net_outflow(self, face_values):
        """Sum over each cell's faces of a face quantity taken outward (precomputed divergence matrix)."""
        return self._divergence @ face_values

    # ------------------------------------------------------------------ linear systems
    def _momentum_system(self, component, implicit_cell, mass_flux, gamma_face, boundary_value):
        """Matrix and boundary right-hand side of one velocity component's momentum equation:
        ``diag(implicit V) + div(mass_flux u) - div(gamma grad u)`` with the component's Dirichlet
        faces (inlet, walls) and the outlet's outflow. The solver's steps assemble the cached path in
        one compiled pass (``MomentumTables.assemble``); this sparse-operator form is its tested
        reference, and the FiPy form the reference of both."""
        if self.assembly == "fipy":
            return fipy_momentum_system(self.mesh, implicit_cell, mass_flux, gamma_face, boundary_value,
                                        self._velocity_dirichlet[component], self._outlet)
        viscous = self._viscous[component]
        stencil = self._stencil
        implicit = np.broadcast_to(implicit_cell, self.mesh.cell_volumes.shape) * self.mesh.cell_volumes
        matrix = stencil.matrix(stencil.diagonal_data(implicit) + self._convection.data(mass_flux)
                                - viscous.data(gamma_face))
        rhs = self._convection.rhs(mass_flux, boundary_value) - viscous.rhs(gamma_face, boundary_value)
        return matrix, rhs

    def _pressure_system(self, gamma_face):
        """``div(gamma grad p')`` with p' = 0 on the outlet."""
        if self.assembly == "fipy":
            return fipy_pressure_system(self.mesh, gamma_face, self._outlet)
        return self._pressure_laplacian.matrix(gamma_face)

    def _solve(self, matrix, rhs, guess, symmetric_negative=False, tolerance=None):
        """Linear solve: direct (``linear_solver='direct'``) or warm-started Krylov: compiled BiCGStab
        with a Jacobi preconditioner for momentum (``krylov.bicgstab_jacobi``), CG preconditioned by a recent factorization for the
        negative-definite pressure Laplacian, to the relative ``tolerance`` (default ``linear_tolerance``).
        ``matrix``: a sparse matrix, or the data array of one on the shared stencil pattern (the
        compiled momentum assembly's)."""
        stencil_data = isinstance(matrix, np.ndarray)
        if self.linear_solver == "direct":
            return spla.spsolve((self._stencil.matrix(matrix) if stencil_data else matrix).tocsc(), rhs)
        tolerance = self.linear_tolerance if tolerance is None else tolerance
        if symmetric_negative:
            matrix, rhs = -matrix, -rhs
            preconditioner = self._pressure_preconditioner(matrix)
            count = [0]
            solution, info = spla.cg(matrix, rhs, x0=guess, rtol=tolerance, atol=0.0,
                                     M=preconditioner, maxiter=1000, callback=lambda x: count.__setitem__(0, count[0] + 1))
            self._step_iterations += count[0]
            if count[0] > 25:  # the stored factorization has drifted too far from the current matrix
                self._pressure_lu = None
        else:  # compiled Jacobi-BiCGStab (fvdem/gas/krylov.py), on the CSR arrays without building a matrix
            if stencil_data:
                indptr, indices, data = self._stencil.indptr, self._stencil.indices, matrix
            else:
                matrix = sp.csr_matrix(matrix)
                indptr, indices, data = matrix.indptr, matrix.indices, matrix.data
            solution = np.array(guess, dtype=float)
            info, _ = bicgstab_jacobi(indptr, indices, data, np.ascontiguousarray(rhs, float), solution, tolerance, 1000)
        if info != 0 or not np.all(np.isfinite(solution)):
            self.direct_fallbacks += 1  # Krylov stalled (e.g. a convection-dominated step): solve directly
            if stencil_data:
                matrix = self._stencil.matrix(matrix)
            return spla.spsolve(matrix.tocsc(), rhs)  # the same (possibly sign-flipped) system
        return solution

    def _pressure_preconditioner(self, matrix):
        """LU factorization of a recent pressure matrix as CG preconditioner. The Laplacian changes
        only through the voidage and the momentum diagonal, slowly from step to step, so an older
        factorization cuts CG from ~200 (Jacobi) to a few iterations; it is refreshed every
        ``refactor_interval`` steps or when CG needs more than 25 iterations."""
        if (self._pressure_lu is None or self._pressure_lu.shape != matrix.shape or self._refactor_due
                or self._steps_since_factor >= self.refactor_interval):
            self.set_preconditioner_matrix(matrix.tocsc())
            self.factorizations += 1
        return spla.LinearOperator(matrix.shape, matvec=self._pressure_lu.solve, dtype=float)

    def set_preconditioner_matrix(self, matrix, steps_since_factor: int = 0, iterations_since_factor: int = 0) -> None:
        """Factorize ``matrix`` as the pressure preconditioner (also used to restore a checkpoint:
        refactoring the same matrix reproduces the same factorization, so a resumed run is bit-for-bit)."""
        self._pressure_factor_matrix = sp.csc_matrix(matrix)
        # the Laplacian is symmetric positive definite: symmetric-mode SuperLU (minimum degree on
        # A + A^T, diagonal pivots) fills half of what the default COLAMD ordering does on the
        # 10 x 10 x 70 grid (0.75 M against 1.33 M entries): each CG preconditioner solve 0.51 ms
        # instead of 0.85, the factorization 27 ms instead of 43 (measured 2026-12-01)
        self._pressure_lu = spla.splu(self._pressure_factor_matrix, permc_spec="MMD_AT_PLUS_A",
                                      diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        self._steps_since_factor = steps_since_factor
        self._iterations_since_factor = iterations_since_factor
        self._refactor_due = False

    # ------------------------------------------------------------------ checkpoint state
    STATE_FIELDS = ("velocity", "pressure", "face_flux", "voidage", "beta")

    def state(self) -> dict:
        """Everything a solver needs to continue bit-for-bit: its fields, the last step's face pressure and
        gradient correction, the preconditioner's counters ``counters`` (steps and iterations since its
        factorization, factorizations, whether a refactorization is due) and, when it has one, the matrix
        it factorized (``preconditioner.*``: refactoring it reproduces the factorization)."""
        state = {name: getattr(self, name) for name in self.STATE_FIELDS}
        state.update({"face_pressure": self.face_pressure if self.face_pressure is not None else np.zeros(0),
                      "gradient_correction": self.gradient_correction,
                      "counters": np.array([self._steps_since_factor, self.factorizations,
                                            self._iterations_since_factor, int(self._refactor_due)])})
        if self._pressure_lu is not None:
            m = self._pressure_factor_matrix
            state.update({"preconditioner.data": m.data, "preconditioner.indices": m.indices,
                          "preconditioner.indptr": m.indptr, "preconditioner.shape": np.array(m.shape)})
        return state

    def restore(self, data) -> None:
        """Load a ``state()`` (copies; keys missing from older checkpoints keep their defaults)."""
        for name in self.STATE_FIELDS:
            setattr(self, name, np.array(data[name], copy=True))
        face_pressure = np.array(data["face_pressure"], copy=True) if "face_pressure" in data else np.zeros(0)
        self.face_pressure = face_pressure if len(face_pressure) else None
        if "gradient_correction" in data:
            self.gradient_correction = np.array(data["gradient_correction"], copy=True)
        self.voidage_old = self.voidage.copy()
        since_factor, self.factorizations, iterations_since, refactor_due = [int(v) for v in data["counters"]]
        if "preconditioner.data" in data and self._multigrid is None:  # (multigrid keeps no preconditioner)
            matrix = sp.csc_matrix((data["preconditioner.data"], data["preconditioner.indices"],
                                    data["preconditioner.indptr"]), shape=tuple(data["preconditioner.shape"]))
            self.set_preconditioner_matrix(matrix, since_factor, iterations_since)
            self._refactor_due = bool(refactor_due)
        else:  # no factorization to restore (multigrid, or none yet): the counts still continue as they were
            self._steps_since_factor, self._iterations_since_factor = since_factor, iterations_since

    def _plan_refactor(self) -> None:
        """After a step: refactor the preconditioner at the next step when this step's CG iterations
        exceed the average cost per step since the last factorization, the factorization counted as
        ``FACTOR_COST_ITERATIONS`` (the renewal rule: renew once the marginal cost passes the average,
        which minimises the long-run cost per step). Counts, not timings: a run stays reproducible."""
        steps = self._steps_since_factor
        if self._pressure_lu is None or steps <= 0:
            return
        self._iterations_since_factor += self._step_iterations
        average = (FACTOR_COST_ITERATIONS + self._iterations_since_factor) / steps
        self._refactor_due = steps > 1 and self._step_iterations > average

    def _predict_momentum(self, dt, u_old, gamma, inlet_value, relax):
        """Solve the three momentum components with the current pressure; returns ``(a_P, grad p)``."""
        rho = self.gas.density
        eps, eps_old, vol = self.voidage, self.voidage_old, self.mesh.cell_volumes
        implicit = rho * eps / dt + self.beta
        grad_p = self._gauss_gradient(self._linear_face_pressure(self.pressure)) + self.gradient_correction
        # explicit right-hand side per unit volume: old momentum, exchange source, gravity, pressure
        explicit = (rho * eps_old / dt)[:, None] * u_old + self.source + rho * eps[:, None] * self.gravity
        explicit -= eps[:, None] * grad_p
        fipy = self.assembly == "fipy"
        if not fipy:  # one compiled pass for the three systems (fvdem/gas/momentum_kernels.py)
            data, rhs, diagonal = self._momentum_tables.assemble(
                vol, implicit, rho * self.face_flux,
                gamma * self._face_geometry, inlet_value, explicit)
        diagonals = []
        for c in range(3):
            if fipy:
                a, b = self._momentum_system(c, implicit, rho * self.face_flux, gamma, inlet_value[:, c])
                b, diag_c = b + explicit[:, c] * vol, a.diagonal()
            else:  # the matrix as its data array on the shared stencil pattern
                a, b, diag_c = data[c], rhs[:, c], diagonal[:, c]
            if relax < 1.0:
                extra = diag_c / relax - diag_c
                if fipy:
                    a = a + sp.diags(extra)
                else:
                    a[self._momentum_tables.diagonal] += extra
                b = b + extra * self.velocity[:, c]
                diag_c = diag_c + extra
            self.velocity[:, c] = self._solve(a, b, self.velocity[:, c])
            diagonals.append(diag_c)
        return np.mean(diagonals, axis=0), grad_p

    def _correct_pressure(self, dt, a_p, grad_p, relax, old, tolerance=None, final=False):
        """Drag-aware Rhie-Chow fluxes from the current velocity and pressure, then one pressure
        correction: the corrected fluxes satisfy continuity (with the voidage change) to solver
        tolerance, and the cell velocity is recovered with the gradient of the face pressures that
        match them (``_face_pressure``). ``old`` holds the old face superficial velocities and old cell
        superficial velocities of the time-step correction; ``tolerance`` the pressure solve's relative
        tolerance (default ``linear_tolerance``); ``final``: the solve may stop once the continuity
        residual's norm is below ``tolerance`` times the largest face flux, when that is reached before
        ``tolerance`` times the imbalance's own norm (the last PISO corrector's imbalance is thousands of
        times smaller than the first's: solved relative to its own norm, continuity held to round-off
        of round-off). Returns the continuity residual before the correction (relative to the largest
        flux)."""
        mesh = self.mesh
        eps, eps_old, vol = self.voidage, self.voidage_old, mesh.cell_volumes
        d_cell = eps * vol / a_p
        k_cell = eps * d_cell
        u_hat = self.velocity + d_cell[:, None] * grad_p
        c = eps[:, None] * u_hat  # superficial u_hat: what is continuous across a voidage jump
        flux, k_face, c_first, c_second = self._predicted_fluxes(dt, d_cell, k_cell, c, old)
        imbalance = self._net_outflow(flux) + (eps - eps_old) * vol / dt
        tolerance = self.linear_tolerance if tolerance is None else tolerance
        if final:  # |r| <= tolerance * max(|b|, largest flux): continuity to tolerance of the flow
            norm, scale = float(np.sqrt(np.dot(imbalance, imbalance))), float(np.abs(flux).max())
            if scale > norm:
                tolerance = tolerance * scale / norm if norm > 0.0 else 1.0
        p_corr = np.zeros(mesh.cell_count)
        if self._multigrid is not None:
            p_corr = self._multigrid_correction(k_face, imbalance, tolerance)
        elif self.periodic:  # pressure fixed up to a constant: pin cell 0
            laplacian = self._pressure_system(k_face).tocsr()
            p_corr[1:] = self._solve(laplacian[1:, 1:], imbalance[1:], p_corr[1:], symmetric_negative=True,
                                     tolerance=tolerance)
        else:
            p_corr = self._solve(self._pressure_system(k_face).tocsr(), imbalance, p_corr, symmetric_negative=True,
                                 tolerance=tolerance)
        self.face_flux = corrected_fluxes(self._face_kind, self._face_first, self._face_second, mesh.face_areas,
                                          mesh.face_distances, k_face, flux, p_corr)
        c_normal = (c_first, c_second)
        corrected = self.pressure + p_corr
        face_p = self._face_pressure(corrected, c_normal, k_cell)
        gradient = self._gauss_gradient(face_p)
        self.velocity = u_hat - d_cell[:, None] * gradient
        if relax < 1.0:  # SIMPLE: the pressure of the next outer iteration is under-relaxed
            corrected = self.pressure + relax * p_corr
            face_p = self._face_pressure(corrected, c_normal, k_cell)
            gradient = self._gauss_gradient(face_p)
        if self.periodic:  # a uniform shift leaves the gradient unchanged
            shift = corrected.mean()
            corrected, face_p = corrected - shift, face_p - shift
        self.pressure, self.face_pressure = corrected, face_p
        self._face_gradient = gradient  # the next PISO corrector's gradient
        target = gradient - self._gauss_gradient(self._linear_face_pressure(corrected))
        self.gradient_correction += GRADIENT_RELAXATION * (target - self.gradient_correction)
        return np.abs(imbalance).max() / max(np.abs(self.face_flux).max(), 1e-30)

    def _predicted_fluxes(self, dt, d_cell, k_cell, c, old):
        """Rhie-Chow face fluxes before the correction, with the face coefficients and the normal
        components of ``c = eps u_hat`` at each face's cells (compiled: ``face_kernels.predicted_fluxes``)."""
        old_face, old_cell = old
        d_old = d_cell[:, None] * old_cell
        flux, k_face, c_first, c_second = predicted_fluxes(
            self._face_kind, self._face_first, self._face_second, self._face_axis_int, self._face_sign,
            self.mesh.face_areas, self.mesh.face_distances, k_cell, d_cell, np.ascontiguousarray(c), d_old,
            self.pressure, np.ascontiguousarray(old_face, float), self.gas.density / dt)
        flux[self._inlet] = self._inlet_flux
        return flux, k_face, c_first, c_second

    def _predicted_fluxes_reference(self, dt, d_cell, k_cell, c, old):
        """``_predicted_fluxes`` in numpy, term by term (the tests' reference)."""
        mesh = self.mesh
        weight, k_interior = self._face_weights(k_cell)
        k_face = k_cell[self._boundary_cell]
        k_face[self._interior] = k_interior
        c_first = self._normal_component(c, self._boundary_cell)
        c_second = np.zeros(mesh.face_count)
        c_second[self._interior] = c[self._q, self._interior_axis] * self._interior_sign
        c_face = self._face_interpolate_normal(c_first, c_second, weight)
        # time-step-independent Rhie-Chow (Choi 1999; OpenFOAM's ddtCorr): on faces, the old-velocity
        # part of u_hat, (rho / dt) D eps_old u_old, is taken from the old face flux
        old_face, old_cell = old
        d_face = self._face_interpolate(d_cell, weight)
        d_old = d_cell[:, None] * old_cell
        d_old_second = np.zeros(mesh.face_count)
        d_old_second[self._interior] = d_old[self._q, self._interior_axis] * self._interior_sign
        old_term = self.gas.density / dt * (d_face * old_face - self._face_interpolate_normal(
            self._normal_component(d_old, self._boundary_cell), d_old_second, weight))
        old_term[self._closed] = 0.0
        old_term[self._inlet] = 0.0
        old_term[self._outlet] = 0.0
        flux = mesh.face_areas * (c_face - k_face * self._face_difference(self.pressure) + old_term)
        flux[self._closed] = 0.0
        flux[self._inlet] = self._inlet_flux
        return flux, k_face, c_first, c_second

    def _multigrid_correction(self, k_face, imbalance, tolerance):
        """The pressure correction ``div(k_f grad p') = imbalance`` by multigrid-preconditioned CG
        (``fvdem.gas.multigrid``; no sparse matrix is assembled), from zero to the relative
        ``tolerance``; a solve that fails falls back to a direct one (counted in ``direct_fallbacks``)."""
        faces, low, high, axis, outlet, outlet_cells = self._multigrid
        n = self.mesh.cell_count
        d, cx, cy, cz = multigrid.stencil_from_faces(k_face, self._face_geometry, faces, low, high, axis, outlet,
                                                     outlet_cells, n)
        rhs = -np.asarray(imbalance, float)
        solution = np.zeros(n)
        info, iterations = multigrid.solve_stencil(d, cx, cy, cz, self.mesh.shape, rhs, solution, tolerance, 1000)
        self._step_iterations += iterations
        if info != 0 or not np.all(np.isfinite(solution)):
            self.direct_fallbacks += 1
            return spla.spsolve((-self._pressure_system(k_face)).tocsc(), rhs)
        return solution

    def _face_difference(self, cell_values):
        """``(phi_N - phi_P) / d`` on interior faces, ``(0 - phi_P) / d`` on outlet faces, else 0."""
        mesh = self.mesh
        out = np.zeros(mesh.face_count)
        out[self._interior] = (cell_values[self._q] - cell_values[self._p]) / mesh.face_distances[self._interior]
        out[self._outlet] = -cell_values[self._boundary_cell[self._outlet]] / mesh.face_distances[self._outlet]
        return out

    # ------------------------------------------------------------------ one time step
    def step(self, dt: float) -> dict:
        """Advance the gas by ``dt`` [s] with ``voidage``, ``voidage_old``, ``beta`` and ``source`` as
        set by the caller. Returns convergence information.

        ``scheme='piso'``: one momentum predictor, then ``correctors`` pressure corrections without
        under-relaxation (for CFD steps small against the flow time scales, as in CFD-DEM);
        ``scheme='simple'``: under-relaxed outer iterations of predictor and corrector until the
        continuity residual and the velocity change are below ``tolerance`` (for large steps and
        steady states)."""
        mesh = self.mesh
        eps = self.voidage
        u_old = self.velocity.copy()
        # old face and cell superficial velocities for the time-step correction of the fluxes
        old = (np.divide(self.face_flux, mesh.face_areas, out=np.zeros(mesh.face_count), where=mesh.face_areas > 0),
               self.voidage_old[:, None] * u_old)
        eps_face = self._face_average(eps)
        gamma = self.gas.viscosity * eps_face
        inlet_value = np.zeros((mesh.face_count, 3))
        inlet_value[self._inlet, 2] = self.inlet_velocity / eps[self._boundary_cell[self._inlet]]
        self.face_flux[self._inlet] = self._inlet_flux
        self._steps_since_factor += 1
        self._step_iterations = 0
        if self.scheme == "piso":
            t0 = perf_counter()
            a_p, grad_p = self._predict_momentum(dt, u_old, gamma, inlet_value, 1.0)
            t1 = perf_counter()
            residuals = []
            for corrector in range(self.correctors):
                final = corrector == self.correctors - 1
                tolerance = (self.linear_tolerance if final or self.corrector_tolerance is None
                             else max(self.corrector_tolerance, self.linear_tolerance))
                residuals.append(self._correct_pressure(dt, a_p, grad_p, 1.0, old, tolerance, final))
                grad_p = self._face_gradient
            self._plan_refactor()
            self.timings.add("gas_momentum", t1 - t0)
            self.timings.add("gas_pressure", perf_counter() - t1)
            self.iterations = 1
            return {"iterations": 1, "continuity_residual": residuals[-1], "first_residual": residuals[0],
                    "direct_fallbacks": self.direct_fallbacks, "factorizations": self.factorizations}
        residual = change = np.inf
        for iteration in range(1, self.max_iterations + 1):
            previous = self.velocity.copy()
            t0 = perf_counter()
            a_p, grad_p = self._predict_momentum(dt, u_old, gamma, inlet_value, self.relax_velocity)
            t1 = perf_counter()
            residual = self._correct_pressure(dt, a_p, grad_p, self.relax_pressure, old)
            self.timings.add("gas_momentum", t1 - t0)
            self.timings.add("gas_pressure", perf_counter() - t1)
            change = np.abs(self.velocity - previous).max() / max(np.abs(self.velocity).max(), 1e-30)
            if residual < self.tolerance and change < self.tolerance:
                break
        self._plan_refactor()
        self.iterations = iteration
        return {"iterations": iteration, "continuity_residual": residual, "velocity_change": change}
