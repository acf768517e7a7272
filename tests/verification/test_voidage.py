"""Voidage mapping: volume conservation and the bound on jumps when a particle crosses a face."""
import numpy as np
import pytest

from fvdem.coupling.voidage import voidage
from fvdem.dem.particles import ParticleArrays, spherocylinder_volume
from fvdem.gas.mesh import GasMesh

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")
MESH = GasMesh.box((10, 10, 70), (0, 0, 0), (0.15, 0.15, 1.05))


@pytest.mark.parametrize("method", ["centroid", "divided"])
def test_solid_volume_is_conserved(method):
    rng = np.random.default_rng(0)
    n = 2000
    particles = ParticleArrays.create(rng.uniform([0, 0, 0], [0.15, 0.15, 0.3], size=(n, 3)), 1.5e-3, 4.5e-3, 1442.0,
                                      axis=rng.normal(size=(n, 3)))
    eps, over = voidage(particles, MESH, method, minimum=0.0)
    solid = ((1 - eps) * MESH.cell_volumes).sum()
    assert solid == pytest.approx(n * spherocylinder_volume(1.5e-3, 4.5e-3), rel=1e-12)
    assert over == 0


@pytest.mark.parametrize("method, satellites", [("centroid", 1), ("divided", 5)])
def test_a_rod_crossing_a_face_changes_the_voidage_by_at_most_the_method_bound(method, satellites):
    """A vertical AR-4 rod moved upward in 0.1 mm steps through the face at z = 0.15 m."""
    volume = spherocylinder_volume(1.5e-3, 4.5e-3)
    bound = volume / (satellites * MESH.cell_volumes[0])
    previous = None
    largest = 0.0
    for z in np.arange(0.13, 0.17, 1e-4):
        rod = ParticleArrays.create(np.array([[0.0725, 0.0725, z]]), 1.5e-3, 4.5e-3, 1442.0, axis=[[0, 0, 1.0]])
        eps, _ = voidage(rod, MESH, method, satellites=satellites, minimum=0.0)
        if previous is not None:
            largest = max(largest, np.abs(eps - previous).max())
        previous = eps
    assert largest <= bound * (1 + 1e-9)
    assert largest > 0.9 * bound  # the bound is reached: it is the method's real jump


@pytest.mark.parametrize("method", ["centroid", "divided", "trilinear"])
def test_a_given_map_is_used_only_when_its_weights_are_the_methods(method):
    """``voidage(..., grid_map=...)``: the bridge's trilinear map of 5 points serves the trilinear method; the
    others build their own (the same voidage as without a map), and a map of their own, refreshed in place
    after the rods moved, gives what a new one gives."""
    from fvdem.coupling.interpolation import ParticleGridMap
    from fvdem.coupling.voidage import METHODS
    rng = np.random.default_rng(4)
    n = 3000
    rods = ParticleArrays.create(rng.uniform([0, 0, 0], [0.15, 0.15, 0.3], size=(n, 3)), 1.5e-3, 4.5e-3, 1442.0,
                                 axis=rng.normal(size=(n, 3)))
    bridge_map = ParticleGridMap(MESH, rods, "trilinear", 5)
    m = METHODS[method]
    assert bridge_map.fits(m.weights, m.points(5), rods) == (method == "trilinear")
    expected, _ = voidage(rods, MESH, method, minimum=0.0)
    np.testing.assert_array_equal(voidage(rods, MESH, method, minimum=0.0, grid_map=bridge_map)[0], expected)
    own = ParticleGridMap(MESH, rods, m.weights, m.points(5))
    rods.position += rng.uniform(-0.01, 0.01, (n, 3))
    moved, _ = voidage(rods, MESH, method, minimum=0.0)
    np.testing.assert_array_equal(voidage(rods, MESH, method, minimum=0.0, grid_map=own.refresh(rods))[0], moved)
