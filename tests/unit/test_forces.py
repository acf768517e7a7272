"""The contact kernel: the sphere path against the general (any-shape) one, the race-free blocks
against one row after another, the same result on any number of threads, and the blocks' cut."""

import numba
import numpy as np
import pytest

from fvdem.dem.forces import contact_forces
from fvdem.dem.neighbours import contact_blocks
from fvdem.dem.system import Box, ContactModel, DEMSystem
from fvdem.dem.particles import ParticleArrays

from conftest import DENSITY, make_system
from paths import DATA


def _forces(s, spheres, blocks=None):
    """The kernel on copies of the system's state: ``(force, torque, history, wall history, max overlap,
    contacts, wall contacts)``. ``blocks``: ``(block_start, deferred, deferred_rows)``, by default the
    system's own."""
    p = s.particles
    n = p.count
    block_start, deferred, deferred_rows = s._blocks if blocks is None else blocks
    out = (np.full((n, 3), np.nan), np.full((n, 3), np.nan), s.history.copy(), s.wall_history.copy(),
           s._row_max_overlap.copy(), s._row_contacts.copy(), s._row_wall_contacts.copy())
    contact_forces(spheres, p.position, p.velocity, p.angular_velocity, p.axis, p.radius, p.half_length, p.mass,
                   p.inertia, s.row_start, s.neighbours, out[2], block_start, deferred, deferred_rows, s._walls,
                   s._box_lo, s._box_hi, out[3], s.wall_mask.copy(), s._box_len, s._periodic, s.params, s._uniform,
                   out[0], out[1], out[4], out[5], out[6])
    return out


def _one_by_one(n):
    """Blocks that defer every row: the kernel then runs the rows one after another, in order."""
    return np.array([0, n], np.int64), np.ones(n, np.uint8), np.arange(n, dtype=np.int64)


NAMES = ("force", "torque", "history", "wall history", "max overlap", "contacts", "wall contacts")


def _close(a, b, tolerance):
    for x, y, name in zip(a, b, NAMES):
        scale = max(float(np.abs(x).max()), 1e-300)
        assert np.abs(x - y).max() <= tolerance * scale, name


def _colliding_spheres(polydisperse, periodic=(True, True, False), n=300):
    rng = np.random.default_rng(5)
    box = Box((0.0, 0.0, 0.0), (0.04, 0.04, 0.04), periodic)
    radius = rng.uniform(1.0e-3, 1.6e-3, n) if polydisperse else np.full(n, 1.3e-3)
    low, high = (0.0, 0.04) if periodic[2] else (0.002, 0.038)  # a periodic z axis: pairs across it
    position = rng.uniform([0, 0, low], [0.04, 0.04, high], size=(n, 3))
    particles = ParticleArrays.create(position, radius, 0.0, DENSITY, velocity=rng.normal(scale=0.3, size=(n, 3)))
    particles.angular_momentum[:] = rng.normal(scale=1e-8, size=(n, 3))
    return DEMSystem(particles, box, ContactModel(normal_stiffness=800.0), 2e-5, (0.0, 0.0, -9.81), skin=2e-4)


def _colliding_rods(periodic, n=200):
    rng = np.random.default_rng(8)
    box = Box((0.0, 0.0, 0.0), (0.05, 0.05, 0.06), periodic)
    position = rng.uniform([0.0, 0.0, 0.006], [0.05, 0.05, 0.054], size=(n, 3))
    particles = ParticleArrays.create(position, 1.5e-3, 4.5e-3, DENSITY, axis=rng.normal(size=(n, 3)),
                                      velocity=rng.normal(scale=0.3, size=(n, 3)))
    particles.angular_momentum[:] = rng.normal(scale=1e-9, size=(n, 3))
    return DEMSystem(particles, box, ContactModel(normal_stiffness=800.0), 2e-5, (0.0, 0.0, -9.81), skin=3e-4)


@pytest.mark.parametrize("polydisperse", [False, True])
def test_the_sphere_path_equals_the_general_path_on_a_colliding_pack(polydisperse):
    s = _colliding_spheres(polydisperse)
    assert (s._uniform[0] >= 0.0) == (not polydisperse)
    checked = 0
    for _ in range(60):
        s.step(1)
        general, sphere = _forces(s, False), _forces(s, True)
        checked += int(general[5].sum())
        _close(general, sphere, 1e-12)
    assert checked > 500  # many contacts compared (the random pack starts overlapped and collides)
    assert s.rebuild_count > 1


@pytest.mark.parametrize("shape, periodic", [("sphere", (True, True, False)), ("sphere", (True, True, True)),
                                             ("rod", (False, False, False)), ("rod", (True, True, True))])
