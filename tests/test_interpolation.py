"""Trilinear interpolation: exact for linear fields, continuous across cells, periodic wrap."""
import numpy as np
import pytest

from fvdem.coupling.interpolation import interpolate
from fvdem.gas.mesh import GasMesh

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")


def test_linear_fields_are_reproduced_exactly_inside_the_lattice():
    mesh = GasMesh.box((10, 10, 70), (0, 0, 0), (0.15, 0.15, 1.05))
    c = mesh.cell_centers
    field = np.stack([1 + 2 * c[:, 0] - c[:, 2], 3 * c[:, 1], 0.5 + c[:, 0] + c[:, 1] + c[:, 2]], axis=1)
    rng = np.random.default_rng(1)
    points = rng.uniform(c.min(axis=0), c.max(axis=0), size=(500, 3))
    expected = np.stack([1 + 2 * points[:, 0] - points[:, 2], 3 * points[:, 1],
                         0.5 + points.sum(axis=1)], axis=1)
    np.testing.assert_allclose(interpolate(mesh, field, points), expected, rtol=1e-12, atol=1e-12)
    # at cell centres the cell value itself
    np.testing.assert_allclose(interpolate(mesh, field[:, 0], c[:50]), field[:50, 0], rtol=1e-12)


def test_near_walls_the_field_is_held_and_periodic_axes_wrap():
    walled = GasMesh.box((4, 4, 4), (0, 0, 0), (0.04, 0.04, 0.04))
    field = walled.cell_centers[:, 2].copy()
    below = interpolate(walled, field, np.array([[0.02, 0.02, 0.001]]))
    assert below[0] == pytest.approx(walled.cell_centers[:, 2].min())
    periodic = GasMesh.box((4, 4, 4), (0, 0, 0), (0.04, 0.04, 0.04), (True, True, True))
    field = np.sin(2 * np.pi * periodic.cell_centers[:, 0] / 0.04)
    # across the periodic boundary x = 0: halfway between the last and the first centre
    value = interpolate(periodic, field, np.array([[0.0, 0.02, 0.02]]))[0]
    first, last = field[periodic.cell_centers[:, 0].argmin()], field[periodic.cell_centers[:, 0].argmax()]
    assert value == pytest.approx(0.5 * (first + last), abs=1e-12)


def test_interpolation_is_continuous_as_a_particle_moves():
    mesh = GasMesh.box((5, 5, 5), (0, 0, 0), (0.05, 0.05, 0.05))
    field = np.random.default_rng(2).normal(size=mesh.cell_count)
    z = np.linspace(0.004, 0.046, 2001)
    path = np.stack([np.full_like(z, 0.021), np.full_like(z, 0.033), z], axis=1)
    values = interpolate(mesh, field, path)
    steps = np.abs(np.diff(values))
    assert steps.max() < 4 * np.abs(field).max() * (z[1] - z[0]) / 0.01
