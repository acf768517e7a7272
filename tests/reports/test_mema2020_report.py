"""Seed 000's study report (fvdem.reports.mema2020) on the engine: the table's columns (bed height and expansion over one window, the outlet's share, the dense bed, the void fractions' binarity), the
paper's figures as the findings count the runs, the plan of the open findings, and an archive that rebuilds the
report and findings without the run folders."""
import json
from pathlib import Path

import pytest

from fvdem.study import load_study

from study_runs import ROOT, SMOKE, fake_run


def test_the_report_pairs_the_families_of_the_papers_figures(tmp_path, monkeypatch):
    """Figs. 3 / 7 (AR-1 against AR-4 MP) and 9 (AR-4 MP drag only against full) at the velocities both
    families ran, with every replica of each; a family without its partner draws no pair."""
    import fvdem.analysis.plots as plots
    from fvdem.study import report
    import fvdem.reports.mema2020.figures as mema
    drawn, plot_mixing, plot_void_fractions = {}, plots.plot_mixing, mema.plot_void_fractions
    monkeypatch.setattr(plots, "plot_mixing", lambda folders, path: drawn.setdefault(
        Path(path).name, [Path(f).name for f in folders]) and plot_mixing(folders, path))
    monkeypatch.setattr(mema, "plot_void_fractions", lambda runs, path: drawn.setdefault(
        Path(path).name, [Path(r["folder"]).name for r in runs]) and plot_void_fractions(runs, path))
    plot_t95, named = plots.plot_t95, {}

    def t95_chart(folders, path, names, **kw):  # each run's name on Fig. 4, and the runs set aside
        named.update(zip([Path(f).name for f in folders], names), aside=kw.get("aside"))
        return plot_t95(folders, path, names=names, **kw)
    monkeypatch.setattr(plots, "plot_t95", t95_chart)
    runs = []
    for family, ratio in (("ar1", 2.0), ("ar4_mp", 2.0), ("ar4_mp", 2.9), ("ar4_mp_drag", 2.9), ("ar1", 1.6),
                          ("ar1_r2", 2.0), ("ar1_r3", 2.0)):
        folder = tmp_path / "runs" / f"{family}_{ratio}"
        family = family.removesuffix("_r2").removesuffix("_r3")
        folder.mkdir(parents=True)
        on_its_way = folder.name == "ar1_r3_2.0"  # a replica on its way, not yet mixed (in its start-up)
        (folder / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.5,0.6\n"
                                               + ("" if on_its_way else "1.0,0.97\n"))
        (folder / "case.toml").write_text(f'name = "{family}"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = {ratio}\n')
        runs.append({"name": folder.name, "family": family, "status": "stopped" if on_its_way else "finished",
                     "folder": str(folder), "t95": None if on_its_way else 1.0, "point": {"gas.u_over_umf": ratio}})
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    names = sorted(Path(p).name for p in report(tmp_path))
    assert "fig3_mixing_2.png" in names and "fig7_void_fraction_2.png" in names and "fig9_mixing_2.9.png" in names
    assert not any(n.startswith(("fig3_mixing_1.6", "fig3_mixing_2.9", "fig9_mixing_2.png")) for n in names)
    assert {"mixing_ar1.png", "mixing_ar4_mp.png", "t95.png", "table.csv", "table.json"} <= set(names)
    assert drawn["fig3_mixing_2.png"] == ["ar1_2.0", "ar1_r2_2.0", "ar1_r3_2.0", "ar4_mp_2.0"]  # every AR-1 replica
    # the void fractions of the fluidized bed: the replica on its way and not yet mixed waits
    assert drawn["fig7_void_fraction_2.png"] == ["ar1_2.0", "ar1_r2_2.0", "ar4_mp_2.0"]
    # the paper's own charts: Fig. 3 at its 1.6, 1.7 and 2.9 Umf (none here ran both there), Fig. 9 a at every
    # velocity drag only ran
    assert "fig3_mixing.png" not in names and "fig9_mixing.png" in names
    assert "fig7_void_fraction.png" in names  # the paper's Fig. 7 panels: 2.0 Umf is one
    # AR-4 MP at 2.9 in a taller column (family ar4_mp_tall): once mixed, it stands for ar4_mp's run there in the
    # pairs, as in the findings (the roofed run keeps its own chart); on its way, it waits
    for family, on_its_way in (("ar1", False), ("ar4_mp_tall", False)):
        folder = tmp_path / "runs" / f"{family}_2.9"
        folder.mkdir(parents=True)
        (folder / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.5,0.6\n1.0,0.97\n")
        (folder / "case.toml").write_text(f'name = "{family}"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = 2.9\n')
        runs.append({"name": folder.name, "family": family, "status": "finished", "folder": str(folder), "t95": 1.0,
                     "point": {"gas.u_over_umf": 2.9}})
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    drawn.clear()
    names = sorted(Path(p).name for p in report(tmp_path))
    assert drawn["fig3_mixing_2.9.png"] == ["ar1_2.9", "ar4_mp_tall_2.9"]
    assert drawn["fig9_mixing_2.9.png"] == ["ar4_mp_drag_2.9", "ar4_mp_tall_2.9"]
    assert drawn["fig7_void_fraction_2.9.png"] == ["ar1_2.9", "ar4_mp_tall_2.9"]
    assert "mixing_ar4_mp.png" in names and "mixing_ar4_mp_tall.png" in names
    # Fig. 4: AR-4 MP's line through the taller column's run, the paper's column's run there a cross beside it
    aside = "ar4_mp: the paper's column, set aside (particles pinned at its outlet)"
    assert named["ar4_mp_tall_2.9"] == "ar4_mp" and named["ar4_mp_2.0"] == "ar4_mp" and named["ar4_mp_2.9"] == aside
    assert named["aside"] == {aside: "ar4_mp"}
    runs[-1] = {**runs[-1], "status": "stopped", "t95": None}
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    drawn.clear()
    (tmp_path / "runs" / "ar4_mp_tall_2.9" / "timeseries.csv").write_text("time,mixing_entropy\n0.0,0.1\n0.5,0.6\n")
    report(tmp_path)
    assert drawn["fig3_mixing_2.9.png"] == ["ar1_2.9", "ar4_mp_2.9"]


def test_the_share_of_the_window_with_the_bed_top_at_the_outlet():
    """``bed_at_roof``: over the window (1 s after a 1 s ramp, for 3 s), the share of samples whose bed_top lies
    within 1 cm of the outlet."""
    import numpy as np
    from fvdem.reports.mema2020.table import _at_roof
    time = np.round(np.arange(0, 8.001, 0.01), 2)
    top = np.where((time >= 2.0) & (time < 3.5), 1.05, 0.6)  # at the roof for the first half of 2-5 s
    series = {"time": time, "bed_top": top}
    assert _at_roof(series, 1.05, ramp=1.0) == pytest.approx(150 / 301, abs=1e-9)
    assert _at_roof({**series, "bed_top": np.full_like(time, 1.045)}, 1.05, ramp=1.0) == 1.0  # within 1 cm
    assert _at_roof(series, None, ramp=1.0) is None and _at_roof({"time": time}, 1.05) is None


def test_the_share_of_the_particles_pinned_at_the_outlet_at_the_end(tmp_path):
    """``roof_share``: the column's top layer of the mixing grid at the last snapshot, from a run's snapshots or
    its archived colour-by-layer record; 0 where the bed's top never reached the outlet (nothing read), and
    where the record stops below the top layer."""
    import json

    import numpy as np
    from fvdem.analysis.plots import COLOUR_LAYERS
    from fvdem.scenes.observables import colour_layer_record
    from fvdem.reports.mema2020.table import _reaches_roof, _roof_share
    time = np.round(np.arange(0, 6.001, 0.5), 2)
    series = {"time": time, "bed_top": np.where(time >= 1.5, 1.05, 0.5)}
    record = {"z_lower": 0.0, "layer_height": 0.03, "times": [0.0, 6.0],
              "count": [[100] * 34 + [0], [90] * 34 + [40]], "fraction": [[0.5] * 35, [0.5] * 35]}
    (tmp_path / COLOUR_LAYERS).write_text(json.dumps(record))
    assert _reaches_roof(series, 1.05) and not _reaches_roof(series, None) and not _reaches_roof(None, 1.05)
    assert _roof_share(series, 1.05, colour_layer_record(tmp_path)) == pytest.approx(40 / (90 * 34 + 40))
    low = {**series, "bed_top": np.full_like(time, 0.6)}
    assert not _reaches_roof(low, 1.05) and _roof_share(low, 1.05, None) == 0.0  # never up there: nothing to read
    short = {**record, "count": [[100] * 20, [100] * 20]}  # no snapshot reached above 0.6 m
    (tmp_path / COLOUR_LAYERS).write_text(json.dumps(short))
    assert _roof_share(series, 1.05, colour_layer_record(tmp_path)) == 0.0
    assert colour_layer_record(tmp_path / "none") is None and _roof_share(series, 1.05, None) is None
    assert _roof_share(series, None, record) is None and _roof_share(None, 1.05, record) is None


def test_the_dense_beds_height_and_expansion_from_the_centres_by_layer():
    """``_centre_quantile``: the height under a share of the centres, spread evenly within their layer (uniform
    counts: the share of the filled height); ``_dense_bed_expansion``: its mean over the window at the snapshots
    over its first, unmoved by the few particles thrown far above the bed that set the 99 % top."""
    import numpy as np
    from fvdem.reports.mema2020.table import _centre_quantile, _dense_bed_expansion
    assert _centre_quantile([100] * 10, 0.0, 0.03) == pytest.approx(0.9 * 0.3)  # uniform over 0-0.3 m
    assert _centre_quantile([100] * 10, 0.1, 0.03, share=0.5) == pytest.approx(0.1 + 0.15)
    assert _centre_quantile([0, 50, 50], 0.0, 0.1, share=0.5) == pytest.approx(0.2)  # the first layer holds none
    assert _centre_quantile([0, 0], 0.0, 0.03) is None
    settled = [100] * 10  # 0.27 m under 90 %
    expanded = [50] * 20  # 0.54 m
    spout = [50] * 20 + [0] * 10 + [1] * 5  # five centres thrown 0.3 m above it: 90 % of 1,005 lies at 0.543 m
    times = [0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 4.5, 5.0, 5.5]
    record = {"z_lower": 0.0, "layer_height": 0.03, "times": times, "count": [settled] * 3 + [expanded] * 9}
    assert _dense_bed_expansion(record, ramp=1.0) == pytest.approx(2.0)  # window 2-5 s: all expanded
    thrown = {**record, "count": [settled] * 3 + [expanded, spout] * 4 + [expanded]}
    mean = np.mean([0.9 * 1005 / 50 * 0.03, 0.54] * 3 + [0.9 * 1005 / 50 * 0.03])  # the seven from 2.0 to 5.0 s
    assert _dense_bed_expansion(thrown, ramp=1.0) == pytest.approx(mean / 0.27)
    assert _dense_bed_expansion(thrown, ramp=1.0) < 2.02  # the spout moves it by under 1 %
    assert _dense_bed_expansion(None) is None and _dense_bed_expansion({**record, "count": []}) is None


def test_the_papers_fig7_pools_each_familys_replicas_panel_by_panel(tmp_path, monkeypatch):
    """Fig. 7 as the paper draws it: a panel per velocity, one histogram per family, its replicas pooled by
    their cells, each replica's binarity in the label; a velocity without snapshots says so."""
    import fvdem.analysis.plots as plots
    from fvdem.reports.mema2020.figures import plot_void_fraction_panels
    from fvdem.reports.mema2020.table import VOID_FRACTION
    edges = [0.05 * k for k in range(21)]
    runs = []
    for name, family, cells, peak, binarity in (("a1", "ar1", 100, 9, 0.4), ("a2", "ar1", 300, 10, 0.5),
                                                ("b1", "ar4_mp", 200, 11, None)):
        folder = tmp_path / name
        folder.mkdir()
        density = [0.0] * 20
        density[peak] = 20.0  # all cells in one bin of width 0.05
        (folder / VOID_FRACTION).write_text(json.dumps({"below": 0.3, "edges": edges, "density": density,
                                                        "cells": cells, "binarity": binarity}))
        runs.append({"name": name, "family": family, "folder": str(folder)})
    empty = tmp_path / "empty"
    empty.mkdir()
    figures, real_save = [], plots._save
    monkeypatch.setattr(plots, "_save", lambda fig, path: figures.append(fig) or real_save(fig, path))
    plot_void_fraction_panels({2.0: runs, 1.6: [{"name": "e", "family": "ar1", "folder": str(empty)}]},
                              tmp_path / "fig7.png")
    first, second = figures[0].axes  # one row of two
    assert first.get_title() == "1.6 Umf: no gas snapshots" and not first.get_lines()
    assert second.get_title() == "2 Umf"
    lines = {line.get_label(): line.get_ydata() for line in second.get_lines()}
    assert set(lines) == {"ar1 (2 runs, binarity 0.40, 0.50)", "ar4_mp (1 run, binarity -)"}
    pooled = lines["ar1 (2 runs, binarity 0.40, 0.50)"]
    assert pooled[9] == pytest.approx(20.0 * 100 / 400) and pooled[10] == pytest.approx(20.0 * 300 / 400)
    assert sum(pooled) * 0.05 == pytest.approx(1.0)  # still a density


def test_a_run_in_progress_is_reported_from_its_time_series_not_from_an_earlier_stops_summary(tmp_path):
    """A run stopped once early and running again: its summary.json is from the first stop; the table
    takes t95, the pressure drop and its fluctuation and the bed height from what the time series holds now."""
    import numpy as np
    from fvdem.study import report
    folder = tmp_path / "runs" / "ar1_2.9"
    folder.mkdir(parents=True)
    (folder / "case.toml").write_text('name = "ar1"\n[gas]\nenabled = true\numf = 1.58\nu_over_umf = 2.9\n')
    (folder / "summary.json").write_text(json.dumps({"stopped_early": True, "bed_pressure_drop_std_second_half": 5.0,
                                                     "bed_weight_per_area": 1000.0, "bed_height": 0.2,
                                                     "pressure_drop_over_weight": 1.03, "simulated_time": 0.07}))
    t = np.linspace(0.0, 3.0, 31)
    drop = 1.0 + 0.3 * np.sin(5.0 * t)
    entropy = np.minimum(1.0, t / 2.0)
    top = 0.3 + 0.05 * np.sin(3.0 * t)
    fastest = 12.0 + 4.0 * t
    overlap = 0.04 + 0.001 * np.arange(len(t))  # 0.04 ... 0.07, then one impact
    overlap[17] = 0.3
    (folder / "timeseries.csv").write_text(
        "time,mixing_entropy,pressure_drop_over_weight,bed_top,gas_max_speed,max_overlap_over_diameter\n"
        + "".join(f"{a},{b},{c},{d},{e},{f}\n" for a, b, c, d, e, f in zip(t, entropy, drop, top, fastest, overlap)))
    (tmp_path / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [
        {"name": "ar1_2.9", "family": "ar1", "status": "stopped", "folder": str(folder), "t95": None,
         "point": {"gas.u_over_umf": 2.9}}]}))
    report(tmp_path)
    row = json.loads((tmp_path / "table.json").read_text())[0]
    half = t >= 1.5
    assert row["simulated_seconds"] == 3.0 and row["t95"] == pytest.approx(1.9, abs=0.02)
    assert row["pressure_drop_over_weight"] == pytest.approx(np.mean(drop[half]))
    assert row["pressure_drop_std_over_weight"] == pytest.approx(np.std(drop[half]))
    # the bed's surface over one window in every run, from 1 s after the inlet ramp (none here) for 3 s (the
    # summary's packed-bed height of 0.2 m is not a fluidized bed's height)
    window = (t >= 1.0) & (t <= 4.0)
    assert row["bed_height"] == pytest.approx(np.mean(top[window]))
    assert row["bed_expansion"] == pytest.approx(np.mean(top[window]) / 0.3)  # over the bed it started as
    # the largest cell gas speed over the inlet velocity (2.9 x 1.58 m/s), over the same window: channels
    assert row["gas_max_speed_over_inlet"] == pytest.approx(np.mean(fastest[window]) / (2.9 * 1.58))
    # the contacts' depth over the whole run: the impact is its largest, not its median or 99th percentile
    assert row["overlap_max"] == 0.3 and row["overlap_median"] == pytest.approx(0.055)  # the 16th of 31
    assert row["overlap_p99"] == pytest.approx(np.percentile(overlap, 99)) and row["overlap_p99"] < 0.3
    # runs of different lengths (8 s; ended at 5.5 s, 2 s past t95) over one window: a bed rising slowly
    # stands as high in both (over their second halves it would not: 6 s against 4.1 s)
    from fvdem.reports.mema2020.table import _bed_surface
    runs = [{"time": np.linspace(0.0, end, int(end * 100) + 1)} for end in (8.0, 5.5)]
    for series in runs:
        series["bed_top"] = 0.3 + 0.01 * series["time"]
    assert _bed_surface(runs[0], 1.0) == pytest.approx(_bed_surface(runs[1], 1.0)) == pytest.approx(0.335)
    assert _bed_surface(runs[0]) == pytest.approx(0.36) and _bed_surface(runs[1]) == pytest.approx(0.34125)


