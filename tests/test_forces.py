"""The sphere contact kernel against the general (any-shape) one: the same contacts, forces, torques,
histories and overlaps, identical or polydisperse spheres, over steps of a colliding pack in which
contacts start and end and the list is rebuilt."""
import numpy as np
import pytest

from fvdem.dem.forces import pair_forces, sphere_pair_forces
from fvdem.dem.system import Box, ContactModel, DEMSystem
from fvdem.dem.particles import ParticleArrays

from conftest import DENSITY


def _general(s):
    """The general kernel on copies of the state the sphere kernel works on."""
    p = s.particles
    history, partner, owner = s.history.copy(), s._partner_result.copy(), s._owner_sum.copy()
    overlap, contacts = s._row_max_overlap.copy(), s._row_contacts.copy()
    pair_forces(p.position, p.velocity, p.angular_velocity, p.axis, p.radius, p.half_length, p.mass, p.inertia,
                s.row_start, s.neighbours, history, s._partner_slot, owner, partner, overlap, contacts, s._box_len,
                s._periodic, s.params, s._uniform)
    return history, partner, owner, overlap, contacts


def _sphere(s):
    p = s.particles
    history, partner, owner = s.history.copy(), s._partner_result.copy(), s._owner_sum.copy()
    overlap, contacts = s._row_max_overlap.copy(), s._row_contacts.copy()
    sphere_pair_forces(p.position, p.velocity, p.angular_velocity, p.radius, p.mass, p.inertia, s.row_start,
                       s.neighbours, history, s._partner_slot, owner, partner, overlap, contacts, s._box_len,
                       s._periodic, s.params, s._uniform)
    return history, partner, owner, overlap, contacts


@pytest.mark.parametrize("polydisperse", [False, True])
def test_the_sphere_kernel_equals_the_general_kernel_on_a_colliding_pack(polydisperse):
    rng = np.random.default_rng(5)
    n = 300
    box = Box((0.0, 0.0, 0.0), (0.04, 0.04, 0.04), (True, True, False))
    radius = rng.uniform(1.0e-3, 1.6e-3, n) if polydisperse else np.full(n, 1.3e-3)
    position = rng.uniform([0, 0, 0.002], [0.04, 0.04, 0.038], size=(n, 3))
    particles = ParticleArrays.create(position, radius, 0.0, DENSITY,
                                      velocity=rng.normal(scale=0.3, size=(n, 3)))
    particles.angular_momentum[:] = rng.normal(scale=1e-8, size=(n, 3))
    s = DEMSystem(particles, box, ContactModel(normal_stiffness=800.0), 2e-5, (0.0, 0.0, -9.81), skin=2e-4)
    assert (s._uniform[0] >= 0.0) == (not polydisperse)
    checked = 0
    for _ in range(60):
        s.step(1)
        general, sphere = _general(s), _sphere(s)
        touching = int(general[4].sum())
        checked += touching
        for a, b, name in zip(general, sphere, ("history", "partner", "owner", "max overlap", "contacts")):
            scale = max(float(np.abs(a).max()), 1e-300)
            assert np.abs(a - b).max() <= 1e-12 * scale, name
    assert checked > 500  # many contacts compared (the random pack starts overlapped and collides)
    assert s.rebuild_count > 1
