"""Segment distance against brute-force sampling; shape mass properties against integration."""
import numpy as np
import pytest

from fvdem.dem.geometry import segment_distance
from fvdem.dem.particles import (axis_from_quaternion, quaternion_from_axis, spherocylinder_inertia,
                                 spherocylinder_volume, volume_equivalent_diameter)


def brute_force_distance(p1, a1, h1, p2, a2, h2, samples=801):
    s = np.linspace(-h1, h1, samples) if h1 > 0 else np.zeros(1)
    t = np.linspace(-h2, h2, samples) if h2 > 0 else np.zeros(1)
    pts1 = p1 + s[:, None] * a1
    pts2 = p2 + t[:, None] * a2
    d = np.linalg.norm(pts1[:, None, :] - pts2[None, :, :], axis=2)
    return d.min()


def unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def random_pairs(rng, kind, count):
    for _ in range(count):
        p1 = rng.normal(size=3)
        a1 = unit(rng.normal(size=3))
        h1, h2 = rng.uniform(0.1, 1.5, size=2)
        if kind == "parallel":
            a2 = a1 * rng.choice([-1.0, 1.0])
            p2 = p1 + rng.normal(size=3)
        elif kind == "crossing":
            # segment 2 passes near the middle of segment 1
            a2 = unit(np.cross(a1, rng.normal(size=3)))
            p2 = p1 + rng.uniform(-0.5, 0.5) * h1 * a1 + 0.2 * rng.normal(size=3)
        elif kind == "end_caps":
            # collinear-ish, end to end
            a2 = unit(a1 + 0.2 * rng.normal(size=3))
            p2 = p1 + (h1 + h2 + rng.uniform(0.05, 0.5)) * a1 + 0.1 * rng.normal(size=3)
        elif kind == "point":
            a2 = unit(rng.normal(size=3))
            h2 = 0.0
            p2 = p1 + rng.normal(size=3)
        else:
            a2 = unit(rng.normal(size=3))
            p2 = p1 + rng.normal(size=3)
        yield p1, a1, h1, p2, a2, h2


@pytest.mark.parametrize("kind", ["random", "parallel", "crossing", "end_caps", "point"])
def test_segment_distance_matches_brute_force(kind):
    rng = np.random.default_rng(42)
    for p1, a1, h1, p2, a2, h2 in random_pairs(rng, kind, 60):
        exact = segment_distance(p1, a1, h1, p2, a2, h2)
        sampled = brute_force_distance(p1, a1, h1, p2, a2, h2)
        # sampling can only over-estimate, by at most half a sample spacing
        spacing = 2 * max(h1, h2) / 800
        assert exact <= sampled + 1e-12
        assert sampled - exact <= spacing + 1e-9, (kind, exact, sampled)


def test_segment_distance_is_symmetric_and_sphere_limit():
    rng = np.random.default_rng(1)
    for p1, a1, h1, p2, a2, h2 in random_pairs(rng, "random", 50):
        assert segment_distance(p1, a1, h1, p2, a2, h2) == pytest.approx(segment_distance(p2, a2, h2, p1, a1, h1),
                                                                          rel=1e-12, abs=1e-14)
        assert segment_distance(p1, a1, 0.0, p2, a2, 0.0) == pytest.approx(np.linalg.norm(p1 - p2), rel=1e-14)


def test_parallel_side_by_side_touch_in_the_middle_of_the_common_stretch():
    # two parallel rods offset along their axis: distance is the lateral gap
    a = np.array([1.0, 0.0, 0.0])
    assert segment_distance(np.zeros(3), a, 1.0, np.array([0.5, 0.3, 0.0]), a, 1.0) == pytest.approx(0.3)
    assert segment_distance(np.zeros(3), a, 1.0, np.array([2.5, 0.3, 0.0]), a, 1.0) == pytest.approx(
        np.hypot(0.5, 0.3))


def test_spherocylinder_volume_and_inertia_against_monte_carlo():
    r, h, rho = 1.5e-3, 4.5e-3, 1442.0
    rng = np.random.default_rng(0)
    n = 2_000_000
    box = np.array([r, r, h + r])
    pts = rng.uniform(-1, 1, size=(n, 3)) * box
    axial_dist = np.clip(np.abs(pts[:, 2]) - h, 0.0, None)
    inside = pts[:, 0] ** 2 + pts[:, 1] ** 2 + axial_dist ** 2 <= r * r
    box_volume = np.prod(2 * box)
    volume_mc = inside.mean() * box_volume
    assert spherocylinder_volume(r, h) == pytest.approx(volume_mc, rel=3e-3)
    mass = rho * spherocylinder_volume(r, h)
    q = pts[inside]
    i_axial_mc = mass * np.mean(q[:, 0] ** 2 + q[:, 1] ** 2)
    i_trans_mc = mass * np.mean(q[:, 1] ** 2 + q[:, 2] ** 2)
    transverse, axial = spherocylinder_inertia(r, h, rho)
    assert axial == pytest.approx(i_axial_mc, rel=5e-3)
    assert transverse == pytest.approx(i_trans_mc, rel=5e-3)
    # sphere limit
    t0, a0 = spherocylinder_inertia(r, 0.0, rho)
    m0 = rho * 4 / 3 * np.pi * r ** 3
    assert t0 == pytest.approx(0.4 * m0 * r * r) and a0 == pytest.approx(0.4 * m0 * r * r)


def test_seed_particles_are_volume_equivalent():
    # Table 6: AR-4 (L = 12 mm, d = 3 mm) and AR-1 (d = 5.3 mm) have the same volume
    assert volume_equivalent_diameter(1.5e-3, 4.5e-3) == pytest.approx(5.3e-3, rel=2e-3)


def test_quaternion_axis_round_trip():
    rng = np.random.default_rng(3)
    axes = rng.normal(size=(100, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    axes[0] = (0, 0, -1)
    axes[1] = (0, 0, 1)
    # a hair from -e_z and +e_z (1 + a_z ~ 1e-16 .. 1e-8: where (1 + a_z, -a_y, a_x, 0) loses all its digits)
    tilt = np.array([1e-8, 3e-7, 1e-5, 1e-4])
    axes[2:6] = np.stack([tilt, 0.5 * tilt, -np.sqrt(1 - 1.25 * tilt ** 2)], axis=1)
    axes[6:10] = np.stack([tilt, -0.5 * tilt, np.sqrt(1 - 1.25 * tilt ** 2)], axis=1)
    q = quaternion_from_axis(axes)
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-14)
    np.testing.assert_allclose(axis_from_quaternion(q), axes, rtol=0, atol=1e-15)


def test_the_branch_free_clamp_gives_the_branching_clamps_values():
    from fvdem.dem.geometry import _clamp
    rng = np.random.default_rng(2)
    for x, lo, hi in [(0.5, -1.0, 1.0), (-2.0, -1.0, 1.0), (2.0, -1.0, 1.0), (1.0, -1.0, 1.0), (-1.0, -1.0, 1.0),
                      (0.0, 0.0, 0.0), (-0.0, 0.0, 0.0), *zip(rng.normal(0, 2, 500), -np.abs(rng.normal(0, 1, 500)),
                                                           np.abs(rng.normal(0, 1, 500)))]:
        assert _clamp(x, lo, hi) == (lo if x < lo else (hi if x > hi else x))
