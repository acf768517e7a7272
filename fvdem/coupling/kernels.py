"""The coupling's compiled per-particle loops (the bridge's fast path).

**The closures** run through loops that ``law_loops`` writes from the registry (``closures.fast_loops``),
each registered law inlined by its index; here is ``reynolds_loop``, the slip Reynolds numbers for their
range warnings. Inputs: slip (N, 3), voidage (N,), axis (N, 3), C-contiguous float64, and the shape vector
(``laws.shape_vector``, ``closures.ParticleShape.kernel_args``).

Also here: the semi-implicit exchange of the bridge (``exchange_terms``: the particle response, the
gas coefficient and source, deposited with the interpolation weights in one race-free pass) and the
bridge's per-particle glue.
"""
from __future__ import annotations

import math

import numba
import numpy as np
from numba import njit

from ..dem.particles import spherocylinder_volume
from .interpolation import scatter_blocks
from .laws import D_P, MU, RHO, reynolds, slip_speed


# --------------------------------------------------------------------------- the closures' range warnings
@njit(cache=True, parallel=True)
def reynolds_loop(slip, voidage, shape, out):
    """Superficial slip Reynolds numbers (floored, ``laws.reynolds``), for the validity-range warnings."""
    for i in numba.prange(slip.shape[0]):
        out[i] = reynolds(slip_speed(slip[i, 0], slip[i, 1], slip[i, 2]), voidage[i], shape[D_P], shape[RHO], shape[MU])
    return out


# --------------------------------------------------------------------------- the semi-implicit exchange
@njit(cache=True, parallel=True)
def exchange_terms(mass, c, velocity, force, gravity, lift, substep, substeps, dt, cells, weights, counts,
                   beta_out, source_out):
    """The bridge's semi-implicit exchange, per particle and deposited in one pass (``bridge`` step 3):
    ``R = (1 + h c / 2m)^(-2n)``, ``k = (1 - R) m / (c dt) - 1`` (0 where c = 0), coefficient
    ``m (1 - R) / dt``, exchanged momentum rate ``coefficient v - m k a - F_L`` with ``a = F / m + g``
    (``F`` contact + external force); their interpolation-weighted sums (row i's ``counts[i]`` cells and
    weights, ``interpolation.particle_weights``) go to ``beta_out`` (C,) and
    ``source_out`` (C, 3) (not yet divided by the cell volumes). ``lift`` may be (0, 3): none.
    Race-free like ``interpolation.scatter``: fixed particle blocks into private copies, added in
    block order."""
    n = cells.shape[0]
    chunks = scatter_blocks(n)
    ncell = beta_out.shape[0]
    partial = np.zeros((chunks, ncell, 4))
    has_lift = lift.shape[0] == n
    for chunk in numba.prange(chunks):
        block = partial[chunk]
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            m, ci = mass[i], c[i]
            q = 0.5 * substep * ci / m
            one_minus_r = -math.expm1(-2.0 * substeps * math.log1p(q))
            x = ci * substep * substeps / m
            k = one_minus_r / x - 1.0 if x > 0 else 0.0
            coefficient = m * one_minus_r / dt
            e0 = coefficient * velocity[i, 0] - m * k * (force[i, 0] / m + gravity[0])
            e1 = coefficient * velocity[i, 1] - m * k * (force[i, 1] / m + gravity[1])
            e2 = coefficient * velocity[i, 2] - m * k * (force[i, 2] / m + gravity[2])
            if has_lift:
                e0 -= lift[i, 0]
                e1 -= lift[i, 1]
                e2 -= lift[i, 2]
            for j in range(counts[i]):
                w = weights[i, j]
                cell = cells[i, j]
                block[cell, 0] += w * coefficient
                block[cell, 1] += w * e0
                block[cell, 2] += w * e1
                block[cell, 3] += w * e2
    for cell in numba.prange(ncell):
        for chunk in range(chunks):
            beta_out[cell] += partial[chunk, cell, 0]
            for d in range(3):
                source_out[cell, d] += partial[chunk, cell, d + 1]
    return beta_out, source_out


# --------------------------------------------------------------------------- the bridge's per-particle glue
@njit(cache=True, parallel=True)
def slip_at_particles(at_particles, velocity, minimum_voidage, fixed, voidage_out, slip_out):
    """From the gathered ``(voidage, u_x, u_y, u_z)`` rows: the voidage clipped to
    ``[minimum_voidage, 1]`` and the slip ``u - v`` (``u`` itself for fixed particles), written into
    ``voidage_out`` (N,) and ``slip_out`` (N, 3). The numpy form: ``np.clip(at[:, 0], minimum, 1)``,
    ``at[:, 1:] - v``."""
    for i in numba.prange(at_particles.shape[0]):
        voidage_out[i] = min(max(at_particles[i, 0], minimum_voidage), 1.0)
        for d in range(3):
            slip_out[i, d] = at_particles[i, 1 + d] if fixed else at_particles[i, 1 + d] - velocity[i, d]
    return voidage_out, slip_out


@njit(cache=True, inline="always")
def _sum_blocks(partial):
    """The rows of the per-block partial sums ``partial`` (blocks, k) added in block order (k,)."""
    total = np.zeros(partial.shape[1])
    for chunk in range(partial.shape[0]):
        for d in range(partial.shape[1]):
            total[d] += partial[chunk, d]
    return total


@njit(cache=True, parallel=True)
def particle_forces(at_particles, pressure_gradient_force, radius, half_length, mean_gradient, lift, explicit_drag,
                    fluid_velocity_out, external_out):
    """The gas's forces on the particles held over a coupling interval, from the gathered rows
    ``(u_x, u_y, u_z[, dp/dx, dp/dy, dp/dz])``: ``fluid_velocity_out = u`` and ``external_out =
    -V_p grad p + V_p G + F_L + F_D,explicit`` (``V_p`` the spherocylinder volume; ``G`` the imposed mean
    pressure gradient; ``lift`` / ``explicit_drag`` may be (0, 3): none). Returns the pressure part's
    sum over the particles, ``sum(-V_p grad p + V_p G)`` (3,), summed in fixed particle blocks, so the
    same on any number of threads."""
    n = at_particles.shape[0]
    chunks = scatter_blocks(n)
    partial = np.zeros((chunks, 3))
    has_lift = lift.shape[0] == n
    has_explicit = explicit_drag.shape[0] == n
    for chunk in numba.prange(chunks):
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            volume = spherocylinder_volume(radius[i], half_length[i])
            for d in range(3):
                fluid_velocity_out[i, d] = at_particles[i, d]
                f = 0.0
                if pressure_gradient_force:
                    f -= volume * at_particles[i, 3 + d]
                f += volume * mean_gradient[d]
                partial[chunk, d] += f
                if has_lift:
                    f += lift[i, d]
                if has_explicit:
                    f += explicit_drag[i, d]
                external_out[i, d] = f
    return _sum_blocks(partial)


@njit(cache=True, parallel=True)
def column_sums(values):
    """``values.sum(axis=0)`` of an (N, 3) array, summed in fixed particle blocks (the same on any number
    of threads; numpy's strided axis-0 sum cost 0.37 ms on 32,500 rows)."""
    n = values.shape[0]
    chunks = scatter_blocks(n)
    partial = np.zeros((chunks, values.shape[1]))
    for chunk in numba.prange(chunks):
        for i in range(chunk * n // chunks, (chunk + 1) * n // chunks):
            for d in range(values.shape[1]):
                partial[chunk, d] += values[i, d]
    return _sum_blocks(partial)
