"""Neighbour lists: complete against brute force; contact histories survive rebuilds and re-sorting."""
import numpy as np
import pytest

from fvdem.dem.geometry import segment_distance
from fvdem.dem.system import SKIN_RANGE, SKIN_TARGET_INTERVAL, Box, ContactModel, adapted_skin

from conftest import by_id, make_system, paper_contact


def _listed_pairs(system):
    p = system.particles
    return {(p.ids[i], p.ids[system.neighbours[slot]]) for i in range(p.count)
            for slot in range(system.row_start[i], system.row_start[i + 1])}


def _brute_force_pairs(system):
    """Pairs (ids, in the order the list holds them) whose axis segments are within the radii plus
    the skin, every pair tested (minimum image on periodic axes)."""
    p = system.particles
    listed = _listed_pairs(system)
    length, periodic = system.box.length, np.asarray(system.box.periodic, bool)
    expected = set()
    for i in range(p.count):
        for j in range(i + 1, p.count):
            d = p.position[i] - p.position[j]
            d[periodic] -= length[periodic] * np.round(d[periodic] / length[periodic])
            if segment_distance(d, p.axis[i], p.half_length[i], np.zeros(3), p.axis[j],
                                p.half_length[j]) < p.radius[i] + p.radius[j] + system.skin:
                a, b = p.ids[i], p.ids[j]
                expected.add((a, b) if (a, b) in listed else (b, a))
    return expected


@pytest.mark.parametrize("skin", [None, 7.5e-3])
@pytest.mark.parametrize("span", [None, 1, 3])
def test_half_list_is_complete_and_unique_against_brute_force(skin, span):
    """Also with a skin wide enough that rows overflow the one-pass build's first row capacity, and
    with cells of a whole reach (span 1), of a half (the rods' default) and of a third, searched
    1, 2 or 3 cells either way, across two periodic axes."""
    rng = np.random.default_rng(7)
    n = 400
    r, h = 1.5e-3, 4.5e-3
    box = Box((0.0, 0.0, 0.0), (0.06, 0.05, 0.07), (True, False, True))
    pos = rng.uniform([0, 0.003, 0], [0.06, 0.047, 0.07], size=(n, 3))
    s = make_system(pos, r, h, axis=rng.normal(size=(n, 3)), box=box, skin=skin)
    assert s.cell_span == 2  # rods: half-reach cells
    if span is not None:
        s.cell_span = span
        s._cell_grid()
        s.rebuild()
    if skin is not None:
        assert np.diff(s.row_start).max() > 16  # the buffer was widened and the build redone
    for i in range(n):
        assert np.all(s.neighbours[s.row_start[i]:s.row_start[i + 1]] > i)
    listed = _listed_pairs(s)
    assert len(listed) == len(s.neighbours)  # no pair twice
    assert _brute_force_pairs(s) == listed


def test_a_mixture_of_sizes_and_shapes_is_listed_completely():
    """Spheres and rods of several radii and lengths: the rods' scan bounds every candidate's reach by
    the largest particle's, and the point-segment and segment-segment tests use each pair's own sizes."""
    rng = np.random.default_rng(11)
    n = 300
    r = rng.choice([1.0e-3, 1.5e-3, 2.5e-3], n)
    h = rng.choice([0.0, 2.0e-3, 4.5e-3, 8.0e-3], n)
    pos = rng.uniform(0.01, 0.07, size=(n, 3))
    s = make_system(pos, r, h, axis=rng.normal(size=(n, 3)), box=Box((0.0, 0.0, 0.0), (0.08, 0.08, 0.08)),
                    skin=2e-3)
    assert s.track_orientation and len(s.neighbours) > n
    assert _brute_force_pairs(s) == _listed_pairs(s)


def test_a_row_that_exactly_fills_the_buffer_widens_it():
    """The rods' build writes each tested candidate at the row's next slot, the last one while the row is
    full, so a row is complete only below the buffer's width: one that fills it exactly must be redone."""
    rng = np.random.default_rng(5)
    n = 400
    pos = rng.uniform(0.005, 0.045, size=(n, 3))
    s = make_system(pos, 1.5e-3, 4.5e-3, axis=rng.normal(size=(n, 3)),
                    box=Box((0.0, 0.0, 0.0), (0.05, 0.05, 0.05)), skin=3e-3)
    reference = _listed_pairs(s)
    longest = int(np.diff(s.row_start).max())
    s._row_buffer = np.empty((n, longest), np.int32)
    s.rebuild()
    assert s._row_buffer.shape[1] > longest
    assert _listed_pairs(s) == reference == _brute_force_pairs(s)


def _sliding_pair(skin):
    """A sphere pressed on another and dragged sideways: a long-lived sliding/sticking contact."""
    d = 4e-3
    s = make_system([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05 + d - 1e-7]], d / 2, velocity=[[0, 0, 0], [0.02, 0.01, 0]],
                    contact=paper_contact(friction=0.5, rolling_friction=0.1), dt=2e-6, skin=skin)
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


