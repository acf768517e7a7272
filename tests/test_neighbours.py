"""Neighbour lists: complete against brute force; contact histories survive rebuilds and re-sorting."""
import numpy as np

from fvdem.dem.geometry import segment_distance
from fvdem.dem.system import Box, ContactModel

from conftest import by_id, make_system


def test_half_list_is_complete_and_unique_against_brute_force():
    rng = np.random.default_rng(7)
    n = 400
    r, h = 1.5e-3, 4.5e-3
    box = Box((0.0, 0.0, 0.0), (0.06, 0.05, 0.07), (True, False, True))
    pos = rng.uniform([0, 0.003, 0], [0.06, 0.047, 0.07], size=(n, 3))
    s = make_system(pos, r, h, axis=rng.normal(size=(n, 3)), box=box)
    p = s.particles
    listed = set()
    for i in range(n):
        for slot in range(s.row_start[i], s.row_start[i + 1]):
            j = s.neighbours[slot]
            assert j > i
            key = (p.ids[i], p.ids[j])
            assert key not in listed
            listed.add(key)
    length = box.length
    expected = set()
    for i in range(n):
        for j in range(i + 1, n):
            d = p.position[i] - p.position[j]
            for ax in (0, 2):  # periodic axes: minimum image
                d[ax] -= length[ax] * np.round(d[ax] / length[ax])
            if segment_distance(d, p.axis[i], h, np.zeros(3), p.axis[j], h) < 2 * r + s.skin:
                a, b = p.ids[i], p.ids[j]
                expected.add((a, b) if (a, b) in listed else (b, a))
    assert expected == listed


def _sliding_pair(skin):
    """A sphere pressed on another and dragged sideways: a long-lived sliding/sticking contact."""
    d = 4e-3
    s = make_system([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05 + d - 1e-7]], d / 2, velocity=[[0, 0, 0], [0.02, 0.01, 0]],
                    contact=ContactModel(friction=0.5, rolling_friction=0.1), dt=2e-6)
    s.skin = skin
    s.rebuild()
    s.compute_forces()
    return s


def test_history_survives_rebuilds():
    """Rebuilding every step (tiny skin, re-sorting) gives the trajectory of never rebuilding."""
    never = _sliding_pair(skin=2e-3)
    always = _sliding_pair(skin=1e-9)
    force = np.array([[0, 0, 2e-3], [0, 0, -2e-3]])  # press the pair together (equilibrium overlap F/k = 1e-7 m)
    for s in (never, always):
        for _ in range(400):
            s.particles.external_force[:] = force[s.particles.ids]
            s.step(1)
    assert always.rebuild_count > 300 and never.rebuild_count == 2  # construction + helper
    assert np.abs(never.history[:, :3]).max() > 0  # the contact carried a tangential history
    np.testing.assert_allclose(by_id(always, "velocity"), by_id(never, "velocity"), rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(by_id(always, "angular_velocity"), by_id(never, "angular_velocity"),
                               rtol=1e-10, atol=1e-12)