def test_the_bed_expansion_figure_draws_what_the_finding_counts(tmp_path, monkeypatch):
    """``bed_expansion.png`` (the report's, from the table's rows) shows the runs the expansion finding counts:
    a "<family>_expansion" family's runs as their family's, a taller column's in place of the paper's column's
    at its velocity, a bed whose top stood at the outlet apart (a cross), runs still on their way left out."""
    import fvdem.reports.mema2020.figures as mema
    from fvdem.reports.mema2020 import check_findings

    def row(family, ratio, height, status="finished", **more):
        return {"family": family, "status": status, "gas.u_over_umf": ratio, "t95": 3.0, "simulated_seconds": 8.0,
                "bed_expansion": height, **more}

    rows = [row("ar1", 1.6, 1.73), row("ar1", 1.6, 1.75), row("ar4_mp", 1.6, 1.63), row("ar4_mp", 1.6, 2.57),
            row("ar4_mp_expansion", 1.6, 2.2), row("ar1_expansion", 1.6, 1.72),
            row("ar1", 2.9, 3.1, bed_at_roof=1.0), row("ar1_tall", 2.9, 2.7), row("ar4_mp", 2.9, 4.0),
            row("ar4_mp", 2.9, 5.0, bed_at_roof=0.9), row("ar4_mp", 2.0, 2.8, status="running", t95=None),
            row("ar4_sp", 1.6, 1.9)]
    drawn = {}
    real = mema.plot_expansion
    monkeypatch.setattr(mema, "plot_expansion", lambda measured, roofed, path: drawn.update(
        measured=measured, roofed=roofed) or real(measured, roofed, path))
    assert mema.draw_table_figures(tmp_path, rows) == [tmp_path / "bed_expansion.png"]
    assert (tmp_path / "bed_expansion.png").stat().st_size > 10_000
    shown = sorted((r["family"], r["gas.u_over_umf"], r["bed_expansion"]) for r in drawn["measured"])
    finding = {f["finding"]: f for f in check_findings(rows)}["AR-4 beds expand more than AR-1 at the same U/Umf"]
    counted = sorted((family, float(v), h) for v, pair in finding["values"].items()
                     for family, heights in pair.items() for h in heights)
    assert shown == counted == [("ar1", 1.6, 1.72), ("ar1", 1.6, 1.73), ("ar1", 1.6, 1.75), ("ar1", 2.9, 2.7),
                                ("ar4_mp", 1.6, 1.63), ("ar4_mp", 1.6, 2.2), ("ar4_mp", 1.6, 2.57),
                                ("ar4_mp", 2.9, 4.0)]
    assert [(r["family"], r["bed_expansion"]) for r in drawn["roofed"]] == [("ar4_mp", 5.0)]  # the 1.05 m AR-1 aside
    assert mema.draw_table_figures(tmp_path, [row("ar4_sp", 1.6, 1.9)]) == []  # neither family: no figure