def test_histories_follow_their_pairs_through_a_resorted_list():
    """``carry_history`` against the plain search it replaced: every new slot's pair looked up in the old
    rows of either particle (the history negated when the owner changed, new pairs at zero), on random
    half lists before and after a random permutation that keeps most pairs, drops some and adds others."""
    from fvdem.dem.neighbours import carry_history, row_offsets
    rng = np.random.default_rng(7)
    n = 60
    pairs = {tuple(sorted(rng.choice(n, 2, replace=False))) for _ in range(400)}
    old_pairs = sorted(pairs)
    flags = {pair: rng.random() < 0.4 for pair in old_pairs}  # touching: a history; the rest hold zeros
    history = {pair: (np.append(rng.normal(size=3), 1.0) if flags[pair] else np.zeros(4)) for pair in old_pairs}

    def csr(pair_list, count):
        rows = [[] for _ in range(count)]
        for a, b in pair_list:
            rows[min(a, b)].append(max(a, b))
        for row in rows:
            rng.shuffle(row)  # cell-scan order, not sorted
        start = row_offsets(np.array([len(r) for r in rows], np.int64))
        return start, np.array([j for r in rows for j in r], np.int32), rows

    old_start, old_neighbours, old_rows = csr(old_pairs, n)
    old_history = np.array([history[(i, j)] for i in range(n) for j in old_rows[i]]).reshape(-1, 4)
    new_to_old = rng.permutation(n)
    old_to_new = np.empty(n, np.int64)
    old_to_new[new_to_old] = np.arange(n)
    kept = [p for p in old_pairs if flags[p] or rng.random() < 0.7]  # every touching pair stays listed
    added = [tuple(rng.choice(n, 2, replace=False)) for _ in range(50)]
    new_pairs = {tuple(sorted((old_to_new[a], old_to_new[b]))) for a, b in kept + added}
    new_start, new_neighbours, _ = csr(sorted(new_pairs), n)
    new_history = np.zeros((len(new_neighbours), 4))
    carry_history(old_start, old_neighbours, old_history, new_start, new_neighbours, new_history, old_to_new)

    expected = np.zeros_like(new_history)  # the search it replaced
    for i in range(n):
        for slot in range(new_start[i], new_start[i + 1]):
            oi, oj = new_to_old[i], new_to_old[new_neighbours[slot]]
            for src in range(old_start[oi], old_start[oi + 1]):
                if old_neighbours[src] == oj:
                    expected[slot] = old_history[src]
            for src in range(old_start[oj], old_start[oj + 1]):
                if old_neighbours[src] == oi:
                    expected[slot, :3], expected[slot, 3] = -old_history[src, :3], old_history[src, 3]
    assert np.array_equal(new_history, expected)
    assert (new_history[:, 3] == 1.0).sum() == sum(flags.values()) > 100  # every contact found again
    flipped = sum(old_to_new[a] > old_to_new[b] for (a, b) in old_pairs if flags[(a, b)])
    assert flipped > 20  # owners changed for many: the negation is exercised


def test_adapted_skin_converges_to_the_target_interval_within_bounds():
    """If a list lasts in proportion to its skin (ballistic motion), the rule reaches the target
    interval geometrically; each change is at most a factor 2 and the bounds hold."""
    speed = 1e-5  # m per step: a list with skin s lasts s / (2 speed) steps
    skin = 1e-4
    for _ in range(30):
        skin = adapted_skin(skin, int(skin / (2 * speed)), 1e-5, 1e-2)
    assert abs(skin / (2 * speed) - SKIN_TARGET_INTERVAL) <= 1.0
    assert adapted_skin(1e-3, 1, 1e-5, 1e-2) == 2e-3  # factor capped at 2
    assert adapted_skin(1e-3, 10_000, 1e-5, 1e-2) == 5e-4  # and at 1/2
    assert adapted_skin(1e-3, 10_000, 9e-4, 1e-2) == 9e-4  # floor
    assert adapted_skin(1e-3, 1, 1e-5, 1.5e-3) == 1.5e-3  # ceiling


def _granular_gas(skin, steps=300):
    rng = np.random.default_rng(3)
    n, d = 150, 2e-3
    box = Box((0.0, 0.0, 0.0), (0.03, 0.03, 0.03), (True, True, True))
    side = np.arange(6) * 0.005 + 0.0025
    grid = np.stack(np.meshgrid(side, side, side, indexing="ij"), -1).reshape(-1, 3)[:n]
    s = make_system(grid, d / 2, velocity=rng.normal(scale=0.5, size=(n, 3)), box=box, dt=2e-5,
                    contact=ContactModel(normal_stiffness=800.0), skin=skin)
    intervals = []
    last = 0
    s.contact_steps = 0  # pair contacts summed over steps: the gas collides
    for _ in range(steps):
        before = s.rebuild_count
        s.step(1)
        s.contact_steps += int(s._row_contacts.sum())
        if s.rebuild_count != before:
            intervals.append(s.step_count - last)
            last = s.step_count
    return s, intervals


