"""Gas channels along a bed's walls and corners (fvdem.analysis.channels): the shares against the
cross-section's when the gas rises evenly, their limits, and the rods' alignment against its known values
(upright 1, flat 0, random orientations 1/2)."""
import numpy as np
import pytest

from fvdem.analysis.channels import column_classes, gas_shares, rod_alignment

LOWER, UPPER, CELLS = (0.0, 0.0, 0.0), (0.15, 0.15, 1.05), (10, 10, 70)


def _centres():
    h = np.array(UPPER) / np.array(CELLS)
    i, j, k = np.meshgrid(*(np.arange(n) for n in CELLS), indexing="ij")
    return np.column_stack([(i.ravel() + 0.5) * h[0], (j.ravel() + 0.5) * h[1], (k.ravel() + 0.5) * h[2]])


def test_the_columns_of_a_grid_are_4_corners_the_walls_between_and_the_inside():
    kind = column_classes(10, 10)
    assert [(kind == c).sum() for c in range(3)] == [4, 32, 64]
    assert kind[0, 0] == kind[9, 9] == kind[0, 9] == 0 and kind[0, 4] == kind[5, 9] == 1 and kind[4, 5] == 2
    assert column_classes(1, 1).tolist() == [[0]]


def test_evenly_rising_gas_shares_out_as_the_cross_section_and_a_channel_raises_its_share():
    centres = _centres()
    flux = np.full(len(centres), 2.5)
    shares = gas_shares(centres, flux, LOWER, UPPER, CELLS, (0.05, 0.2))
    assert shares == pytest.approx({"corner": 0.04, "wall": 0.32, "inside": 0.64}, abs=1e-12)
    kind = column_classes(10, 10)
    i, j = (np.floor(centres[:, :2] / 0.015).astype(int).T)
    corner = kind[i, j] == 0
    only = gas_shares(centres, np.where(corner, 1.0, 0.0), LOWER, UPPER, CELLS, (0.05, 0.2))
    assert only == pytest.approx({"corner": 1.0, "wall": 0.0, "inside": 0.0})
    # layers outside the range do not count; a layer where no gas rises has no share
    above = np.where(corner & (centres[:, 2] > 0.3), 100.0, flux)
    assert gas_shares(centres, above, LOWER, UPPER, CELLS, (0.05, 0.2)) == pytest.approx(shares)
    assert gas_shares(centres, np.zeros(len(centres)), LOWER, UPPER, CELLS, (0.05, 0.2)) == {
        "corner": None, "wall": None, "inside": None}
    assert gas_shares(centres, flux, LOWER, UPPER, CELLS, (2.0, 3.0))["corner"] is None  # above the column


def test_rods_upright_flat_and_random_have_the_alignments_1_0_and_one_half():
    rng = np.random.default_rng(3)
    position = np.column_stack([rng.uniform(0, 0.15, 200_000), rng.uniform(0, 0.15, 200_000),
                                rng.uniform(0.05, 0.2, 200_000)])
    upright = np.tile([0.0, 0.0, 1.0], (len(position), 1))
    flat = np.tile([np.sqrt(0.5), np.sqrt(0.5), 0.0], (len(position), 1))
    random = rng.normal(size=(len(position), 3))
    random /= np.linalg.norm(random, axis=1)[:, None]
    z_range = (0.05, 0.2)
    assert rod_alignment(position, upright, LOWER, UPPER, CELLS, z_range) == pytest.approx(
        {"corner": 1.0, "wall": 1.0, "inside": 1.0})
    assert rod_alignment(position, flat, LOWER, UPPER, CELLS, z_range) == pytest.approx(
        {"corner": 0.0, "wall": 0.0, "inside": 0.0}, abs=1e-12)
    assert rod_alignment(position, random, LOWER, UPPER, CELLS, z_range) == pytest.approx(
        {"corner": 0.5, "wall": 0.5, "inside": 0.5}, abs=0.02)
    # classed by the gas column a centre lies in; rods outside the range do not count
    one = rod_alignment([[0.001, 0.149, 0.1], [0.07, 0.07, 0.1], [0.07, 0.07, 0.5]],
                        [[0, 0, 1.0], [1.0, 0, 0], [0, 0, 1.0]], LOWER, UPPER, CELLS, z_range)
    assert one == {"corner": 1.0, "wall": None, "inside": 0.0}
