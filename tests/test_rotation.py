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
    assert np.linalg.norm(p.quaternion[0]) == pytest.approx(1.0, abs=1e-14)
    # the body-frame angular velocity: spin component along the axis is constant
    assert p.angular_velocity[0] @ p.axis[0] == pytest.approx(L1 @ a0 / i_a, rel=1e-9)


def test_sphere_orientation_is_not_tracked():
    """Spheres pay for no orientation update: the quaternion stays as created."""
    s = make_system([[0.05, 0.05, 0.05]], 2e-3)
    s.particles.angular_momentum[0] = (1e-8, 2e-8, 0.0)
    q0 = s.particles.quaternion.copy()
    s.step(100)
    assert not s.track_orientation
    np.testing.assert_array_equal(s.particles.quaternion, q0)
    np.testing.assert_allclose(s.particles.angular_velocity[0],
                               s.particles.angular_momentum[0] / s.particles.inertia[0, 0])