def test_adaptive_skin_keeps_the_list_complete_and_reaches_its_interval():
    """A colliding granular gas at 0.5 m/s: the adaptive skin grows from its floor until lists last
    about the target interval, and the trajectory is that of a list rebuilt every step."""
    adaptive, intervals = _granular_gas(None)
    every_step, _ = _granular_gas(1e-9)
    assert every_step.rebuild_count >= 299
    floor = SKIN_RANGE[0] * 2e-3
    assert adaptive.skin > 2 * floor  # it grew: at the floor the gas rebuilt every ~1 step
    late = intervals[len(intervals) // 2:]
    assert SKIN_TARGET_INTERVAL / 2 <= np.mean(late) <= 2 * SKIN_TARGET_INTERVAL
    assert adaptive.contact_steps > 100  # collisions happened: the histories and sort order were exercised
    np.testing.assert_allclose(by_id(adaptive, "position"), by_id(every_step, "position"), rtol=0, atol=1e-12)
    np.testing.assert_allclose(by_id(adaptive, "velocity"), by_id(every_step, "velocity"), rtol=1e-9, atol=1e-12)


def test_adaptive_skin_stays_at_its_floor_at_rest_and_under_its_ceiling():
    s = make_system([[0.05, 0.05, 0.05], [0.05, 0.05, 0.052]], 1e-3, skin=None)
    floor = s.skin
    s.step(2000)
    assert s.skin == floor == SKIN_RANGE[0] * 2e-3 and s.rebuild_count == 1
    s.rebuild()  # a rebuild asked for from outside keeps the skin
    assert s.skin == floor
    for _ in range(8):
        s.rebuild(adapt=True)  # lists that lasted no step: the skin doubles each time, up to its ceiling
    assert s.skin == SKIN_RANGE[1] * 2e-3


def test_adaptive_skin_and_its_last_rebuild_survive_a_checkpoint():
    s, _ = _granular_gas(None, steps=120)
    state = s.state()
    t, _ = _granular_gas(None, steps=1)
    t.restore(state)
    assert t.skin == s.skin and t._last_rebuild_step == s._last_rebuild_step
    for sys_ in (s, t):
        sys_.step(100)
    np.testing.assert_array_equal(by_id(t, "position"), by_id(s, "position"))
    assert t.rebuild_count == s.rebuild_count


def test_permutations_gather_every_array_and_reuse_the_arrays_left_behind():
    """``ParticleArrays.permute`` gives each field the rows ``old[order]`` (every dtype and shape), twice
    in a row, gathering the second time into the arrays the first left behind."""
    from fvdem.dem.particles import ParticleArrays
    rng = np.random.default_rng(3)
    n = 50
    p = ParticleArrays.create(rng.uniform(size=(n, 3)), rng.uniform(1e-3, 2e-3, n), 0.0, 1000.0,
                              colour=rng.integers(0, 2, n), velocity=rng.normal(size=(n, 3)))
    p.ids[:] = rng.permutation(n)
    fields = {k: v.copy() for k, v in p.as_dict().items()}
    first, second = rng.permutation(n), rng.permutation(n)
    p.permute(first)
    after_first = {k: id(v) for k, v in p.as_dict().items()}
    p.permute(second)
    for name, old in fields.items():
        new = p.as_dict()[name]
        assert new.dtype == old.dtype and new.shape == old.shape, name
        np.testing.assert_array_equal(new, old[first][second], err_msg=name)
        assert id(new) not in after_first.values()  # the arrays of the first call were not written over
    p.permute(first)  # the third call reuses the first call's arrays
    assert {id(v) for v in p.as_dict().values()} == set(after_first.values())


def test_wall_histories_follow_their_particles_and_only_those_at_a_wall_are_copied():
    from fvdem.dem.neighbours import permute_wall_history
    rng = np.random.default_rng(4)
    n = 40
    mask = np.where(rng.uniform(size=n) < 0.3, rng.integers(1, 4096, n), 0)
    history = rng.normal(size=(n * 12, 4))
    history.reshape(n, 12, 4)[mask == 0] = 0.0  # the kernel's invariant: no contact, no history
    order = rng.permutation(n)
    new = np.zeros_like(history)
    permute_wall_history(history, mask, order, new)
    np.testing.assert_array_equal(new.reshape(n, 12, 4), history.reshape(n, 12, 4)[order])


def test_particle_arrays_copy_what_the_caller_passes():
    """A caller's position, velocity and colour arrays are not the simulation's: stepping leaves them
    as they were (they were advanced in place before)."""
    from fvdem.dem.particles import ParticleArrays
    position = np.array([[0.01, 0.02, 0.03], [0.04, 0.05, 0.06]])
    velocity = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    colour = np.array([0, 1], np.int32)
    p = ParticleArrays.create(position, 1e-3, 0.0, 2500.0, velocity=velocity, colour=colour)
    p.position += 1.0
    p.velocity += 1.0
    p.colour += 1
    assert position[0, 0] == 0.01 and velocity[0, 0] == 1.0 and colour[1] == 1