def test_runs_that_end_when_they_mix_count_for_the_t95_findings_alone(tmp_path, monkeypatch):
    """A family "<name>_t95" (<name>'s case ending when it mixes, from beds of its own: t95 is the entropy's first
    crossing, the same as a whole run's) counts as <name>'s in the t95 findings and Fig. 4, and "<name>_tall_t95"
    as a taller column's; neither in the bed expansion (a window it may not reach) nor in the void fractions
    (over the second half of a run that ended at t95)."""
    from fvdem.reports.mema2020 import check_findings
    from fvdem.reports.mema2020.figures import draw_figures

    def row(family, v, t95, height, binarity):
        return {"family": family, "status": "finished", "gas.u_over_umf": v, "t95": t95, "simulated_seconds": 8.0,
                "bed_expansion": height, "void_fraction_binarity": binarity}

    base = [row("ar1", 2.0, 4.21, 2.11, 0.38), row("ar1", 2.0, 5.45, 2.21, 0.42),
            row("ar4_mp", 2.0, 4.81, 2.84, 0.49), row("ar4_mp", 2.0, 5.48, 2.56, 0.51),
            row("ar1_tall", 2.9, 2.89, 2.68, 0.37), row("ar1_tall", 2.9, 3.62, 3.14, 0.38),
            row("ar4_mp_tall", 2.9, 2.64, 3.8, 0.47), row("ar4_mp_tall", 2.9, 2.89, 4.2, 0.50)]
    # cut at their t95, with heights and binarities that would turn both findings were they counted
    cut = [row("ar1_t95", 2.0, 4.6, 3.5, 0.9), row("ar1_t95", 2.0, 4.9, 3.6, 0.9),
           row("ar4_mp_t95", 2.0, 4.2, 1.2, 0.1), row("ar1_tall_t95", 2.9, 3.1, 3.3, 0.9),
           row("ar4_mp_tall_t95", 2.9, 2.7, 1.3, 0.1)]
    as_whole = [dict(r, family=r["family"][:-len("_t95")], bed_expansion=None, void_fraction_binarity=None)
                for r in cut]

    def found(rows):
        return {f["finding"]: f for f in check_findings(rows)}

    with_cut, alone, counted = found(base + cut), found(base), found(base + as_whole)
    expansion, binarity = "AR-4 beds expand more than AR-1 at the same U/Umf", "AR-1 void fractions more binary " \
        "than AR-4 (Fig. 7)"
    assert with_cut[expansion] == alone[expansion] and with_cut[binarity] == alone[binarity]
    shrinks = "the AR-1/AR-4 difference shrinks at the highest velocity (2.9 Umf)"
    assert with_cut[shrinks] == counted[shrinks] != alone[shrinks]
    assert with_cut[shrinks]["values"]["difference at 2.9 Umf"] == pytest.approx((2.89 + 3.62 + 3.1) / 3
                                                                                 - (2.64 + 2.89 + 2.7) / 3)
    assert {k: f for k, f in with_cut.items() if k not in (expansion, binarity)} == \
        {k: f for k, f in counted.items() if k not in (expansion, binarity)}
    # Fig. 4 draws them as their family's, Fig. 7 leaves them out
    import fvdem.analysis.plots as plots
    import fvdem.reports.mema2020.figures as mema
    drawn = {}
    monkeypatch.setattr(plots, "plot_t95", lambda folders, path, names=None, **kw: drawn.update(t95=sorted(names)))
    monkeypatch.setattr(mema, "plot_void_fraction_panels", lambda panels, path: drawn.update(
        fig7={v: sorted(r["name"] for r in pair) for v, pair in panels.items()}))
    for name in ("plot_mixing_by_velocity", "plot_mixing"):
        monkeypatch.setattr(plots, name, lambda *args, **kwargs: None)
    monkeypatch.setattr(mema, "plot_void_fractions", lambda *args, **kwargs: None)
    runs = [{"name": f"{r['family']}_{k}", "family": r["family"], "status": "finished", "t95": r["t95"],
             "point": {"gas.u_over_umf": r["gas.u_over_umf"]}, "folder": str(tmp_path / f"run{k}")}
            for k, r in enumerate(base + cut)]
    draw_figures(tmp_path, runs)
    assert drawn["t95"] == ["ar1"] * 7 + ["ar4_mp"] * 6  # 4 and 4 whole, 3 and 2 cut at t95
    assert drawn["fig7"] == {2.0: ["ar1_0", "ar1_1", "ar4_mp_2", "ar4_mp_3"],
                             2.9: ["ar1_tall_4", "ar1_tall_5", "ar4_mp_tall_6", "ar4_mp_tall_7"]}  # whole runs alone


