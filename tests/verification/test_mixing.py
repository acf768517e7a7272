"""Mixing measures against their limits: segregated 0, random mixture ~1, analytic cases."""
import numpy as np
import pytest

from fvdem.analysis.mixing import lacey_index, mixing_entropy, mixing_time, orientation_angles

LOWER, UPPER = (0.0, 0.0, 0.0), (0.15, 0.15, 1.05)


def _bed(n=20000, seed=1, height=0.21):
    rng = np.random.default_rng(seed)
    return rng.uniform((0, 0, 0), (0.15, 0.15, height), (n, 3))


def test_segregated_layers_have_zero_entropy_and_lacey_zero():
    position = _bed()
    # the colour boundary on an analysis-cell face (cells are 0.03 m tall): every cell is pure
    colour = (position[:, 2] >= 0.09).astype(int)
    assert mixing_entropy(position, colour, LOWER, UPPER) == 0.0
    assert lacey_index(position, colour, LOWER, UPPER) == pytest.approx(0.0, abs=1e-12)


def test_random_colours_approach_one():
    position = _bed(200000)
    colour = np.random.default_rng(2).integers(0, 2, len(position))
    # a cell of ~700 particles at x1 ~ 1/2 +- 0.02 has S / ln 2 = 1 - O(1e-3)
    assert mixing_entropy(position, colour, LOWER, UPPER) == pytest.approx(1.0, abs=2e-3)
    assert lacey_index(position, colour, LOWER, UPPER) == pytest.approx(1.0, abs=0.05)


def test_one_particle_a_cell_has_zero_entropy_and_no_lacey_index(recwarn):
    """Each occupied cell holds one particle (a sparse bed, the first chunk of a suspended run): every cell is
    pure (S = 0), and Lacey's random-mix variance s0 / n equals s0, so the index is undefined: nan, quietly."""
    position = np.array([[0.01, 0.01, 0.01], [0.01, 0.01, 0.5], [0.1, 0.1, 0.9]])
    colour = np.array([0, 1, 1])
    assert mixing_entropy(position, colour, LOWER, UPPER) == 0.0
    assert np.isnan(lacey_index(position, colour, LOWER, UPPER))
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_entropy_of_a_known_cell_mixture():
    """Two occupied cells: one 50/50 (S = ln 2), one 25/75 (S = -(1/4 ln 1/4 + 3/4 ln 3/4)), equal counts."""
    position = np.array([[0.01, 0.01, 0.01]] * 4 + [[0.01, 0.01, 0.5]] * 4)
    colour = np.array([0, 1, 0, 1, 0, 1, 1, 1])
    s2 = -(0.25 * np.log(0.25) + 0.75 * np.log(0.75))
    expected = (np.log(2) * 4 + s2 * 4) / 8 / np.log(2)
    assert mixing_entropy(position, colour, LOWER, UPPER) == pytest.approx(expected, rel=1e-14)


def test_mixing_time_interpolates_the_first_crossing():
    t = np.array([0.0, 1.0, 2.0, 3.0])
    s = np.array([0.0, 0.5, 0.97, 0.9])
    assert mixing_time(t, s) == pytest.approx(1.0 + 0.45 / 0.47)
    assert mixing_time(t, s, 0.99) is None


def test_orientation_angle_is_folded_to_a_quarter_turn():
    axis = np.array([[0, 0, 1.0], [0, 0, -1.0], [1.0, 0, 0], [0, np.sqrt(0.5), np.sqrt(0.5)]])
    np.testing.assert_allclose(orientation_angles(axis), [0, 0, np.pi / 2, np.pi / 4])


