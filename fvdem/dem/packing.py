"""Dense random packings in a fully periodic box by compression.

Random sequential insertion jams near a solids fraction of 0.35 (spheres) and lower for elongated
particles; the suspensions of Derksen reach 0.48. ``compress_periodic`` inserts the particles at a
fraction insertion can reach into a proportionally larger periodic box, then shrinks the box in small
affine steps (every position scaled with the box, as LAMMPS' ``fix deform ... remap x``), letting
frictionless, damped contacts push apart the small overlaps each step creates, until the box has its
target size. Without gravity or friction the orientations stay random (isotropic), which Derksen's
initial state also is.
"""
from __future__ import annotations

import math

import numpy as np

from .insertion import insert_particles
from .particles import ParticleArrays
from .system import Box, ContactModel, DEMSystem, SimulationError

INSERTABLE_FRACTION = 0.25  # what random sequential insertion reaches quickly for any aspect ratio


def compress_periodic(count: int, radius: float, half_length: float, density: float, box_length,
                      seed: int = 1, orientation: str = "random", shrink_per_stage: float = 0.02,
                      steps_per_stage: int = 20, tolerance: float = 0.01) -> ParticleArrays:
    """``count`` particles (sphere radius / spherocylinder radius and half cylinder length [m],
    density [kg/m^3]) at random positions and orientations in the periodic box ``[0, box_length)``
    [m], with the largest overlap below ``tolerance`` x diameter. Raises ``ValueError`` when the box
    cannot be packed (beyond about 0.55 for spheres)."""
    box_length = np.asarray(box_length, float)
    volume = math.pi * radius ** 2 * (2.0 * half_length) + 4.0 / 3.0 * math.pi * radius ** 3
    fraction = count * volume / float(np.prod(box_length))
    if fraction > 0.55:
        raise ValueError(f"solids fraction {fraction:.3f} above 0.55: a random packing this dense cannot be "
                         "made by compression")
    scale = max(1.0, (fraction / INSERTABLE_FRACTION) ** (1.0 / 3.0))
    start = box_length * scale
    position, axis = insert_particles(count, radius, half_length, (0.0, 0.0, 0.0), tuple(start), orientation,
                                      0.0, seed)
    particles = ParticleArrays.create(position, radius, half_length, density, axis=axis)
    # contacts of the compression: frictionless, strongly damped; time in units of the collision time
    mass = float(particles.mass[0])
    contact = ContactModel(normal_stiffness=1.0e6 * mass, restitution=0.2, friction=0.0,
                           rolling_friction=0.0)
    dt = contact.collision_time(mass) / 15.0
    current = start.copy()
    stages = 0
    while True:
        target = np.maximum(box_length, current * (1.0 - shrink_per_stage))
        particles.position *= target / current
        current = target
        system = DEMSystem(particles, Box((0.0, 0.0, 0.0), tuple(current), (True, True, True)), contact, dt,
                           (0.0, 0.0, 0.0))
        done = np.allclose(current, box_length)
        for _ in range(steps_per_stage if not done else 20 * steps_per_stage):
            system.step(10)
            particles.velocity *= 0.5  # drain the energy of the pushed-apart overlaps
            particles.angular_momentum *= 0.5
            if done and system.diagnostics()["max_overlap_over_diameter"] < tolerance:
                break
        stages += 1
        if done:
            break
        if stages > 2000:
            raise SimulationError("compression did not reach the target box in 2,000 stages")
    overlap = system.diagnostics()["max_overlap_over_diameter"]
    if overlap > tolerance:
        raise ValueError(f"compressed packing still overlaps by {overlap:.3g} diameters at solids fraction "
                         f"{fraction:.3f}: too dense for this shape")
    particles.velocity[:] = 0.0
    particles.angular_momentum[:] = 0.0
    particles.angular_velocity[:] = 0.0
    particles.contact_force[:] = 0.0
    particles.contact_torque[:] = 0.0
    return particles
