"""``fvdem compare``: the comparisons of several run folders come from their scenes (a registry,
``fvdem.analysis.compare``), not from one kind of run: a suspension's runs get their diagnostics overlaid,
a fluidized bed's the mixing charts besides; a comparison of one's own is one registration."""
import numpy as np
import pytest

from fvdem.analysis import compare as comparisons
from fvdem.case import case_from_dict, to_toml
from fvdem.cli import main
from fvdem.scenes import comparisons_of


def _run(folder, table, columns):
    """A run folder with ``table``'s case and a time series of ``columns`` (name -> function of time)."""
    folder.mkdir()
    (folder / "case.toml").write_text(to_toml(case_from_dict(table)))
    t = np.linspace(0.0, 2.0, 21)
    rows = [",".join(["time", *columns])] + [",".join(f"{v:.6g}" for v in [x, *(f(x) for f in columns.values())])
                                            for x in t]
    (folder / "timeseries.csv").write_text("\n".join(rows) + "\n")
    return folder


SUSPENSION = {"name": "box", "suspension": {"enabled": True, "aspect_ratio": 2.0, "galileo_equivalent": 1296.0,
                                            "solids_fraction": 0.2}}
BED = {"name": "bed", "gas": {"enabled": True, "umf": 1.58, "u_over_umf": 2.0}}


def test_a_suspensions_runs_get_their_common_diagnostics_one_line_a_run(tmp_path, monkeypatch):
    a = _run(tmp_path / "a", SUSPENSION, {"slip_reynolds": lambda t: 9 + t, "kinetic_energy": lambda t: t})
    b = _run(tmp_path / "b", SUSPENSION, {"slip_reynolds": lambda t: 8 + t, "rms_speed": lambda t: 1 + t})
    assert comparisons_of([a, b]) == ("timeseries",)
    assert comparisons.common_columns([a, b]) == ["slip_reynolds"]
    import fvdem.analysis.plots as plots
    figures, real_save = [], plots._save
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or real_save(fig, path))
    assert main(["compare", str(a), str(b), "--out", str(tmp_path / "cmp")]) == 0
    assert sorted(p.name for p in (tmp_path / "cmp").iterdir()) == ["timeseries_compare.png"]
    lines = figures[0].axes[0].get_lines()
    assert [line.get_label() for line in lines] == ["a", "b"]
    np.testing.assert_allclose(lines[1].get_ydata(), 8 + np.linspace(0.0, 2.0, 21))


def test_a_beds_runs_get_the_mixing_charts_too(tmp_path):
    runs = [_run(tmp_path / f"r{k}", BED, {"mixing_entropy": lambda t, k=k: 1 - np.exp(-(k + 1) * t)})
            for k in range(2)]
    assert comparisons_of(runs) == ("timeseries", "mixing")
    assert main(["compare", *map(str, runs), "--out", str(tmp_path / "cmp")]) == 0
    assert sorted(p.name for p in (tmp_path / "cmp").iterdir()) == [
        "mixing_by_velocity.png", "mixing_compare.png", "t95.png", "timeseries_compare.png"]
    assert main(["compare", *map(str, runs), "--out", str(tmp_path / "only"), "--only", "mixing"]) == 0
    assert "timeseries_compare.png" not in [p.name for p in (tmp_path / "only").iterdir()]


def test_a_comparison_of_ones_own_is_one_registration(tmp_path, monkeypatch):
    monkeypatch.setitem(comparisons.COMPARISONS, "final", None)  # restored after the test
    drawn = []

    @comparisons.register_comparison("final", lambda runs: True)
    def final(runs, out, options):
        """The last value of each run."""
        drawn.append([r.name for r in runs])
        return []

    runs = [_run(tmp_path / "a", SUSPENSION, {"slip_reynolds": lambda t: t})]
    assert comparisons.COMPARISONS["final"].summary == "The last value of each run."
    assert main(["compare", str(runs[0]), "--out", str(tmp_path / "cmp"), "--only", "final"]) == 0
    assert drawn == [["a"]]


@pytest.mark.parametrize("extra, message", [
    (["--columns", "bed_top"], "--columns: columns not recorded: bed_top in"),
    (["--only", "mixng"], "--only: 'mixng' is not a comparison; allowed: timeseries, mixing"),
])
def test_bad_comparison_arguments_get_a_clear_error(tmp_path, capsys, extra, message):
    run = _run(tmp_path / "a", SUSPENSION, {"slip_reynolds": lambda t: t})
    assert main(["compare", str(run), "--out", str(tmp_path / "cmp"), *extra]) == 2
    assert message in capsys.readouterr().err