def test_t95_against_u_over_umf_from_run_folders(tmp_path, monkeypatch):
    """fvdem compare: t95 of each run folder against its U/Umf, grouped by case name; a run that has
    not mixed gives None (drawn as a lower bound at its end)."""
    from fvdem.analysis.plots import mixing_times
    from fvdem.case import case_from_dict, to_toml
    from fvdem.cli import main
    runs = []
    for name, ratio, rate in (("ar1", 1.6, 0.5), ("ar1", 2.9, 2.0), ("ar4_mp", 2.0, 0.05)):
        out = tmp_path / f"{name}_{ratio}"
        out.mkdir()
        case = case_from_dict({"name": name, "gas": {"enabled": True, "umf": 1.58, "u_over_umf": ratio}})
        (out / "case.toml").write_text(to_toml(case))
        t = np.linspace(0, 4, 401)
        entropy = 1 - np.exp(-rate * t)
        (out / "timeseries.csv").write_text("time,mixing_entropy\n" + "".join(f"{a},{b}\n" for a, b in zip(t, entropy)))
        runs.append(out)
    table = mixing_times(runs)
    assert [r for r, _, _ in table["ar1"]] == [1.6, 2.9]
    # S = 1 - exp(-k t) reaches 0.95 at ln(20)/k: 5.99 s (beyond the 4 s run) and 1.50 s
    assert table["ar1"][0][1] is None and table["ar1"][0][2] == 4.0
    assert table["ar1"][1][1] == pytest.approx(np.log(20) / 2.0, abs=0.01)
    assert table["ar4_mp"][0][1] is None
    # a second family of the same case at the same velocity (a study's ar1 and ar1_paper), one mixed
    # and one not: grouped by the names given, and runs at one velocity sort with None last
    twin = tmp_path / "twin"
    twin.mkdir()
    (twin / "case.toml").write_text((runs[1] / "case.toml").read_text())
    t = np.linspace(0, 4, 401)
    (twin / "timeseries.csv").write_text("time,mixing_entropy\n" + "".join(f"{a},{0.5 * a / 4}\n" for a in t))
    merged = mixing_times(runs + [twin])
    assert [row[1] is None for row in merged["ar1"]] == [True, False, True]
    by_family = mixing_times(runs + [twin], names=["ar1", "ar1", "ar4_mp", "ar1_paper"])
    assert by_family["ar1_paper"] == [(2.9, None, 4.0)] and len(by_family["ar1"]) == 2
    # a published value (the study's paper terminal t95s) is a dashed line in its family's colour from its U/Umf on;
    # one of a family not drawn is left out
    import fvdem.analysis.plots as plots
    figures, real_save = [], plots._save
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or real_save(fig, path))
    plots.plot_t95(runs, tmp_path / "t95_ref.png", references={"ar1": (2.6, 2.3, "ar1: paper"),
                                                                "ar4_sp": (2.0, 2.3, "ar4_sp: paper")})
    lines = {line.get_label(): line for line in figures[0].axes[0].get_lines()}
    assert "ar4_sp: paper" not in lines and list(lines["ar1: paper"].get_ydata()) == [2.6, 2.6]
    assert lines["ar1: paper"].get_xdata()[0] == 2.3 and lines["ar1: paper"].get_linestyle() == "--"
    assert lines["ar1: paper"].get_color() == lines["ar1"].get_color()
    # the paper's layout of Figs. 2, 3 and 9 a: a colour per U/Umf (its rank among the levels given), a line style
    # per group, replicas alike, one legend entry per group and U/Umf with its runs' t95s
    from matplotlib import colormaps
    figures.clear()
    plots.plot_mixing_by_velocity(runs + [twin], tmp_path / "by_velocity.png", names=["ar1", "ar1", "ar4_mp", "ar1"],
                                  styles={"ar4_mp": "--"}, levels=[2.9, 1.6, 2.0, 2.3])
    lines = figures[0].axes[0].get_lines()
    entries = {line.get_label(): line for line in lines if not line.get_label().startswith("_")}
    assert set(entries) == {"ar1, 1.6 Umf: t95 > 4 s", "ar4_mp, 2 Umf: t95 > 4 s", "ar1, 2.9 Umf: t95 1.50 s, > 4 s"}
    tab10 = colormaps["tab10"]
    assert entries["ar1, 1.6 Umf: t95 > 4 s"].get_color() == tab10(0)
    assert entries["ar4_mp, 2 Umf: t95 > 4 s"].get_color() == tab10(1)
    assert entries["ar1, 2.9 Umf: t95 1.50 s, > 4 s"].get_color() == tab10(3)  # 2.3 ranks between
    assert entries["ar4_mp, 2 Umf: t95 > 4 s"].get_linestyle() == "--"
    assert entries["ar1, 1.6 Umf: t95 > 4 s"].get_linestyle() == "-"
    curves = [line for line in lines if len(line.get_xdata()) > 2]  # the 0.95 line has two points
    assert len(curves) == 4 and sum(line.get_color() == tab10(3) for line in curves) == 2  # both 2.9 replicas
    dots = [line for line in lines if len(line.get_xdata()) == 1]  # t95 on the 0.95 line: the one run that mixed
    assert len(dots) == 1 and dots[0].get_xdata()[0] == pytest.approx(np.log(20) / 2.0, abs=0.01)
    figures.clear()
    plots.plot_mixing_by_velocity(runs + [twin], tmp_path / "at_2.9.png", velocities=[2.9])
    assert [line.get_label() for line in figures[0].axes[0].get_lines() if not line.get_label().startswith("_")] == [
        "ar1, 2.9 Umf: t95 1.50 s, > 4 s"]
    # a run that has not ended (a study's run in progress) and has not mixed: its time bounds nothing yet
    figures.clear()
    plots.plot_mixing_by_velocity(runs + [twin], tmp_path / "at_2.9.png", velocities=[2.9],
                                  ended=[True, True, True, False])
    assert [line.get_label() for line in figures[0].axes[0].get_lines() if not line.get_label().startswith("_")] == [
        "ar1, 2.9 Umf: t95 1.50 s, on its way at 4 s"]
    assert main(["compare", *map(str, runs), "--out", str(tmp_path / "cmp")]) == 0
    assert (tmp_path / "cmp" / "t95.png").exists() and (tmp_path / "cmp" / "mixing_compare.png").exists()
    assert (tmp_path / "cmp" / "mixing_by_velocity.png").exists()
    assert not (tmp_path / "cmp" / "colour_layers_compare.png").exists()  # no snapshots, no archived record
    # runs with a colour-by-layer record (archived, as a study's archive keeps it) get a panel each
    import json

    from fvdem.scenes.observables import colour_layer_items
    record = {"z_lower": 0.0, "layer_height": 0.03, "times": [0.0, 0.5, 1.0],
              "count": [[40, 40], [40, 40], [40, 0]], "fraction": [[0.0, 1.0], [0.3, 0.7], [0.5, None]]}
    for run in (runs[1], runs[2]):
        (run / "colour_layers.json").write_text(json.dumps(record))
    items = colour_layer_items(runs)
    assert [(label, t95 is None) for label, _, t95 in items] == [("ar1_2.9", False), ("ar4_mp_2.0", True)]
    assert items[0][2] == pytest.approx(np.log(20) / 2.0, abs=0.01) and items[0][1] == record
    assert main(["compare", *map(str, runs), "--out", str(tmp_path / "cmp2")]) == 0
    assert (tmp_path / "cmp2" / "colour_layers_compare.png").exists()
    # two runs of one case at one velocity (two `demo` runs) are two lines named by their folders
    from fvdem.scenes.observables import mixing_groups
    assert mixing_groups(runs + [twin]) == ["ar1", "ar1_2.9", "ar4_mp", "twin"]


