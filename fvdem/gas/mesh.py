"""The one adapter between fvdem and FiPy.

Everything else in fvdem reads mesh geometry from a ``GasMesh`` as plain numpy arrays with
snake_case names; FiPy-specific attributes (some of them private, such as face areas and cell
distances) are touched here only. The reference path of the gas solver, which rebuilds its linear
systems from plain FiPy terms (``fipy_momentum_system``, ``fipy_pressure_system``), lives here too.

FiPy's naming on a ``Grid3D``: ``facesLeft/Right`` are x faces, ``facesBottom/Top`` are **y** faces,
and ``facesFront`` (z = 0) / ``facesBack`` (z = max) are the z faces. ``GasMesh.boundary_faces``
exposes them as ``x-, x+, y-, y+, z-, z+``.
"""
from __future__ import annotations

from dataclasses import dataclass

import fipy
import numpy as np
import scipy.sparse as sp

BOUNDARIES = ("x-", "x+", "y-", "y+", "z-", "z+")


@dataclass
class GasMesh:
    """Geometry of a structured FiPy grid as numpy arrays (SI units).

    Attributes:
        fipy_mesh: the FiPy mesh (for reference-path terms and variables);
        cell_volumes (C,) [m^3]; cell_centers (C, 3) [m];
        face_cells (F, 2): the two cells of each face (second = -1 on the boundary, and on the unused
        copy of a periodic face, which carries no flux);
        face_areas (F,) [m^2]; face_normals (F, 3) unit normals from first to second cell
        (outward on the boundary); face_distances (F,) [m]: centre-to-centre distance across an
        interior face, centre-to-face distance on a boundary face;
        boundary_faces: dict name -> face indices for x-, x+, y-, y+, z-, z+ (empty on periodic axes).
    """

    fipy_mesh: object
    shape: tuple
    spacing: tuple
    periodic: tuple
    cell_volumes: np.ndarray
    cell_centers: np.ndarray
    face_cells: np.ndarray
    face_areas: np.ndarray
    face_normals: np.ndarray
    face_distances: np.ndarray
    boundary_faces: dict

    @property
    def cell_count(self) -> int:
        return len(self.cell_volumes)

    @property
    def face_count(self) -> int:
        return len(self.face_areas)

    @property
    def interior(self) -> np.ndarray:
        """Mask of faces between two cells (periodic faces included)."""
        return self.face_cells[:, 1] >= 0

    @property
    def unused(self) -> np.ndarray:
        """Mask of faces that are neither interior nor a boundary: the single-cell copies that FiPy
        keeps of periodic faces. They carry no flux and take no part in gradients."""
        mask = ~self.interior
        for faces in self.boundary_faces.values():
            mask[faces] = False
        return mask

    @classmethod
    def box(cls, shape, lower, upper, periodic=(False, False, False)) -> "GasMesh":
        """A structured grid of ``shape = (nx, ny, nz)`` cells on the box ``lower``-``upper`` [m];
        periodic on all three axes or on none (FiPy's ``PeriodicGrid3D`` or ``Grid3D``)."""
        nx, ny, nz = (int(n) for n in shape)
        lower = np.asarray(lower, float)
        spacing = (np.asarray(upper, float) - lower) / np.array([nx, ny, nz])
        if all(periodic):
            mesh = fipy.PeriodicGrid3D(nx=nx, ny=ny, nz=nz, dx=spacing[0], dy=spacing[1], dz=spacing[2])
        elif not any(periodic):
            mesh = fipy.Grid3D(nx=nx, ny=ny, nz=nz, dx=spacing[0], dy=spacing[1], dz=spacing[2])
        else:
            raise ValueError("the gas grid is periodic on all axes or on none")
        if np.any(lower != 0.0):
            mesh = mesh + lower[:, None]
        return cls.from_fipy(mesh, (nx, ny, nz), tuple(spacing), tuple(bool(p) for p in periodic))

    @classmethod
    def from_fipy(cls, mesh, shape, spacing, periodic) -> "GasMesh":
        face_cells = np.asarray(mesh.faceCellIDs.filled(-1)).T.copy()
        centers = np.asarray(mesh.cellCenters).T.copy()
        groups = {}
        fipy_groups = {"x-": mesh.facesLeft, "x+": mesh.facesRight, "y-": mesh.facesBottom,
                       "y+": mesh.facesTop, "z-": mesh.facesFront, "z+": mesh.facesBack}
        for k, name in enumerate(BOUNDARIES):
            faces = np.nonzero(np.asarray(fipy_groups[name]))[0]
            # on a periodic axis FiPy joins the end cells through one copy of each boundary face and
            # leaves the other copy with a single cell and no flux: neither is a boundary
            groups[name] = faces[:0] if periodic[k // 2] else faces[face_cells[faces, 1] < 0]
        return cls(
            fipy_mesh=mesh, shape=tuple(shape), spacing=tuple(spacing), periodic=tuple(periodic),
            cell_volumes=np.asarray(mesh.cellVolumes).copy(), cell_centers=centers, face_cells=face_cells,
            face_areas=np.asarray(mesh._faceAreas).copy(), face_normals=np.asarray(mesh.faceNormals).T.copy(),
            face_distances=np.asarray(mesh._cellDistances).copy(), boundary_faces=groups,
        )


# --------------------------------------------------------------------------- reference path
def _fipy_linear_system(term, var):
    """Matrix and right-hand side FiPy assembles for ``term == 0`` in ``var`` (no solve)."""
    solver = term._prepareLinearSystem(var=var, solver=None, boundaryConditions=(), dt=1.0)
    return sp.csr_matrix(solver.matrix.matrix), np.asarray(solver.RHSvector)


def fipy_momentum_system(mesh: GasMesh, implicit_cell, mass_flux, gamma_face, boundary_value, dirichlet_faces,
                         outlet_faces):
    """One velocity component's momentum system from plain FiPy terms:
    ``ImplicitSourceTerm(implicit) + UpwindConvectionTerm(mass flux) - DiffusionTerm(gamma)`` with
    Dirichlet ``boundary_value`` on ``dirichlet_faces``. FiPy's convection carries nothing through
    unconstrained boundary faces, so the outflow through ``outlet_faces`` enters as an implicit
    source on their cells."""
    fm = mesh.fipy_mesh
    var = fipy.CellVariable(mesh=fm, value=0.0)
    dirichlet = np.zeros(mesh.face_count, bool)
    dirichlet[dirichlet_faces] = True
    if dirichlet.any():
        var.constrain(fipy.FaceVariable(mesh=fm, value=boundary_value), where=dirichlet)
    carried = mass_flux.copy()
    carried[outlet_faces] = 0.0
    outflow = np.zeros(mesh.cell_count)
    np.add.at(outflow, mesh.face_cells[outlet_faces, 0], mass_flux[outlet_faces])
    face_velocity = (carried / mesh.face_areas)[None, :] * mesh.face_normals.T
    term = (fipy.ImplicitSourceTerm(coeff=fipy.CellVariable(mesh=fm, value=implicit_cell + outflow / mesh.cell_volumes))
            + fipy.UpwindConvectionTerm(coeff=fipy.FaceVariable(mesh=fm, rank=1, value=face_velocity))
            - fipy.DiffusionTerm(coeff=fipy.FaceVariable(mesh=fm, value=gamma_face)))
    return _fipy_linear_system(term, var)


def fipy_pressure_system(mesh: GasMesh, gamma_face, outlet_faces):
    """``DiffusionTerm(gamma)`` for the pressure correction, p' = 0 on ``outlet_faces``."""
    fm = mesh.fipy_mesh
    var = fipy.CellVariable(mesh=fm, value=0.0)
    if len(outlet_faces):
        outlet = np.zeros(mesh.face_count, bool)
        outlet[outlet_faces] = True
        var.constrain(0.0, where=outlet)
    matrix, _ = _fipy_linear_system(fipy.DiffusionTerm(coeff=fipy.FaceVariable(mesh=fm, value=gamma_face)), var)
    return matrix