def test_blocks_equal_one_row_after_another_and_any_thread_count(shape, periodic):
    """The blocked kernel sums each particle's contributions in another order than row by row: equal to
    round-off; and the same bits on one and two threads (the cut does not depend on threads)."""
    s = _colliding_spheres(False, periodic) if shape == "sphere" else _colliding_rods(periodic)
    spheres = shape == "sphere"
    threads = numba.get_num_threads()
    checked = 0
    try:
        for _ in range(25):
            s.step(1)
            blocked = _forces(s, spheres)
            checked += int(blocked[5].sum() + blocked[6].sum())
            _close(blocked, _forces(s, spheres, _one_by_one(s.particles.count)), 1e-12)
            numba.set_num_threads(1)
            single = _forces(s, spheres)
            numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
            for a, b, name in zip(blocked, single, NAMES):
                np.testing.assert_array_equal(a, b, err_msg=name)
    finally:
        numba.set_num_threads(threads)
    assert checked > 200  # pair and wall contacts compared (the random pack starts overlapped)
    assert len(s._blocks[0]) > 3  # several blocks, so both phases ran


@pytest.mark.parametrize("periodic_z", [False, True])
def test_the_blocks_keep_every_row_race_free(periodic_z):
    """Each row's partners lie in its own block or the next (two blocks running at once are at least
    two apart); rows that reach further (across a periodic z boundary) are deferred; every block but
    the last is at least ``cell_span`` cell layers deep."""
    s = _colliding_spheres(False, (True, True, periodic_z), n=600)
    s.step(3)
    block_start, deferred, deferred_rows = s._blocks
    n = s.particles.count
    block = np.searchsorted(block_start, np.arange(n), side="right") - 1
    rows = np.repeat(np.arange(n), np.diff(s.row_start))
    reach = block[s.neighbours] - block[rows]
    assert np.all(s.neighbours > rows)
    ok = (reach >= 0) & (reach <= 1)
    assert np.all(deferred[rows[~ok]] == 1)
    assert set(np.flatnonzero(deferred)) == set(deferred_rows)
    flagged = np.unique(rows[~ok])
    np.testing.assert_array_equal(np.sort(deferred_rows), flagged)  # only the rows that must be
    if periodic_z:
        assert len(deferred_rows) > 0  # pairs across the z boundary exist in this dense pack
    else:
        assert len(deferred_rows) == 0
    layers = s._cell_of // int(s._n_cells[0] * s._n_cells[1])
    for b in range(len(block_start) - 2):
        lo, hi = block_start[b], block_start[b + 1]
        assert layers[hi] - layers[lo] >= s.cell_span
        assert layers[hi] != layers[hi - 1]  # cut between layers


def test_one_block_when_the_list_is_small():
    row_start = np.array([0, 1, 1], np.int64)
    block_start, deferred, rows = contact_blocks(row_start, np.array([1], np.int32), np.array([0, 5], np.int64),
                                                 10, 1, 32)
    np.testing.assert_array_equal(block_start, [0, 2])
    assert not deferred.any() and len(rows) == 0
    block_start, deferred, rows = contact_blocks(np.zeros(1, np.int64), np.zeros(0, np.int32),
                                                 np.zeros(0, np.int64), 10, 1, 32)
    np.testing.assert_array_equal(block_start, [0, 0])


def _rod_pack():
    """144 nearly upright rods 0.2 mm apart in a walled box, random velocities and spins, gravity
    and the coupling's implicit drag: 51 touching pairs and 2 wall contacts after 40 steps."""
    from fvdem.dem.system import Box
    rng = np.random.default_rng(11)
    grid = np.stack(np.meshgrid(np.arange(6), np.arange(6), np.arange(4), indexing="ij"), -1).reshape(-1, 3)
    position = np.array([0.0045, 0.0045, 0.0065]) + grid * [0.0032, 0.0032, 0.0125] + rng.uniform(-1e-4, 1e-4, (len(grid), 3))
    axis = np.array([0.0, 0.0, 1.0]) + rng.normal(0, 0.05, (len(grid), 3))
    s = make_system(position, 1.5e-3, 4.5e-3, axis=axis, velocity=rng.normal(0, 0.2, (len(grid), 3)),
                    box=Box((0.0, 0.0, 0.0), (0.0225, 0.0225, 0.06), (False, False, False)), gravity=(0.0, 0.0, -9.81))
    p = s.particles
    p.angular_momentum[:] = rng.normal(0, 1, p.angular_momentum.shape) * p.inertia[:, :1] * 200.0
    s.implicit_drag = True
    p.drag_coefficient[:] = 2e-4
    p.fluid_velocity[:] = [0.0, 0.0, 0.5]
    return s


def test_the_rods_step_is_the_one_before_its_speed_work():
    """Issue 31 made the rods' step cheaper (branch-free clamps in the segment geometry, the pair constants
    read once per row, a capsule test before the segment test in the list, series for the drift's small
    rotation angles): the same 40 steps of a colliding pack of rods as the base commit b85eb78 computed
    them (``tests/data/rod_pack_b85eb78.npz``), to round-off."""
    s = _rod_pack()
    s.step(40)
    p = s.particles
    order = np.argsort(p.ids)
    with np.load(DATA / "rod_pack_b85eb78.npz") as ref:
        assert int(s._row_contacts.sum()) == int(ref["touching"]) == 51
        assert int(s._row_wall_contacts.sum()) == int(ref["walls"])
        assert s.rebuild_count == int(ref["rebuilds"])
        for name in ("position", "velocity", "angular_momentum", "axis", "contact_force", "contact_torque"):
            value, expected = getattr(p, name)[order], ref[name]
            assert np.abs(value - expected).max() <= 1e-12 * np.abs(expected).max(), name
