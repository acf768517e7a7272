"""Free rotation of a spherocylinder: angular momentum and energy are invariants."""
import numpy as np
import pytest

from conftest import make_system


def rotate(v, axis, angle):
    k = axis / np.linalg.norm(axis)
    return v * np.cos(angle) + np.cross(k, v) * np.sin(angle) + k * np.dot(k, v) * (1 - np.cos(angle))


def test_torque_free_spherocylinder_keeps_angular_momentum_and_energy():
    r, h = 1.5e-3, 4.5e-3
    s = make_system([[0.05, 0.05, 0.05]], r, h, axis=[[0.3, -0.2, 0.9]], dt=1e-5)
    p = s.particles
    i_t, i_a = p.inertia[0]
    a0 = p.axis[0].copy()
    # a spin about the axis plus a tumble: L not aligned with the axis
    L = i_a * 800.0 * a0 + i_t * 150.0 * np.cross(a0, [1.0, 0.0, 0.0])
    p.angular_momentum[0] = L
    s.step(1)  # refresh angular velocity from L
    L1 = p.angular_momentum[0].copy()
    energy0 = 0.5 * L1 @ p.angular_velocity[0]
    steps = 20000
    s.step(steps)
    np.testing.assert_array_equal(p.angular_momentum[0], L1)
    energy = 0.5 * p.angular_momentum[0] @ p.angular_velocity[0]
    assert energy == pytest.approx(energy0, rel=1e-10)
    # the axis precesses about L at |L| / I_t (exact solution of Euler's equations, I_1 = I_2)
    t = (steps + 1) * s.dt
    expected_axis = rotate(a0, L, np.linalg.norm(L) / i_t * t)
    np.testing.assert_allclose(p.axis[0], expected_axis, atol=1e-8)
    assert np.linalg.norm(p.axis[0]) == pytest.approx(1.0, abs=1e-14)  # 20,000 drifts, each renormalised
    # the body-frame angular velocity: spin component along the axis is constant
    assert p.angular_velocity[0] @ p.axis[0] == pytest.approx(L1 @ a0 / i_a, rel=1e-9)


def test_sphere_orientation_is_not_tracked():
    """Spheres pay for no orientation update: the axis stays as created."""
    s = make_system([[0.05, 0.05, 0.05]], 2e-3)
    s.particles.angular_momentum[0] = (1e-8, 2e-8, 0.0)
    a0 = s.particles.axis.copy()
    s.step(100)
    assert not s.track_orientation
    np.testing.assert_array_equal(s.particles.axis, a0)
    np.testing.assert_allclose(s.particles.angular_velocity[0],
                               s.particles.angular_momentum[0] / s.particles.inertia[0, 0])


@pytest.mark.parametrize("half_length", [0.0, 4.5e-3])
def test_a_run_of_steps_is_bit_for_bit_the_same_steps_one_at_a_time(half_length):
    """``step(n)`` folds each step's second half kick into the next step's pass (one memory pass
    fewer): with contacts, walls, rebuilds, external forces and the implicit drag of the coupling, the
    state after ``step(n)`` is bit-identical to ``n`` calls of ``step(1)``."""
    from fvdem.dem.system import Box
    rng = np.random.default_rng(7)
    grid = np.stack(np.meshgrid(*[np.arange(4)] * 3, indexing="ij"), -1).reshape(-1, 3)
    position = 0.006 + grid * 0.0105 + rng.uniform(-5e-4, 5e-4, (len(grid), 3))
    axis = rng.normal(size=(len(grid), 3))
    systems = []
    for _ in range(2):
        s = make_system(position, 1.5e-3 if half_length else 5e-3, half_length, axis=axis,
                        velocity=np.random.default_rng(3).normal(0, 0.3, (len(grid), 3)),
                        box=Box((0.0, 0.0, 0.0), (0.05, 0.05, 0.05), (False, False, False)), gravity=(0.0, 0.0, -9.81))
        p = s.particles
        p.external_force[:] = np.random.default_rng(5).normal(0, 1e-4, p.external_force.shape)
        p.external_torque[:] = np.random.default_rng(6).normal(0, 1e-7, p.external_torque.shape)
        s.implicit_drag = True
        p.drag_coefficient[:] = 1e-4
        p.fluid_velocity[:] = [0.0, 0.0, 0.4]
        systems.append(s)
    together, one_by_one = systems
    touching = []
    for _ in range(10):
        together.step(30)
        touching.append(int(together._row_contacts.sum() + together._row_wall_contacts.sum()))
        for _ in range(30):
            one_by_one.step(1)
    assert together.rebuild_count == one_by_one.rebuild_count > 1
    assert max(touching) > 0
    for name, value in together.particles.as_dict().items():
        np.testing.assert_array_equal(value, one_by_one.particles.as_dict()[name], err_msg=name)
    np.testing.assert_array_equal(together.history, one_by_one.history)
    np.testing.assert_array_equal(together.wall_history, one_by_one.wall_history)


def test_half_angle_terms_match_the_library_across_the_series_threshold():
    """The rotation's series of cos x and sin x / x agree with the library's functions to a rounding
    below the threshold and are the library above it (continuous across)."""
    import math

    from fvdem.dem.integrate import SMALL_ANGLE, half_angle_terms
    xs = np.concatenate([[0.0, 1e-300, 1e-8, 1e-4], np.linspace(1e-3, 3 * SMALL_ANGLE, 2001), [0.5, 2.0, 3.1]])
    for x in xs:
        c, sinc = half_angle_terms(x * x)
        assert c == pytest.approx(math.cos(x), rel=2.5e-16, abs=0.0)
        assert sinc == pytest.approx(math.sin(x) / x if x else 1.0, rel=2.5e-16, abs=0.0)
