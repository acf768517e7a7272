"""Packed-bed observables: solids fraction of the bed core and bed height."""
from __future__ import annotations

import numpy as np

from ..dem.particles import spherocylinder_volume


def particle_top(position, axis, radius, half_length):
    """Highest point of each particle [m] (centre + radius + half_length |a_z|)."""
    return position[:, 2] + radius + half_length * np.abs(axis[:, 2])


def bed_top(position, axis, radius, half_length, quantile=0.99):
    """Height [m] below which ``quantile`` of the particle tops lie (robust to stray particles)."""
    return float(np.quantile(particle_top(position, axis, radius, half_length), quantile))


def core_solids_fraction(position, axis, radius, half_length, lower, upper, periodic, floor=None, top=None,
                         wall_margin=None):
    """Solids fraction of the bed core: particle volume whose centres lie in the core region divided
    by the region's volume. The core excludes ``wall_margin`` [m] (default 2 particle lengths) next to
    side walls and the bottom and top 20 % of the bed, where packing is ordered or loose.
    """
    inside, region = core_particles(position, axis, radius, half_length, lower, upper, periodic, floor, top,
                                    wall_margin)
    if inside is None:
        return float("nan")
    volume = spherocylinder_volume(radius[inside], half_length[inside]).sum()
    return float(volume / region)


def core_particles(position, axis, radius, half_length, lower, upper, periodic, floor=None, top=None,
                   wall_margin=None):
    """Mask of the particles whose centres lie in the bed core (as ``core_solids_fraction`` defines it)
    and the core's volume [m^3]; ``(None, 0.0)`` when the margins leave no core."""
    lower = np.asarray(lower, float)
    upper = np.asarray(upper, float)
    extent = float(np.max(2.0 * (radius + half_length)))
    margin = 2.0 * extent if wall_margin is None else wall_margin
    floor = lower[2] if floor is None else floor
    top = bed_top(position, axis, radius, half_length) if top is None else top
    lo = lower.copy()
    hi = upper.copy()
    for d in range(2):
        if not periodic[d]:
            lo[d] += margin
            hi[d] -= margin
    height = top - floor
    lo[2] = floor + 0.2 * height
    hi[2] = floor + 0.8 * height
    if np.any(hi <= lo):
        return None, 0.0
    return np.all((position >= lo) & (position < hi), axis=1), float(np.prod(hi - lo))


def bed_packing(particles, lower, upper, periodic) -> dict:
    """What a gas flowing up through a packed bed sees of it: the solids fraction of its core (bottom
    and top fifth left out, wall regions kept: the gas crosses the whole section), the bed top [m],
    the core particles' axes and their mean sin^2 of the angle from the vertical (None for spheres)."""
    args = (particles.position, particles.axis, particles.radius, particles.half_length)
    top = bed_top(*args)
    fraction = core_solids_fraction(*args, lower, upper, periodic, top=top, wall_margin=0.0)
    core, _ = core_particles(*args, lower, upper, periodic, top=top, wall_margin=0.0)
    axes = particles.axis[core]
    return {"solids_fraction": fraction, "bed_top": top, "axes": axes,
            "sin2": None if np.all(particles.half_length == 0) else float(1.0 - np.mean(axes[:, 2] ** 2))}


def packed_bed_summary(particles, box) -> dict:
    """Bed top, core solids fraction and the equivalent packed height (solid volume / (area * fraction))."""
    args = (particles.position, particles.axis, particles.radius, particles.half_length)
    top = bed_top(*args)
    fraction = core_solids_fraction(*args, box.lower, box.upper, box.periodic, top=top)
    area = float(np.prod(np.asarray(box.upper[:2]) - np.asarray(box.lower[:2])))
    solid = float(spherocylinder_volume(particles.radius, particles.half_length).sum())
    return {
        "bed_top": top,
        "solids_fraction": fraction,
        "bed_height": solid / (area * fraction) if fraction > 0 else float("nan"),
        "mean_solids_fraction_below_top": solid / (area * (top - box.lower[2])),
    }


def bed_weight_per_area(particles, lower, upper, gravity) -> float:
    """Particle weight over the column's cross-section, W/A [Pa] (a fluidized bed's pressure drop):
    ``sum(m) |g| / ((x_hi - x_lo)(y_hi - y_lo))``."""
    area = (upper[0] - lower[0]) * (upper[1] - lower[1])
    return float(particles.mass.sum() * np.linalg.norm(gravity) / area)


def uniform_bed_umf(model, voidage, axes, particle_density, gravity=9.81):
    """Minimum fluidization velocity [m/s] that the drag closure ``model`` (a
    ``coupling.bridge.HydrodynamicModel``) gives a uniform fixed bed of gas fraction ``voidage``, with
    the particle axes ``axes`` (N, 3) and vertical flow: the superficial velocity ``U`` at which the mean
    drag holds the bed's weight, ``<c(U/eps)> U/eps = eps V_p (rho_p - rho_f) g``.

    In model A (``-eps grad p`` in the gas, ``-V_p grad p`` on the particles) the pressure gradient of a
    fixed bed is ``n <F_D> / eps``; it equals the bed weight per volume ``eps_s (rho_p - rho_f) g`` when the
    drag is ``eps`` times the buoyant weight. This is the closure's own Umf, independent of the CFD-DEM
    solution: a simulated defluidization ramp of a deep, wide bed approaches it; a shallow or narrow
    bed lies above it (looser bottom layer and bed surface, channelling along the walls).
    """
    from scipy.optimize import brentq

    weight = (1.0 - voidage) * (particle_density - model.density) * gravity  # buoyant bed weight per volume

    def excess(superficial):
        return uniform_bed_pressure_gradient(model, voidage, superficial, axes) - weight

    return float(brentq(excess, 1e-6, 100.0, xtol=1e-9))


def uniform_bed_pressure_gradient(model, voidage, superficial, axes):
    """-dp/dz [Pa/m] (gas head excluded) that the drag closure ``model`` gives a uniform fixed bed of gas
    fraction ``voidage`` with particle axes ``axes`` (N, 3) at superficial velocity ``superficial`` [m/s]:
    model A's ``n <c(U/eps)> (U/eps) / eps``, ``n = (1 - eps) / V_p`` particles per volume. At
    ``uniform_bed_umf`` it equals the buoyant bed weight per volume ``(1 - eps)(rho_p - rho_f) g``."""
    from ..coupling.closures import spherocylinder_shape
    axes = np.atleast_2d(np.asarray(axes, float))
    volume = float(spherocylinder_shape(model.diameter, max(model.length, model.diameter))[1])
    u = superficial / voidage
    slip = np.zeros_like(axes)
    slip[:, 2] = u
    c = model.drag_coefficient(slip, np.full(len(axes), float(voidage)), axes)
    return (1.0 - voidage) / volume * float(np.mean(c)) * u / voidage