def test_cells_in_bed_leave_out_the_freeboard_above_a_low_bed_and_keep_its_bubbles():
    from fvdem.analysis.mixing import cells_in_bed
    z = np.repeat((np.arange(40) + 0.5) * 0.015, 16)  # 4 x 4 cells a layer, 40 layers of 15 mm
    centres = np.column_stack([np.zeros_like(z), np.zeros_like(z), z])
    voidage = np.where(z < 0.18, 0.45, 1.0)            # bed to 0.18 m, empty above
    voidage[np.flatnonzero(z < 0.1)[:5]] = 0.98         # a bubble low in the bed
    mask = cells_in_bed(voidage, centres, below=0.3)
    assert mask.sum() == 12 * 16 and np.all(z[mask] < 0.18) and mask[np.flatnonzero(z < 0.1)[:5]].all()
    tall = np.full_like(z, 0.6)                         # a bed above 0.3 m: every cell below 0.3 m
    assert cells_in_bed(tall, centres, below=0.3).sum() == np.sum(z < 0.3)
    assert not cells_in_bed(np.ones_like(z), centres).any()


def test_a_log_panel_leaves_out_the_zero_at_the_start():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fvdem.analysis.plots import log_panel
    fig, ax = plt.subplots()
    log_panel(ax, np.linspace(0, 1, 5), np.array([0.0, 1e-3, 2e-3, 5e-4, 1e-3]))
    low, high = ax.get_ylim()
    plt.close(fig)
    assert 1e-4 < low < 5e-4 and high >= 2e-3