def test_the_plan_of_the_open_findings_adds_the_replicas_they_ask_less_those_counted_and_on_the_way(tmp_path):
    """``plan_points`` (the report's plan.toml): AR-4 MP at 2 Umf 4.3 s (4.0, 4.6) against AR-1's 4.35 (4.0, 4.7)
    lies within the spread; the finding's plan (``replicas_to_tell``, kept in findings.json as data) asks 12 of
    AR-4 MP and 14 of AR-1 in all. The study has two of AR-1 and three of AR-4 MP there (the third not started):
    the tables raise them to 2 + 12 = 14 and 3 + (12 - 2 - 1) = 12, and appended to the study file they give
    exactly those runs, the earlier ones under their names."""
    from fvdem.reports.mema2020.plan import plan_points
    from fvdem.reports.mema2020.rules import check_findings
    from fvdem.reports.mema2020.spread import replicas_to_tell

    def row(family, t95, replica, status="finished"):
        return {"family": family, "status": status, "gas.u_over_umf": 2.0, "t95": t95, "replica": replica,
                "simulated_seconds": 8.0 if t95 else None}
    rows = [row("ar1", 4.0, 1), row("ar1", 4.7, 2), row("ar4_mp", 4.0, 1), row("ar4_mp", 4.6, 2),
            row("ar4_mp", None, 3, status="pending")]
    finding = check_findings(rows)[0]
    var = [0.18, 0.245]  # the sample variances of AR-4 MP's and AR-1's t95
    plan = replicas_to_tell([(2, var[0], None), (2, var[1], None)], 4.3 - 4.35, 0.435)
    assert plan == [12, 14] and finding["verdict"] == "open"
    assert finding["plans"] == [{"kind": "t95", "core_hours": None, "runs": [
        {"family": "ar4_mp", "u_over_umf": 2.0, "replicas": 12, "now": 2, "cpu_seconds": None},
        {"family": "ar1", "u_over_umf": 2.0, "replicas": 14, "now": 2, "cpu_seconds": None}]}]
    text = plan_points(rows, check_findings(rows), "s")
    assert "12 of ar4_mp at 2 Umf in all (now 2, 1 on the way)" in text
    mp = (f'[families.ar4_mp]\ncase = "{ROOT / "cases" / "demo.toml"}"\nbed = "small"\n'
          'set = {"particles.count" = 150}\n\n')
    study = SMOKE.read_text().replace('"../cases/', f'"{ROOT / "cases"}/').replace("[axes]", mp + "[axes]")
    study = (study.replace("replicas = 1", "replicas = 2")
             + '\n[[points]]\nfamily = "ar4_mp"\n"gas.u_over_umf" = 2.0\nreplicas = 3\n')
    path = tmp_path / "study.toml"
    path.write_text(study)
    before = {r.name for r in load_study(path, tmp_path / "out").runs}
    path.write_text(study + text)
    after = load_study(path, tmp_path / "out").runs
    at_2 = {f: sum(r.family == f and r.point["gas.u_over_umf"] == 2.0 for r in after) for f in ("ar1", "ar4_mp")}
    assert at_2 == {"ar1": 14, "ar4_mp": 12} and before <= {r.name for r in after}
    # decided (single runs 25 % apart), a finding plans nothing
    assert "plans" not in check_findings([row("ar1", 4.0, 1), row("ar4_mp", 3.0, 1)])[0]


