"""The paper's figures from a study's runs (``draw_figures``): mixing entropy against time per family (Fig. 2),
t95 against U/Umf (Fig. 4), AR-1 against AR-4 MP (Fig. 3) with their void fractions below 0.3 m (Fig. 7), AR-4
MP drag only against drag + lift + torque (Fig. 9); and from the table's values as the findings count them, the
bed expansion (``draw_table_figures``)."""
from __future__ import annotations

from pathlib import Path

from .families import (EXPANSION, T95_ONLY, TALL, among, column_of, expansion_runs, expansion_sample, mixed_or_ended,
                       pairs_of, point_of, row_ended, set_aside_name, t95_runs, tall_columns, told_rows)
from .rules import PAPER_TERMINAL_T95, TERMINAL_FROM
from .spread import TOLD, critical
from .table import void_fraction_record


def plot_void_fractions(runs, path, below=0.3):
    """Histograms of the cell void fraction below ``below`` [m] over the second half of each run's gas
    snapshots, on one chart, with each run's binarity (``void_fraction_binarity``; Mema et al. (2020) Fig. 7)."""
    import numpy as np
    from ...analysis.plots import pyplot, save_figure
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for r in runs:
        record = void_fraction_record(r["folder"], below)
        if record is not None:
            edges = np.asarray(record["edges"])
            binarity = "-" if record["binarity"] is None else f"{record['binarity']:.2f}"
            ax.step(0.5 * (edges[1:] + edges[:-1]), record["density"], where="mid",
                    label=f"{r['name']} (binarity {binarity})")
    ax.set_xlabel("cell void fraction")
    ax.set_ylabel("probability density")
    ax.set_title(f"cells below z = {below} m, second half of the run")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return save_figure(fig, Path(path))


FIG7_VELOCITIES = (1.6, 2.0, 2.3, 2.9)  # the paper's Fig. 7 panels (a)-(d), U/Umf


def plot_void_fraction_panels(panels: dict, path, below=0.3):
    """The paper's Fig. 7: one panel per U/Umf (``panels``: U/Umf -> runs), a histogram per family of the cell void
    fraction below ``below`` [m] over the second half of its runs' gas snapshots, the replicas pooled (each run's
    density weighted by its cells), labelled with each replica's binarity (``void_fraction_binarity``)."""
    import numpy as np
    from ...analysis.plots import pyplot, save_figure
    plt = pyplot()
    columns = min(2, len(panels))
    rows = (len(panels) + columns - 1) // columns
    fig, axes = plt.subplots(rows, columns, figsize=(5.0 * columns, 3.4 * rows), squeeze=False, sharey=True)
    for ax, (ratio, runs) in zip(axes.flat, sorted(panels.items())):
        by = {}
        for r in runs:
            record = void_fraction_record(r["folder"], below)
            if record is not None:
                by.setdefault(column_of(r), []).append(record)
        for family, records in by.items():
            edges = np.asarray(records[0]["edges"])
            cells = np.array([rec["cells"] for rec in records], float)
            density = np.average([rec["density"] for rec in records], axis=0, weights=cells)
            binarity = ", ".join("-" if rec["binarity"] is None else f"{rec['binarity']:.2f}" for rec in records)
            ax.step(0.5 * (edges[1:] + edges[:-1]), density, where="mid",
                    label=f"{family} ({len(records)} run{'s' if len(records) > 1 else ''}, binarity {binarity})")
        ax.set_title(f"{ratio:g} Umf" + ("" if by else ": no gas snapshots"), fontsize=9)
        ax.set_xlabel("cell void fraction")
        ax.grid(alpha=0.3)
        if by:
            ax.legend(fontsize=7)
    for ax in axes[:, 0]:
        ax.set_ylabel("probability density")
    for ax in list(axes.flat)[len(panels):]:
        ax.set_visible(False)
    fig.suptitle(f"cells below z = {below} m, second half of each run", fontsize=10)
    return save_figure(fig, Path(path))