def test_run_labels_tell_folders_of_the_same_name_apart(tmp_path):
    from fvdem.analysis.plots import run_labels
    assert run_labels([tmp_path / "a" / "demo", tmp_path / "b" / "demo"]) == ["a/demo", "b/demo"]
    assert run_labels([tmp_path / "x", tmp_path / "y"]) == ["x", "y"]


def test_random_mixture_entropy_limits_of_small_and_large_cells():
    """Cells of one particle: 0 whatever the colours; of two at p = 1/2: (1/2) ln 2 / ln 2 = 1/2; of n >> 1:
    the second-order expansion 1 - 1 / (2 n ln 2) (its next term is O(1 / n^2))."""
    from fvdem.analysis.mixing import random_mixture_entropy
    one = np.array([[0.01 + 0.03 * i, 0.01, 0.01] for i in range(4)])
    assert random_mixture_entropy(one, np.array([0, 1, 0, 1]), LOWER, UPPER) == 0.0
    two = np.array([[0.01, 0.01, 0.01]] * 2 + [[0.04, 0.01, 0.01]] * 2)
    assert random_mixture_entropy(two, np.array([0, 1, 1, 0]), LOWER, UPPER) == pytest.approx(0.5, rel=1e-12)
    for n in (100, 400):
        cell = np.tile([[0.01, 0.01, 0.01]], (n, 1))
        value = random_mixture_entropy(cell, np.arange(n) % 2, LOWER, UPPER)
        assert value == pytest.approx(1 - 1 / (2 * n * np.log(2)), abs=2 / n ** 2)
    assert np.isnan(random_mixture_entropy(np.empty((0, 3)), np.empty(0, int), LOWER, UPPER))


def test_random_mixture_entropy_against_shuffled_colours():
    """The exact expectation against the mean entropy of the same bed with its colours shuffled 200 times
    (a Monte Carlo estimate, independent of the binomial sum), cells of ~23 particles; p = 0.3 as well."""
    from fvdem.analysis.mixing import random_mixture_entropy
    position = _bed(20000, height=0.84)
    rng = np.random.default_rng(3)
    for share in (0.5, 0.3):
        colour = (rng.random(len(position)) < share).astype(int)
        exact = random_mixture_entropy(position, colour, LOWER, UPPER)
        draws = [mixing_entropy(position, rng.permutation(colour), LOWER, UPPER) for _ in range(200)]
        assert exact == pytest.approx(np.mean(draws), abs=3 * np.std(draws) / np.sqrt(len(draws)))
        assert exact < 0.99  # the ceiling is visibly below 1 at this cell size


def test_colour_by_layer_counts_each_slab_by_centre():
    """Three layers of 0.35 m: two particles in the lowest (one of each colour), one colour-1 in the middle,
    none in the top (NaN); a centre below the column counts in the lowest layer, as in the mixing grid."""
    from fvdem.analysis.mixing import colour_by_layer
    position = np.array([[0.1, 0.1, 0.1], [0.1, 0.1, -0.01], [0.1, 0.1, 0.5]])
    count, fraction = colour_by_layer(position, np.array([0, 1, 1]), LOWER, UPPER, 3)
    assert count.tolist() == [2, 1, 0]
    assert fraction[:2].tolist() == [0.5, 1.0] and np.isnan(fraction[2])