def test_a_plans_replicas_are_of_the_cheapest_family_that_counts_in_the_column_the_study_runs():
    """A t95 finding's replicas of AR-1 at 2 Umf are of ar1_t95 where the study runs it there (they end when they
    mix), at 2.9 of ar1_tall_t95 (the taller column stands for the paper's there), at 1.6 of ar1 itself; the bed
    expansion's of ar1_expansion; a run cut short after the expansion window counts for no t95 finding, nor one
    that ends when it mixes for the expansion; and the runs on their way are counted in the column that
    stands."""
    from fvdem.reports.mema2020.plan import EXPANSION_KIND, T95, _counted_as, _on_the_way, _plan_family
    present = {("ar1", 2.0): 2, ("ar1_t95", 2.0): 8, ("ar1", 2.9): 1, ("ar1_tall", 2.9): 3,
               ("ar1_tall_t95", 2.9): 6, ("ar1", 1.6): 2, ("ar1_expansion", 1.7): 11, ("ar1", 1.7): 2}
    assert [_plan_family("ar1", v, T95, present) for v in (2.0, 2.9, 1.6, 1.7)] == [
        "ar1_t95", "ar1_tall_t95", "ar1", "ar1"]
    assert _plan_family("ar1", 1.7, EXPANSION_KIND, present) == "ar1_expansion"
    assert _plan_family("ar4_mp", 2.0, T95, present) is None
    def families(names, kind):  # the family each run counts as in a finding of ``kind`` (None: not counted)
        counted = {r["gas.u_over_umf"]: r["family"] for r in _counted_as(
            [{"family": f, "gas.u_over_umf": k} for k, f in enumerate(names)], kind)}
        return [counted.get(k) if counted.get(k) == "ar1" else None for k in range(len(names))]
    assert families(("ar1_tall_t95", "ar1_expansion", "ar1_tall", "ar1_t95"), T95) == ["ar1", None, "ar1", "ar1"]
    assert families(("ar1_t95", "ar1_expansion", "ar1"), EXPANSION_KIND) == [None, "ar1", "ar1"]
    rows = [{"family": f, "gas.u_over_umf": 2.9, "status": status, "t95": t95} for f, status, t95 in (
        ("ar1", "pending", None), ("ar1_tall", "running", 2.6), ("ar1_tall", "running", None),
        ("ar1_tall_t95", "pending", None), ("ar1_tall_t95", "finished", 2.5))]
    # the paper's column's run set aside, the mixed one counted
    assert _on_the_way(_counted_as(rows, T95), "ar1", 2.9, T95) == 2