def draw_table_figures(out: Path, rows: list) -> list:
    """Figures of the table's values, counted as the findings count them (``check_findings``: the runs that
    mixed or ended, a taller column's in place of the paper's column's at their point): the bed expansion
    against U/Umf, AR-1 against AR-4 MP (``bed_expansion.png``, ``plot_expansion``)."""
    counted = tall_columns(told_rows(rows))[0]
    measured, roofed = expansion_sample(expansion_runs(counted))
    families = ("ar1", "ar4_mp")
    if not any(r["family"] in families for r in measured):
        return []
    return [plot_expansion([r for r in measured if r["family"] in families],
                           [r for r in roofed if r["family"] in families], out / "bed_expansion.png")]


def plot_expansion(measured: list, roofed: list, path) -> Path:
    """Bed expansion against U/Umf, AR-1 against AR-4 MP, as the finding counts it (``_expansion``; §5.1, where
    the paper shows it in its snapshots, Figs. 5-6): the bed's top over the window (``_bed_expansion``) over
    the settled bed's. Each run is a marker (hollow: a run of a "<family>_expansion" family, cut short after the
    window), the line joins the means of the replicas at each U/Umf, with the standard error of each mean times
    Student's t (``critical`` for ``n - 1`` degrees of freedom) as a bar; a run left out for its bed top at the
    outlet is a cross."""
    import numpy as np

    from ...analysis.plots import pyplot, save_figure
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    cut_short = left_out = False
    for family, label in (("ar1", "AR-1"), ("ar4_mp", "AR-4 MP")):
        by = {}
        for r in measured:
            if r["family"] == family:
                by.setdefault(float(r["gas.u_over_umf"]), []).append(r)
        if not by:
            continue
        ratios = sorted(by)
        values = [[float(r["bed_expansion"]) for r in by[v]] for v in ratios]
        means = [float(np.mean(x)) for x in values]
        bars = [critical(len(x) - 1) * float(np.std(x, ddof=1)) / len(x) ** 0.5 if len(x) > 1 else 0.0
                for x in values]
        line = ax.errorbar(ratios, means, yerr=bars, capsize=3, lw=1.5,
                           label=f"{label} (runs; the line: mean, bar: t standard errors, t at {100 * TOLD:.1f} %)")
        colour = line[0].get_color()
        for v in ratios:
            offsets = (np.arange(len(by[v])) - (len(by[v]) - 1) / 2) * 0.012
            for r, dx in zip(by[v], offsets):
                cut = r.get("column", r["family"]).endswith(EXPANSION)
                cut_short = cut_short or cut
                ax.plot(v + dx, r["bed_expansion"], "o", ms=4, color=colour, mfc="none" if cut else colour)
        for r in roofed:
            if r["family"] == family:
                left_out = True
                ax.plot(float(r["gas.u_over_umf"]), r["bed_expansion"], "x", ms=6, color=colour)
    if cut_short:
        ax.plot([], [], "o", ms=4, mfc="none", color="0.3", label="a run cut short after the window (its own bed)")
    if left_out:
        ax.plot([], [], "x", ms=6, color="0.3", label="left out: its bed top at the outlet most of the window")
    ax.set_xlabel("U / Umf")
    ax.set_ylabel("bed expansion (bed top over the settled bed's)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return save_figure(fig, Path(path))


# the paper's pairs of families, the second drawn solid and the first dashed as in its figures, and the velocities
# its figure shows: Fig. 3 AR-1 against AR-4 MP at 1.6, 1.7 and 2.9 Umf; Fig. 9 a AR-4 MP drag only against drag,
# lift and torque at every velocity the drag-only family ran
PAPER_PAIRS = {"fig3": ("ar1", "ar4_mp", (1.6, 1.7, 2.9)), "fig9": ("ar4_mp_drag", "ar4_mp", None)}


def draw_figures(out: Path, runs: list) -> list:
    """Mixing entropy per family, a colour per velocity (Fig. 2), t95 against U/Umf (Fig. 4: the runs that mixed
    or ended), the paper's pairs at its velocities on one chart each (``PAPER_PAIRS``: ``fig3_mixing.png``,
    ``fig9_mixing.png``), and at each velocity both families ran: AR-1 against AR-4 MP run by run (Fig. 3) with
    their void fractions below 0.3 m (Fig. 7), and AR-4 MP drag only against drag + lift + torque (Fig. 9). The
    pairs take a taller column's runs that mixed or ended for their family's, as the findings do
    (``tall_columns``)."""
    from ...analysis.plots import plot_mixing, plot_mixing_by_velocity, plot_t95
    paths = []
    levels = [r["point"]["gas.u_over_umf"] for r in runs if "gas.u_over_umf" in r.get("point", {})] or None
    for family in sorted({r["family"] for r in runs}):
        mine = [r for r in runs if r["family"] == family]
        paths.append(plot_mixing_by_velocity([Path(r["folder"]) for r in mine], out / f"mixing_{family}.png",
                                             names=[family] * len(mine), levels=levels,
                                             ended=[row_ended(r) for r in mine]))
    # the paper's pairs as the findings take them: a taller column's runs that mixed or ended for their family's
    # at their point (``tall_columns``), named as their own family on the charts
    standing = [r for r in runs if not r["family"].endswith(TALL) or mixed_or_ended(r)]
    as_found = tall_columns(standing, point_of)[0]
    # Figs. 4 and 7 as the findings take them too, of the runs that mixed or ended, and the runs set aside
    # (a "<family>_expansion" family's runs, cut short after the bed-expansion window, tell no t95: ``EXPANSION``;
    # a "<family>_t95" family's, which end when they mix, count as <family>'s in Fig. 4 alone: ``T95_ONLY``)
    told = [r for r in standing if mixed_or_ended(r) and not r["family"].endswith(EXPANSION)]
    shown, set_aside = tall_columns(t95_runs(told), point_of)
    paired = {figure: sorted(pairs_of(as_found, first, second).items())
              for figure, (first, second, _) in PAPER_PAIRS.items()}
    for figure, (first, second, velocities) in PAPER_PAIRS.items():
        pairs = [r for point, pair in paired[figure] for r in pair if velocities is None or among(point, velocities)]
        if pairs:
            styles = {first: "--", second: "-", first + TALL: "--", second + TALL: "-"}
            paths.append(plot_mixing_by_velocity([Path(r["folder"]) for r in pairs], out / f"{figure}_mixing.png",
                                                 names=[column_of(r) for r in pairs], styles=styles,
                                                 levels=levels, ended=[row_ended(r) for r in pairs]))
    if shown:
        paper = {family: (t95, TERMINAL_FROM, f"{family}: the paper's terminal t95, about {t95:g} s")
                 for family, t95 in PAPER_TERMINAL_T95.items()}
        # each family's line through the values its findings count (a taller column's runs in place of the paper's
        # column's at their point, ``tall_columns``), the runs set aside as crosses in its colour
        drawn = shown + [{**r, "family": set_aside_name(family)} for (family, _), rs in set_aside.items() for r in rs]
        paths.append(plot_t95([Path(r["folder"]) for r in drawn], out / "t95.png", names=[r["family"] for r in drawn],
                              references=paper, aside={set_aside_name(family): family for family, _ in set_aside}))
    # the void fractions of the fluidized bed (Fig. 7): a run on its way and not yet mixed may still be in its
    # start-up (the second half of 0.8 s is the packed bed), so those runs wait, as in the findings
    whole = tall_columns([r for r in told if not r["family"].endswith(T95_ONLY)], point_of)[0]
    fluidized = sorted(pairs_of(whole, *PAPER_PAIRS["fig3"][:2]).items())
    panels = {point[0]: pair for point, pair in fluidized if len(point) == 1 and among(point, FIG7_VELOCITIES)}
    if panels:
        paths.append(plot_void_fraction_panels(panels, out / "fig7_void_fraction.png"))
    for figure in PAPER_PAIRS:
        for point, pair in paired[figure]:
            paths.append(plot_mixing([Path(r["folder"]) for r in pair], out / f"{figure}_mixing_{_tag(point)}.png"))
    for point, pair in fluidized:
        paths.append(plot_void_fractions(pair, out / f"fig7_void_fraction_{_tag(point)}.png"))
    return paths


def _tag(point: tuple) -> str:
    """An axes point as a file name's part: its values joined by ``_`` (2.0 and 1.6 -> "2_1.6")."""
    return "_".join(f"{v:g}" for v in point)
