"""Shared helpers: tiny DEM scenes built directly from the library, and a drifting bed for the gas solver.

The tests in the folders below (tests/README.md) import them with ``from conftest import ...``, and the helper
modules beside this file the same way (``paths``, ``output_keys``, ``study_runs``): pytest's default import
mode puts tests/, this file's folder, on ``sys.path`` when it loads this file, before any test module. Test
files are imported by their basename, so no two may share one across the folders."""
import os

# `make test` runs the suite on two pytest-xdist workers; each test's numba threads (all cores) then share the
# cores with the other worker's. With OpenMP's default spinning wait a thread waiting at the end of a parallel
# loop holds a core the other worker needs: four numba-heavy tests took 229-254 s on two workers against 51 s
# on one; with waiting threads asleep, 42 s (2 cores, 2026-12-05, docs/benchmarks.md). Before numba loads its
# OpenMP library, in the workers and the runs they start; a user's own setting is kept
if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.setdefault("OMP_WAIT_POLICY", "passive")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from fvdem.dem.particles import ParticleArrays  # noqa: E402
from fvdem.dem.system import Box, ContactModel, DEMSystem  # noqa: E402

SPHERE_D = 5.3e-3
DENSITY = 1442.0
PAPER_STIFFNESS = 2.0e4  # [N/m], Mema et al. (2020) Table 5: the spring the small DEM scenes were written for


def paper_contact(**parameters) -> ContactModel:
    """The contact law with the paper's spring (``PAPER_STIFFNESS``), the other parameters the case's defaults
    unless given."""
    return ContactModel(**{"normal_stiffness": PAPER_STIFFNESS, **parameters})


def make_system(position, radius, half_length=0.0, velocity=None, axis=None, box=None, contact=None,
                dt=None, gravity=(0.0, 0.0, 0.0), steps_per_collision=50, skin=None):
    """A DEM system of a few particles; dt defaults to collision time / ``steps_per_collision``;
    ``skin=None`` is the adaptive skin."""
    particles = ParticleArrays.create(np.asarray(position, float), radius, half_length, DENSITY, axis=axis,
                                      velocity=None if velocity is None else np.asarray(velocity, float))
    box = box or Box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), (True, True, True))
    contact = contact or paper_contact()
    if dt is None:
        dt = contact.collision_time(float(particles.mass.min())) / steps_per_collision
    return DEMSystem(particles, box, contact, dt, gravity, skin)


def by_id(system, name):
    p = system.particles
    return getattr(p, name)[np.argsort(p.ids)]


@pytest.fixture
def system_factory():
    return make_system


def step_drifting_bed(solver, k, dt=5e-4):
    """One gas step under a bed-like voidage (a travelling wave around 0.5 below z = 0.15 m) and its
    Ergun-like drag coefficient, at step ``k`` of the drift."""
    z = solver.mesh.cell_centers[:, 2]
    wave = 0.5 + 0.1 * np.sin(2 * np.pi * (5.0 * k * dt + 4.0 * z))
    solver.voidage_old[:] = solver.voidage
    solver.voidage[:] = np.where(z < 0.15, wave, 1.0)
    solver.beta[:] = np.where(z < 0.15, 3e4 * (1 - solver.voidage) ** 2 / solver.voidage, 0.0)
    solver.step(dt)