def test_void_fraction_binarity_is_one_for_packed_or_empty_cells_and_about_a_third_for_a_uniform_spread():
    import numpy as np

    from fvdem.analysis.mixing import void_fraction_binarity
    rng = np.random.default_rng(1)
    binary = np.where(rng.random(20_000) < 0.3, 1.0, 0.4)
    assert void_fraction_binarity(binary) == pytest.approx(1.0)
    spread = rng.uniform(0.4, 1.0, 200_000)  # var 0.6^2 / 12 over (mean - a)(1 - mean), a its 2nd percentile
    assert void_fraction_binarity(spread) == pytest.approx(0.03 / ((0.7 - 0.412) * 0.3), rel=0.01)
    assert np.isnan(void_fraction_binarity(np.full(10, 0.5))) and np.isnan(void_fraction_binarity([0.5]))


def test_an_archive_of_compact_results_rebuilds_the_report_and_findings_without_the_run_folders(tmp_path):
    """fvdem study DIR --archive DEST: time series, summaries, void-fraction records and logs, no states or
    VTU; the report and findings made from DEST alone equal the ones made from the run folders."""
    import shutil

    from fvdem.cli import main
    from fvdem.study import report
    out = tmp_path / "study"
    runs = []
    for family, ratio, rate, voidage in (("ar1", 2.0, 0.5, [0.4, 0.42, 0.98, 1.0]),
                                         ("ar4_mp", 2.0, 1.2, [0.5, 0.6, 0.7, 0.8])):
        folder = out / "runs" / f"{family}_u_over_umf{ratio:g}"
        fake_run(folder, family, ratio, rate, voidage)
        runs.append({"name": folder.name, "family": family, "status": "finished", "folder": str(folder),
                     "t95": None, "point": {"gas.u_over_umf": ratio}, "replica": 1})
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
    (out / "study.toml").write_text('name = "t"\n')
    written = report(out)
    table, findings = (json.loads((out / name).read_text()) for name in ("table.json", "findings.json"))
    assert {r["family"]: r["void_fraction_binarity"] is not None for r in table} == {"ar1": True, "ar4_mp": True}
    assert out / "costs.json" in written and out / "costs.md" in written
    for name in ("costs.json", "costs.md"):  # kept aside: the archive's, made from it alone, must equal them
        (tmp_path / name).write_text((out / name).read_text())
    # the findings as a page to read: where the study stands, one row per finding with its verdict, the figures
    page = (out / "findings.md").read_text()
    assert out / "findings.md" in written and page.startswith("# t: findings\n")
    assert out / "plan.toml" in written and (out / "plan.toml").read_text().startswith("# t: the replicas that would")
    assert f"2 of 2 runs at their end, 0 on the way, 0 not started; {len(findings)} findings: " in page
    counts = {v: sum(f["verdict"] == v for f in findings) for v in ("holds", "does not hold", "open")}
    said = {"holds": "hold", "does not hold": "do not hold", "open": "open"}  # verbs agree with their counts
    assert all(f"{n} {v if n == 1 else said[v]}" in page.splitlines()[2] for v, n in counts.items() if n)
    rows = [line for line in page.splitlines() if line.startswith("| ") and not line.startswith("| finding")]
    assert [row.split(" | ")[:2] for row in rows] == [[f"| {f['finding']}", f["verdict"]] for f in findings]
    assert "![t95](t95.png)" in page and "![fig7_void_fraction](fig7_void_fraction.png)" in page
    # the channel record over 1-4 s (no inlet ramp): the 2 x 2 test grid's columns are all "inside" the
    # column's 10 x 10 gas grid, so inside carries all the gas; spheres have no alignment
    channels = [(r["corner_gas_share"], r["wall_gas_share"], r["rod_alignment_inside"]) for r in table]
    assert channels == [(0.0, 0.0, None)] * 2
    dest = tmp_path / "docs" / "data" / "t"
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    files = [p for p in dest.rglob("*") if p.is_file()]
    assert not [p for p in files if p.suffix in (".vtu", ".npz", ".pvd")]
    assert all((dest / "runs" / r["name"] / "channels.json").exists() for r in runs)
    assert sum(p.stat().st_size for p in files) < 400_000
    # archived before the report kept a record (its channels.json): archived again, the record is made from the
    # run folder, though the run holds no more simulated time than the archive
    kept = dest / "runs" / runs[0]["name"] / "channels.json"
    record = kept.read_text()
    kept.unlink()
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    assert kept.read_text() == record
    # the study raised a run's duration after it ended ([[durations]]): archived again, the archive says so,
    # and its report shows the run with more to run (not as ended)
    index = json.loads((out / "study.json").read_text())
    index["runs"][0]["duration"] = 8.0
    (out / "study.json").write_text(json.dumps(index))
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    raised = {r["name"]: r for r in json.loads((dest / "table.json").read_text())}
    assert raised[runs[0]["name"]]["status"] == "pending" and raised[runs[0]["name"]]["duration"] == 8.0
    # archived before the report kept a column (its time series without bed_top): archived again with it
    archived = dest / "runs" / runs[1]["name"] / "timeseries.csv"
    lines = [line.split(",") for line in archived.read_text().splitlines()]
    drop = lines[0].index("bed_top")
    archived.write_text("".join(",".join(x for k, x in enumerate(line) if k != drop) + "\n" for line in lines))
    assert main(["study", str(out), "--archive", str(dest)]) == 0
    assert "bed_top" in archived.read_text().splitlines()[0]
    assert raised[runs[1]["name"]]["status"] == "finished"
    index["runs"][0].pop("duration")
    (out / "study.json").write_text(json.dumps(index))
    json_index = json.loads((dest / "study.json").read_text())
    json_index["runs"][0].pop("duration")
    (dest / "study.json").write_text(json.dumps(json_index))
    assert main(["study", str(dest), "--report"]) == 0
    shutil.rmtree(out)  # the run folders are gone: the archive alone
    assert main(["study", str(dest), "--report"]) == 0
    again = json.loads((dest / "table.json").read_text())
    def rounded(value):  # the archive keeps 6 significant digits
        if isinstance(value, float):
            return float(f"{value:.4g}")
        if isinstance(value, dict):
            return {k: rounded(v) for k, v in value.items()}
        return [rounded(v) for v in value] if isinstance(value, list) else value
    assert rounded(json.loads((dest / "findings.json").read_text())) == rounded(findings)
    assert rounded(table) == rounded(again)
    assert (dest / "runs" / "ar1_u_over_umf2" / "run.log").exists() and (dest / "fig7_void_fraction_2.png").exists()
    # what the runs cost, per family, point and processor, from the archive alone as from the run folders
    assert (dest / "costs.json").read_text() == (tmp_path / "costs.json").read_text()
    assert (dest / "costs.md").read_text() == (tmp_path / "costs.md").read_text()
    assert [(c["family"], c["runs"], c["cpu_per_simulated_second"]["median"])
            for c in json.loads((dest / "costs.json").read_text())] == [("ar1", 1, 22.5), ("ar4_mp", 1, 22.5)]
    # the results as one file (docs/data/mema2020.json): the table's rows, the findings, what made them
    assert main(["study", str(dest), "--results", str(tmp_path / "results.json")]) == 0
    results = json.loads((tmp_path / "results.json").read_text())
    assert results["study"] == "t" and results["findings"] == json.loads((dest / "findings.json").read_text())
    assert [r["name"] for r in results["runs"]] == [r["name"] for r in again] and "folder" not in results["runs"][0]
    assert results["ran"].startswith("2 of 2 runs reached their end, 0 on the way, 0 not started")
    # the processor the runs' CPU seconds were spent on, beside their host
    assert results["machine"]["hosts"] == ["vm (AMD EPYC (family 26, model 2), 2 CPUs, 1 thread(s) a run)"]
    assert results["costs"] == json.loads((dest / "costs.json").read_text())
    assert main(["study", str(tmp_path), "--results", str(tmp_path / "r.json")]) == 2  # not a study folder


