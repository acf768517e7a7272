"""Trilinear interpolation: exact for linear fields, continuous across cells, periodic wrap."""
import numpy as np
import pytest

from fvdem.coupling.interpolation import ParticleGridMap, interpolate
from fvdem.dem.particles import ParticleArrays
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


def _dense_reference(mesh, particles, satellites, nearest=False):
    """The map as a dense (N, cells) matrix, point by point and corner by corner (no merging): each
    satellite point's share times its interpolation weights (``interpolate`` of the unit cell fields)."""
    n, cells = particles.count, mesh.cell_count
    dense = np.zeros((n, cells))
    points = satellites if np.any(particles.half_length > 0) else 1
    extent = particles.half_length + particles.radius
    for k in range(points):
        s = np.zeros(n) if points == 1 else -extent + (2 * k + 1) * extent / points
        at = particles.position + s[:, None] * particles.axis
        if nearest:
            index = np.floor((at - mesh.cell_centers[0]) / mesh.spacing + 0.5).astype(int)
            shape = np.array(mesh.shape)
            index = index % shape if mesh.periodic[0] else np.clip(index, 0, shape - 1)
            flat = index[:, 0] + mesh.shape[0] * (index[:, 1] + mesh.shape[1] * index[:, 2])
            dense[np.arange(n), flat] += 1.0 / points
        else:
            dense += interpolate(mesh, np.eye(cells), at) / points
    return dense


@pytest.mark.parametrize("kernel", ["trilinear", "nearest"])
@pytest.mark.parametrize("periodic", [False, True])
def test_grid_map_lists_each_cell_once_with_the_points_weights_summed(kernel, periodic):
    """Rods of every orientation and length (some beyond the outermost centres, some across a periodic face):
    the compact rows equal the point-by-point map and sum to 1; a rod whose points lie within a cell's width
    along every axis lists each cell once; spheres keep their 8 (or 1) cells."""
    mesh = GasMesh.box((4, 4, 6), (0, 0, 0), (0.06, 0.06, 0.09), (periodic,) * 3)
    rng = np.random.default_rng(3)
    n = 400
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    position = rng.uniform((-0.004, -0.004, -0.004), (0.064, 0.064, 0.094), (n, 3))
    rods = ParticleArrays.create(position, 0.0016, rng.uniform(0.0, 0.012, n), 1000.0, axis=axis)
    grid_map = ParticleGridMap(mesh, rods, kernel, 5)
    # the points' spread along each axis, 2 (h + r)(1 - 1/5) |a_d|, below a cell (15 mm): each cell once
    short = np.all(2 * (rods.half_length + rods.radius)[:, None] * 0.8 * np.abs(axis) < 0.015, axis=1)
    assert 100 < short.sum() < n - 50  # both kinds
    dense = np.zeros((n, mesh.cell_count))
    for i in range(n):
        row = grid_map.cells[i, :grid_map.counts[i]]
        if short[i]:
            assert len(np.unique(row)) == len(row)  # each cell once
        np.add.at(dense[i], row, grid_map.weights[i, :grid_map.counts[i]])
    np.testing.assert_allclose(dense, _dense_reference(mesh, rods, 5, kernel == "nearest"), rtol=0, atol=1e-15)
    np.testing.assert_allclose(dense.sum(axis=1), 1.0, rtol=1e-14)
    assert grid_map.counts[short].mean() < 0.5 * grid_map.cells.shape[1]  # the merging pays
    # a refresh after the rods moved equals a new map
    rods.position += 0.003
    fresh = ParticleGridMap(mesh, rods, kernel, 5)
    grid_map.refresh(rods)
    assert np.array_equal(grid_map.counts, fresh.counts)
    for i in range(n):
        assert np.array_equal(grid_map.cells[i, :fresh.counts[i]], fresh.cells[i, :fresh.counts[i]])
        assert np.array_equal(grid_map.weights[i, :fresh.counts[i]], fresh.weights[i, :fresh.counts[i]])
    spheres = ParticleArrays.create(position, 0.0016, 0.0, 1000.0)
    sphere_map = ParticleGridMap(mesh, spheres, kernel, 5)
    assert sphere_map.cells.shape[1] == (8 if kernel == "trilinear" else 1)
    dense = np.zeros((n, mesh.cell_count))
    for i in range(n):
        np.add.at(dense[i], sphere_map.cells[i, :sphere_map.counts[i]], sphere_map.weights[i, :sphere_map.counts[i]])
    np.testing.assert_allclose(dense, _dense_reference(mesh, spheres, 5, kernel == "nearest"), rtol=0, atol=1e-15)
