"""Particle layout (struct of arrays) and shape mass properties.

Every particle is a spherocylinder: a cylinder of radius ``radius`` and length
``2 * half_length`` capped by two hemispheres. A sphere is the special case
``half_length == 0``. The body frame has the symmetry axis along its z axis; the
orientation is the world-frame ``axis`` alone (the spin about it has no effect on an
axisymmetric body; ``ParticleArrays.quaternion`` derives a body-to-world quaternion).

All quantities in SI units.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np
from numba import njit, prange
from numba.extending import register_jitable

FLOAT = np.float64


@njit(cache=True, parallel=True)
def gather_rows(source, order, destination):
    """``destination[k] = source[order[k]]`` row by row (2-D arrays of one dtype)."""
    for k in prange(order.shape[0]):
        o = order[k]
        for c in range(source.shape[1]):
            destination[k, c] = source[o, c]


@register_jitable
def spherocylinder_volume(radius, half_length):
    """Volume [m^3] of a spherocylinder with cylinder radius ``radius`` [m] and
    cylindrical part of length ``2*half_length`` [m] (caps excluded). Callable from kernels too."""
    return np.pi * radius**2 * 2.0 * half_length + 4.0 / 3.0 * np.pi * radius**3


def spherocylinder_surface(radius, half_length):
    """Surface area [m^2]: cylinder mantle plus one full sphere."""
    return 2.0 * np.pi * radius * 2.0 * half_length + 4.0 * np.pi * radius**2


def volume_equivalent_diameter(radius, half_length):
    """Diameter [m] of the sphere with the same volume."""
    return (6.0 * spherocylinder_volume(radius, half_length) / np.pi) ** (1.0 / 3.0)


def spherocylinder_inertia(radius, half_length, density):
    """Principal moments of inertia [kg m^2] about the centre of mass.

    Returns ``(transverse, axial)``. With cylinder length ``Lc = 2 h``, cylinder
    mass ``m_c = rho pi r^2 Lc`` and cap mass (both caps) ``m_s = rho 4/3 pi r^3``:

    - axial:      ``m_c r^2 / 2 + 2/5 m_s r^2``
    - transverse: ``m_c (Lc^2/12 + r^2/4) + m_s (2 r^2/5 + Lc^2/4 + 3 Lc r / 8)``

    The cap term is each hemisphere's own inertia moved by the parallel-axis theorem
    from its centre of mass (3r/8 from its flat face) to the particle centre.
    """
    r = np.asarray(radius, dtype=FLOAT)
    lc = 2.0 * np.asarray(half_length, dtype=FLOAT)
    m_c = density * np.pi * r**2 * lc
    m_s = density * 4.0 / 3.0 * np.pi * r**3
    axial = 0.5 * m_c * r**2 + 0.4 * m_s * r**2
    transverse = m_c * (lc**2 / 12.0 + r**2 / 4.0) + m_s * (0.4 * r**2 + lc**2 / 4.0 + 3.0 * lc * r / 8.0)
    return transverse, axial


def axis_from_quaternion(quaternion):
    """World-frame symmetry axis (body z) of unit quaternions ``(N, 4)``, returns ``(N, 3)``."""
    w, x, y, z = quaternion.T
    return np.stack([2.0 * (x * z + w * y), 2.0 * (y * z - w * x), 1.0 - 2.0 * (x * x + y * y)], axis=1)


def quaternion_from_axis(axis):
    """Unit quaternions ``(N, 4)`` that rotate body z onto unit vectors ``axis (N, 3)``
    (spin about the axis is irrelevant for axisymmetric bodies). Upper hemisphere: the shortest rotation,
    ``(1 + a_z, -a_y, a_x, 0)`` normalised; lower one: a half turn about x (e_z onto -e_z) followed by the
    shortest rotation from -e_z, ``(-a_y, 1 - a_z, 0, a_x)`` normalised. No ``1 + a_z`` near a_z = -1,
    so the axis read back is exact to round-off everywhere."""
    axis = np.asarray(axis, dtype=FLOAT)
    axis = axis / np.linalg.norm(axis, axis=1, keepdims=True)
    ax, ay, az = axis.T
    upper = az >= 0.0
    q = np.empty((len(axis), 4), dtype=FLOAT)
    q[:, 0] = np.where(upper, 1.0 + az, -ay)
    q[:, 1] = np.where(upper, -ay, 1.0 - az)
    q[:, 2] = np.where(upper, ax, 0.0)
    q[:, 3] = np.where(upper, 0.0, ax)
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return q


@dataclass
class ParticleArrays:
    """All per-particle arrays, one row per particle (struct of arrays).

    Attributes (SI units):
        position (N,3) [m]; velocity (N,3) [m/s];
        angular_momentum (N,3) [kg m^2/s], world frame (the integrated rotational state);
        angular_velocity (N,3) [rad/s], world frame, derived from angular_momentum and orientation;
        axis (N,3) world-frame symmetry axis (unit vectors: the orientation of an axisymmetric body;
        ``quaternion`` derives one);
        radius (N) [m]; half_length (N) [m] half the cylindrical part (0 for spheres);
        mass (N) [kg]; inertia (N,2) [kg m^2] (transverse, axial);
        colour (N) int32 tracer colour; ids (N) int64 stable particle id;
        contact_force/contact_torque (N,3): from particle and wall contacts [N], [N m];
        external_force/external_torque (N,3): hydrodynamic and other forces set by the caller, held
        over a step;
        drag_coefficient (N) [kg/s]: implicit drag ``c`` with force ``c (fluid_velocity - velocity)``,
        integrated implicitly by the kicks (0: no implicit drag); fluid_velocity (N,3) [m/s] the
        gas velocity at the particle; drag_impulse (N,3) [N s] the drag impulse the kicks applied
        since the coupling bridge last reset it.
    """

    position: np.ndarray
    velocity: np.ndarray
    angular_momentum: np.ndarray
    angular_velocity: np.ndarray
    axis: np.ndarray
    radius: np.ndarray
    half_length: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    colour: np.ndarray
    ids: np.ndarray
    contact_force: np.ndarray
    contact_torque: np.ndarray
    external_force: np.ndarray
    external_torque: np.ndarray
    drag_coefficient: np.ndarray
    fluid_velocity: np.ndarray
    drag_impulse: np.ndarray

    @property
    def count(self) -> int:
        return len(self.mass)

    @property
    def quaternion(self) -> np.ndarray:
        """Body-to-world unit quaternions ``(N, 4)``, ``(w, x, y, z)``, that turn body z onto each axis
        (``quaternion_from_axis``). The spin about the axis is not tracked (it has no effect on an
        axisymmetric body), so this is one orientation of each particle, not its history."""
        return quaternion_from_axis(self.axis)

    @classmethod
    def create(cls, position, radius, half_length, density, axis=None, colour=None, velocity=None):
        """Allocate arrays for particles at ``position`` with given shape and density [kg/m^3]. The
        arrays passed in are copied: the simulation advances its own, never the caller's."""
        position = np.array(position, dtype=FLOAT, order="C", copy=True)
        n = len(position)
        radius = np.broadcast_to(np.asarray(radius, dtype=FLOAT), (n,)).copy()
        half_length = np.broadcast_to(np.asarray(half_length, dtype=FLOAT), (n,)).copy()
        if axis is None:
            axis = np.tile(np.array([0.0, 0.0, 1.0]), (n, 1))
        axis = np.array(axis, dtype=FLOAT, ndmin=2)
        axis = np.array(np.broadcast_to(axis / np.linalg.norm(axis, axis=1, keepdims=True), (n, 3)), order="C")
        transverse, axial = spherocylinder_inertia(radius, half_length, density)
        zeros3 = lambda: np.zeros((n, 3), dtype=FLOAT)  # noqa: E731
        return cls(
            position=position,
            velocity=zeros3() if velocity is None else np.array(velocity, dtype=FLOAT, order="C", copy=True),
            angular_momentum=zeros3(),
            angular_velocity=zeros3(),
            axis=axis,
            radius=radius,
            half_length=half_length,
            mass=density * spherocylinder_volume(radius, half_length),
            inertia=np.ascontiguousarray(np.stack([transverse, axial], axis=1)),
            colour=np.zeros(n, dtype=np.int32) if colour is None else np.array(colour, dtype=np.int32, copy=True),
            ids=np.arange(n, dtype=np.int64),
            contact_force=zeros3(),
            contact_torque=zeros3(),
            external_force=zeros3(),
            external_torque=zeros3(),
            drag_coefficient=np.zeros(n, dtype=FLOAT),
            fluid_velocity=zeros3(),
            drag_impulse=zeros3(),
        )

    def permute(self, order: np.ndarray) -> None:
        """Reorder every array so that new row k holds old row ``order[k]``.

        The rows are gathered into the arrays the previous permutation left behind (double buffering),
        not into new ones: a fresh array costs its page faults on the first write, which made a
        permutation of the 32,500-particle arrays 5-7x slower than the gather itself. Every field
        therefore holds a new array object after a call, and an array taken from a field before the
        previous call is overwritten by this one (hold fields by attribute, not by array)."""
        spares = self.__dict__.setdefault("_spares", {})
        n = len(order)
        for f in fields(self):
            source = getattr(self, f.name)
            destination = spares.get(f.name)
            if destination is None or destination.shape != source.shape or destination.dtype != source.dtype:
                destination = np.empty(source.shape, source.dtype)
            gather_rows(np.ascontiguousarray(source).reshape(n, -1), order, destination.reshape(n, -1))
            spares[f.name] = source
            setattr(self, f.name, destination)

    def as_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}

    @classmethod
    def from_dict(cls, data) -> "ParticleArrays":
        """New arrays (always copies, never views of ``data``). Coupling arrays missing from ``data``
        (a state written by a DEM-only run) start at zero."""
        n = len(data["mass"])
        optional = {"drag_coefficient": (n,), "fluid_velocity": (n, 3), "drag_impulse": (n, 3)}
        return cls(**{f.name: (np.array(data[f.name], order="C", copy=True) if f.name in data
                               else np.zeros(optional[f.name])) for f in fields(cls)})

    def kinetic_energy(self) -> float:
        """Translational plus rotational kinetic energy [J]."""
        translational = 0.5 * np.sum(self.mass * np.einsum("ij,ij->i", self.velocity, self.velocity))
        rotational = 0.5 * np.sum(np.einsum("ij,ij->i", self.angular_momentum, self.angular_velocity))
        return float(translational + rotational)