def test_the_t95_chart_shows_runs_that_mixed_or_ended_not_runs_on_their_way(tmp_path, monkeypatch):
    """``report`` derives each run's status once, and the t95 chart takes the runs that mixed or ended unmixed
    (the end a lower bound of t95), not those with more to run; a run that ended early, mixed
    ``time.stop_after_mixed`` before, has ended (not "pending" short of its duration)."""
    import fvdem.analysis.plots as plots
    from fvdem.study import report
    drawn = []
    monkeypatch.setattr(plots, "plot_t95", lambda folders, path, names=None, references=None, aside=None: drawn.append(
        sorted(Path(f).name for f in folders)) or path)
    out = tmp_path / "study"
    mixed, slow = out / "runs" / "mixed", out / "runs" / "slow"
    fake_run(mixed, "ar1", 2.0, 1.2, [0.5])  # entropy 0.95 at 2.5 s
    fake_run(slow, "ar1", 1.6, 0.1, [0.5])  # 0.33 at its end, 4 s
    summary = json.loads((mixed / "summary.json").read_text())
    (mixed / "summary.json").write_text(json.dumps({**summary, "t95": 2.5}))

    def chart(slow_status="finished", **entries):
        runs = [{"name": name, "family": "ar1", "status": status, "folder": str(folder), "t95": t95,
                 "point": {"gas.u_over_umf": ratio}, **entries.get(name, {})}
                for name, folder, ratio, t95, status in (("mixed", mixed, 2.0, 2.5, "finished"),
                                                         ("slow", slow, 1.6, None, slow_status))]
        (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": runs}))
        drawn.clear()
        report(out)
        table = json.loads((out / "table.json").read_text())
        return drawn[-1] if drawn else [], {r["name"]: r["status"] for r in table}

    assert chart() == (["mixed", "slow"], {"mixed": "finished", "slow": "finished"})
    # its duration raised: more to run
    assert chart(slow={"duration": 8.0}) == (["mixed"], {"mixed": "finished", "slow": "pending"})
    # ended early by time.stop_after_mixed (2.5 s + 1.5 s): ended, short of its duration
    (mixed / "summary.json").write_text(json.dumps({**summary, "t95": 2.5, "ended": "mixed"}))
    assert chart(mixed={"duration": 8.0}) == (["mixed", "slow"], {"mixed": "finished", "slow": "finished"})
    summary = json.loads((slow / "summary.json").read_text())
    (slow / "summary.json").write_text(json.dumps({**summary, "stopped_early": True}))
    assert chart("stopped")[0] == ["mixed"]  # stopped on its way
    (slow / "summary.json").unlink()
    assert chart("pending")[0] == ["mixed"]  # on its way, its first segment


def test_a_run_listed_in_progress_whose_summary_shows_its_end_is_reported_ended(tmp_path):
    """The index can lag its runs (a study stopped before it handed a finished run on listed it "stopped"):
    the report goes by the run's summary, at its end and not stopped early, and counts it ended."""
    from fvdem.study import report
    out = tmp_path / "study"
    folder = out / "runs" / "ar1_u_over_umf2"
    fake_run(folder, "ar1", 2.0, 0.5, [0.4, 0.9])
    entry = {"name": folder.name, "family": "ar1", "status": "stopped", "folder": str(folder), "replica": 1,
             "point": {"gas.u_over_umf": 2.0}, "duration": 4.0}
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [entry]}))
    report(out)
    assert json.loads((out / "table.json").read_text())[0]["status"] == "finished"
    (out / "study.json").write_text(json.dumps({"study": "t", "report": "mema2020", "runs": [{**entry, "duration": 8.0}]}))
    report(out)  # a longer duration than its summary reached: still on its way
    assert json.loads((out / "table.json").read_text())[0]["status"] == "stopped"
