"""tools/pair_loop_reference.py: its C ports compute the same pairs as fvdem's kernel, so that what it
times is the same work (issue 16). Needs a C compiler."""
import shutil
import sys

import numpy as np
import pytest

from fvdem.dem.particles import ParticleArrays
from fvdem.dem.system import Box, ContactModel, DEMSystem

from conftest import DENSITY
from paths import TOOLS

sys.path.insert(0, str(TOOLS))

import pair_loop_reference  # noqa: E402


@pytest.mark.skipif(shutil.which("cc") is None and shutil.which("gcc") is None, reason="no C compiler")
def test_the_c_ports_equal_the_kernel_on_a_colliding_pack():
    rng = np.random.default_rng(3)
    n = 2000  # solids fraction 0.29: many contacts
    position = rng.uniform([0.002, 0.002, 0.002], [0.038, 0.038, 0.038], size=(n, 3))
    particles = ParticleArrays.create(position, 1.3e-3, 0.0, DENSITY, velocity=rng.normal(scale=0.3, size=(n, 3)))
    particles.angular_momentum[:] = rng.normal(scale=1e-8, size=(n, 3))
    dem = DEMSystem(particles, Box((0.0, 0.0, 0.0), (0.04, 0.04, 0.04)), ContactModel(normal_stiffness=800.0), 2e-5,
                    (0.0, 0.0, -9.81), skin=2e-4)
    for _ in range(30):  # contacts with histories: sticking, sliding, new and ended ones
        dem.step(1)
    touching = int(dem._row_contacts.sum())
    history = dem.history.copy()
    result = pair_loop_reference.measure(dem, calls=1, rounds=1)
    assert touching > 1000 and set(result) == {"numba", "c_scalar", "c_batched"}
    for name in ("c_scalar", "c_batched"):
        assert result[name]["max_relative_difference_to_numba"] < 1e-10, name
    np.testing.assert_array_equal(dem.history, history)  # the system's state is left as it was
