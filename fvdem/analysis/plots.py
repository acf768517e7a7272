"""PNG plots of a run folder: time series and a side view of the particle colours."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from .mixing import MIXED


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _save(fig, path) -> Path:
    """Lay out, write as PNG and close a figure."""
    plt = _pyplot()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def pyplot():
    """matplotlib's pyplot on the Agg backend (for the report packages and the study engine's figures)."""
    return _pyplot()


def save_figure(fig, path) -> Path:
    """Lay out, write as PNG and close a figure (``_save``; for the report packages and the study engine)."""
    return _save(fig, path)


def read_timeseries(out) -> dict:
    with open(Path(out) / "timeseries.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header, data = rows[0], np.array([[float(v) for v in r] for r in rows[1:] if r])
    return {name: data[:, k] for k, name in enumerate(header)}


def series_t95(ts: dict, level=MIXED):
    """t95 [s] of a run's time series (``read_timeseries``): None where it did not mix or has no entropy."""
    from .mixing import mixing_time
    return mixing_time(ts["time"], ts["mixing_entropy"], level) if "mixing_entropy" in ts else None


LOG_SCALE = {"kinetic_energy", "max_overlap_over_diameter"}
NOT_PLOTTED = {"vertical_momentum", "wall_force_vertical"}  # bookkeeping for pressure-drop averages, not states to watch
LABELS = {"kinetic_energy": "kinetic energy [J]", "bed_top": "bed top [m]",
          "contacts_per_particle": "contacts per particle", "max_overlap_over_diameter": "max overlap / diameter",
          "rms_speed": "RMS particle speed [m/s]", "max_speed": "max particle speed [m/s]",
          "gas_max_speed": "max gas speed [m/s]", "gas_inlet_pressure": "inlet pressure [Pa]",
          "porous_zone_pressure_gradient": "porous-zone -dp/dz [Pa/m]",
          "mixing_entropy": "mixing entropy S_tot", "lacey_index": "Lacey index",
          "pressure_drop_over_weight": "bed pressure drop / (W/A)"}


def log_panel(ax, time, values) -> None:
    """A log-scale panel: zeros (the state at t = 0) are left out, not drawn at a floor that stretches the
    axis to 1e-30, and the axis spans at most six decades below the largest value."""
    values = np.where(np.asarray(values) > 0, values, np.nan)
    ax.semilogy(time, values)
    positive = values[np.isfinite(values)]
    if positive.size:
        ax.set_ylim(bottom=0.5 * max(positive.min(), 1e-6 * positive.max()))


def run_labels(runs) -> list[str]:
    """Labels that tell run folders apart: each folder's name, with as many parent folders as it takes
    where two names are the same (``a/demo`` and ``b/demo``)."""
    paths = [Path(r).resolve() for r in runs]
    depth = 1
    while depth < 32:
        labels = ["/".join(p.parts[-depth:]) for p in paths]
        if len(set(labels)) == len(labels) or all(depth >= len(p.parts) for p in paths):
            return labels
        depth += 1
    return [str(p) for p in paths]


def plot_timeseries(out) -> Path:
    """Every recorded diagnostic against time (whatever the run's phases wrote)."""
    ts = read_timeseries(out)
    keys = [k for k in ts if k != "time" and k not in NOT_PLOTTED][:8]
    return timeseries_panels([ts], [None], keys, Path(out) / "timeseries.png")


def timeseries_panels(series, labels, keys, path) -> Path:
    """``keys`` of the time series ``series`` (``read_timeseries``'s) against time, a panel each, two columns, a
    line a series (labelled ``labels``, a legend where they are not None)."""
    plt = _pyplot()
    rows = (len(keys) + 1) // 2
    fig, axes = plt.subplots(rows, 2, figsize=(9.5, 2.7 * rows), sharex=True, squeeze=False)
    for ax, key in zip(axes.flat, keys):
        for ts, label in zip(series, labels):
            if key in LOG_SCALE:
                log_panel(ax, ts["time"], ts[key])
                ax.get_lines()[-1].set_label(label)
            else:
                ax.plot(ts["time"], ts[key], label=label)
        ax.set_ylabel(LABELS.get(key, key))
        ax.grid(alpha=0.3)
    for ax in list(axes.flat)[len(keys):]:
        ax.set_visible(False)
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    if any(label is not None for label in labels):
        axes.flat[0].legend(fontsize=7)
    return _save(fig, path)


def plot_gas_profile(out) -> Path:
    """Layer-averaged pressure and voidage against height from the last gas snapshot."""
    import meshio
    plt = _pyplot()
    last = sorted(Path(out).glob("gas_*.vtu"))[-1]
    grid = meshio.read(last)
    centres = grid.points[grid.cells[0].data].mean(axis=1)
    z = np.round(centres[:, 2], 9)
    layers = np.unique(z)
    pressure = np.array([grid.cell_data["pressure"][0][z == h].mean() for h in layers])
    voidage = np.array([grid.cell_data["voidage"][0][z == h].mean() for h in layers])
    fig, (left, right) = plt.subplots(1, 2, figsize=(8, 5), sharey=True)
    left.plot(pressure, layers)
    left.set_xlabel("pressure [Pa]")
    left.set_ylabel("z [m]")
    right.plot(voidage, layers)
    right.set_xlabel("voidage")
    for ax in (left, right):
        ax.grid(alpha=0.3)
    fig.suptitle(f"gas, {last.name}")
    return _save(fig, Path(out) / "gas_profile.png")


def plot_colour_slice(out, state_file="final_state.npz", thickness=None) -> Path:
    """Side view (x-z) of the particles in a slab around the mid-plane y, coloured by tracer colour
    (as in Fig. 1 of Mema et al. (2020))."""
    plt = _pyplot()
    with np.load(Path(out) / state_file) as data:
        pos, colour, radius = data["position"], data["colour"], data["radius"]
        axis, half = data["axis"], data["half_length"]
    y_mid = 0.5 * (pos[:, 1].min() + pos[:, 1].max())
    slab = thickness or 4.0 * float(radius.max() + half.max())
    sel = np.abs(pos[:, 1] - y_mid) < 0.5 * slab
    fig, ax = plt.subplots(figsize=(4, 8))
    colours = np.where(colour[sel] == 0, "tab:blue", "tab:orange")
    if np.any(half > 0):
        for p, a, h, c in zip(pos[sel], axis[sel], half[sel], colours):
            ax.plot([p[0] - h * a[0], p[0] + h * a[0]], [p[2] - h * a[2], p[2] + h * a[2]], color=c,
                    lw=2.5, solid_capstyle="round")
    else:
        ax.scatter(pos[sel, 0], pos[sel, 2], s=6, c=colours, linewidths=0)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]")
    ax.set_ylim(0, max(0.05, float((pos[:, 2]).max()) * 1.1))
    ax.set_title(f"colours in a {slab * 1e3:.0f} mm slab at mid-depth")
    return _save(fig, Path(out) / "colours.png")


def plot_mixing(runs, path, level=MIXED) -> Path:
    """Mixing entropy against time for one or more run folders on one chart (Mema et al. (2020) Figs. 2-3),
    the t95 of each marked."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4))
    for out, name in zip(runs, run_labels(runs)):
        ts = read_timeseries(out)
        if "mixing_entropy" not in ts:
            continue
        t95 = series_t95(ts, level)
        label = name + (f" (t95 = {t95:.2f} s)" if t95 is not None else " (t95 not reached)")
        line, = ax.plot(ts["time"], ts["mixing_entropy"], label=label)
        if t95 is not None:
            ax.axvline(t95, color=line.get_color(), ls=":", lw=1)
    ax.axhline(level, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("mixing entropy S_tot")
    ax.set_ylim(0, 1.05)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    return _save(fig, Path(path))


LINE_STYLES = ("-", "--", ":", "-.")


def plot_mixing_by_velocity(runs, path, names=None, styles=None, velocities=None, levels=None, level=MIXED,
                            ended=None) -> Path:
    """Mixing entropy against time in the paper's layout (Mema et al. (2020) Figs. 2, 3 and 9 a): one colour per
    U/Umf, one line style per group (``names``, the group of each run, by default its case name; ``styles``:
    group -> matplotlib line style, else solid, dashed, ... in the groups' order), replicas in their point's colour
    and style, each run's t95 a dot on the 0.95 line; one legend entry per group and U/Umf with its runs' t95s
    ("> end" for a run not mixed by its end, "on its way at t" for one not mixed by the time it has reached, where
    ``ended``, a flag per run, says it has not ended: its time bounds nothing yet). ``velocities``: only runs at
    these U/Umf. ``levels``: the U/Umf a velocity's colour is ranked among (a study's, so that a velocity has one
    colour on all its charts), else the runs'."""
    from ..case import load_case
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6.5, 4))
    curves = []
    for k, out in enumerate(runs):
        ts = read_timeseries(out)
        case = load_case(Path(out) / "case.toml")
        ratio = round(u_over_umf(case), 6)
        if "mixing_entropy" in ts and (velocities is None or any(abs(ratio - v) < 1e-6 for v in velocities)):
            curves.append((case.name if names is None else names[k], ratio, ts, True if ended is None else ended[k]))
    groups = list(dict.fromkeys(name for name, _, _, _ in curves))
    style = {name: (styles or {}).get(name, LINE_STYLES[j % len(LINE_STYLES)]) for j, name in enumerate(groups)}
    ratios = sorted({ratio for _, ratio, _, _ in curves})
    ranks = sorted({round(float(v), 6) for v in levels} | set(ratios)) if levels is not None else ratios
    if len(ranks) <= 10:  # distinct colours, in the order of the velocities
        colour = {ratio: plt.get_cmap("tab10")(ranks.index(ratio)) for ratio in ratios}
    else:
        colour = {ratio: plt.get_cmap("viridis")(0.9 * ranks.index(ratio) / (len(ranks) - 1)) for ratio in ratios}
    labelled = {}
    for name, ratio, ts, done in sorted(curves, key=lambda c: (c[1], groups.index(c[0]))):
        t95 = series_t95(ts, level)
        labelled.setdefault((name, ratio), []).append(
            f"{t95:.2f} s" if t95 is not None else f"> {ts['time'][-1]:.3g} s" if done
            else f"on its way at {ts['time'][-1]:.3g} s")
        ax.plot(ts["time"], ts["mixing_entropy"], style[name], color=colour[ratio], lw=1.2)
        if t95 is not None:
            ax.plot(t95, level, "o", color=colour[ratio], ms=3.5)
    for (name, ratio), t95s in labelled.items():
        ax.plot([], [], style[name], color=colour[ratio], label=f"{name}, {ratio:g} Umf: t95 {', '.join(t95s)}")
    ax.axhline(level, color="grey", lw=0.8, ls="--")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("mixing entropy S_tot")
    ax.set_ylim(0, 1.05)
    ax.grid(alpha=0.3)
    if labelled:
        ax.legend(fontsize=7, loc="lower right")
    return _save(fig, Path(path))


def u_over_umf(case) -> float:
    """A case's U/Umf: ``gas.u_over_umf``, else the inlet velocity over ``gas.umf`` (the inlet velocity without
    one)."""
    g = case.gas
    if g.u_over_umf is not None:
        return float(g.u_over_umf)
    return float(g.inlet_velocity / g.umf if g.umf else g.inlet_velocity)


COLOUR_LAYERS = "colour_layers.json"  # an archived run's colour by layer (``scenes.observables.colour_layer_record``)
FEW = 20  # particles: a layer with fewer is left blank on the chart (a few particles thrown up, not a bed)


def _layer_panel(ax, record: dict, t95, title: str):
    """One colour-by-layer map (``plot_colour_layer_panels``) on ``ax``; returns its mesh for a colour bar."""
    from matplotlib.colors import TwoSlopeNorm
    times = np.asarray(record["times"], float)
    fraction = np.array([[np.nan if x is None else x for x in row] for row in record["fraction"]], float)
    fraction[np.asarray(record["count"]) < FEW] = np.nan
    step = np.diff(times).min() if len(times) > 1 else 1.0
    edges_t = np.concatenate([times - 0.5 * step, [times[-1] + 0.5 * step]])
    edges_z = record["z_lower"] + record["layer_height"] * np.arange(fraction.shape[1] + 1)
    mesh = ax.pcolormesh(edges_t, edges_z, np.ma.masked_invalid(fraction.T), cmap="coolwarm",
                         norm=TwoSlopeNorm(0.5, 0.0, 1.0), shading="flat")
    if t95 is not None:
        ax.axvline(t95, color="k", ls=":", lw=1, label=f"t95 = {t95:.2f} s")
        ax.legend(fontsize=7, loc="upper right")
    ax.set_xlabel("time [s]")
    ax.set_title(title, fontsize=9)
    return mesh


def plot_colour_layer_panels(items, path) -> Path:
    """Where beds are still unmixed: for each ``(name, record, t95)`` (``record`` a run's colour by layer,
    ``fvdem.scenes.observables.colour_layer_record``; ``t95`` None where it did not mix) a map of the colour-1
    fraction by layer (the mixing grid's height) against time, side by side on one height scale: 0.5 white,
    layers of fewer than ``FEW`` particles blank, t95 dotted."""
    plt = _pyplot()
    fig, axes = plt.subplots(1, len(items), figsize=(1.5 + 4.5 * len(items), 4), sharey=True, squeeze=False,
                             layout="constrained")
    for ax, (name, record, t95) in zip(axes[0], items):
        mesh = _layer_panel(ax, record, t95, f"colour by layer, {name}")
    axes[0][0].set_ylabel("height of the layer [m]")
    fig.colorbar(mesh, ax=list(axes[0]), label="colour-1 fraction")
    fig.savefig(path, dpi=120)  # (laid out by the constrained layout: a colour bar shared by the panels)
    plt.close(fig)
    return Path(path)


def plot_colour_layers(out, record: dict) -> Path:
    """A run's colour by layer (``plot_colour_layer_panels``) as ``colour_layers.png``, its t95 from its time series."""
    t95 = series_t95(read_timeseries(out)) if (Path(out) / "timeseries.csv").exists() else None
    return plot_colour_layer_panels([(Path(out).name, record, t95)], Path(out) / "colour_layers.png")


def mixing_times(runs, level=MIXED, names=None) -> dict:
    """``{name: [(U/Umf, t95 or None, simulated end), ...]}`` of run folders (their case.toml and
    timeseries.csv), sorted by U/Umf (runs at the same U/Umf, such as replicas, by t95, unmixed last):
    the data of Mema et al.'s Fig. 4. ``names``: the group of each run (a study's families); by default
    its case name."""
    from ..case import load_case
    groups = {}
    for k, out in enumerate(runs):
        case = load_case(Path(out) / "case.toml")
        ratio = u_over_umf(case)
        ts = read_timeseries(out)
        t95 = series_t95(ts, level)
        name = case.name if names is None else names[k]
        groups.setdefault(name, []).append((float(ratio), t95, float(ts["time"][-1])))
    return {name: sorted(rows, key=lambda row: (row[0], row[1] is None, row[1] or 0.0, row[2]))
            for name, rows in groups.items()}


def plot_t95(runs, path, level=MIXED, names=None, references=None, aside=None) -> Path:
    """Mixing time t95 against U/Umf, one line per case name (or per ``names``, the group of each
    run; Mema et al. (2020) Fig. 4). Each run is a marker (replicas side by side at their U/Umf); the line
    joins the means of the replicas at each U/Umf. A run that has not reached the level is an open triangle
    at its end time (t95 is later), and a mean that counts one so is open too: a lower bound. ``references``
    (name -> ``(t95, from U/Umf, label)``): a published value drawn as a dashed line in that name's colour from
    that U/Umf on (the paper's terminal mixing times). ``aside`` (name -> another name): runs drawn as crosses
    in the other's colour, without a line (runs a study's findings set aside, shown beside those they count)."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    bounds = False
    colours = {}
    aside = aside or {}
    groups = mixing_times(runs, level, names)
    for name, rows in sorted(groups.items(), key=lambda item: item[0] in aside):  # lines first: their colours
        by = {}
        for ratio, t, end in rows:
            by.setdefault(ratio, []).append((t, end))
        ratios = sorted(by)
        if name in aside:
            colour = colours.get(aside[name], "0.4")
            for r in ratios:
                for t, end in by[r]:
                    ax.plot(r, end if t is None else t, "^" if t is None else "x", mfc="none", color=colour, ms=6)
                    bounds = bounds or t is None
            ax.plot([], [], "x", color=colour, ms=6, label=name)
            continue
        means = [float(np.mean([t if t is not None else end for t, end in by[r]])) for r in ratios]
        replicas = max(len(v) for v in by.values()) > 1
        line, = ax.plot(ratios, means, "-")
        colour = colours[name] = line.get_color()
        ax.plot([], [], "o-", color=colour, ms=4, label=f"{name} (runs; the line: mean of its replicas)"
                if replicas else name)
        for r, mean in zip(ratios, means):
            if len(by[r]) > 1:  # the mean: filled if every replica mixed, open if it is a lower bound
                bounded = any(t is None for t, _ in by[r])
                ax.plot(r, mean, "_", color=colour, ms=12, mew=2 if not bounded else 1)
            offsets = (np.arange(len(by[r])) - (len(by[r]) - 1) / 2) * 0.015
            for (t, end), dx in zip(by[r], offsets):
                if t is not None:
                    ax.plot(r + dx, t, "o", color=colour, ms=4)
                else:
                    ax.plot(r + dx, end, "^", mfc="none", color=colour, ms=6)
                    bounds = True
    if bounds:
        ax.plot([], [], "^", mfc="none", color="0.3", label="not mixed by the run's end (a lower bound)")
    right = ax.get_xlim()[1]
    for name, (t95, start, label) in (references or {}).items():
        if name in colours:
            ax.plot([start, max(right, start + 0.1)], [t95, t95], "--", color=colours[name], lw=1.2, label=label)
    ax.set_xlabel("U / Umf")
    ax.set_ylabel(f"mixing time t{round(100 * level)} [s]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return _save(fig, Path(path))


def plot_void_fraction_histogram(out, below=0.3) -> Path:
    """Histogram of the cell voidage below ``below`` [m] and inside the bed (``cells_in_bed``: the empty
    freeboard of a bed lower than ``below`` left out) over all gas snapshots (Mema et al. (2020) Fig. 7)."""
    import meshio
    from .mixing import cells_in_bed
    plt = _pyplot()
    values = []
    for path in sorted(Path(out).glob("gas_*.vtu"))[1:]:  # the first snapshot is the initial state
        grid = meshio.read(path)
        centres = grid.points[grid.cells[0].data].mean(axis=1)
        voidage = np.asarray(grid.cell_data["voidage"][0])
        values.append(voidage[cells_in_bed(voidage, centres, below)])
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    if values and sum(v.size for v in values):
        counts, edges = np.histogram(np.concatenate(values), bins=20, range=(0.0, 1.0), density=True)
        ax.bar(0.5 * (edges[1:] + edges[:-1]), counts, width=np.diff(edges), edgecolor="k", lw=0.4)
    ax.set_xlabel("cell void fraction")
    ax.set_ylabel("probability density")
    ax.set_title(f"cells below z = {below} m inside the bed, {len(values)} snapshots")
    ax.grid(alpha=0.3)
    return _save(fig, Path(out) / "void_fraction.png")


def plot_orientation(out, state_file="final_state.npz") -> Path:
    """Distribution of the angle between particle axes and the vertical against the random
    orientation's sin(angle)."""
    from .mixing import orientation_angles
    plt = _pyplot()
    with np.load(Path(out) / state_file) as data:
        angles = orientation_angles(data["axis"])
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    ax.hist(np.degrees(angles), bins=18, range=(0, 90), density=True, edgecolor="k", lw=0.4, label="particles")
    phi = np.linspace(0, 90, 91)
    ax.plot(phi, np.sin(np.radians(phi)) * np.pi / 180, "k--", label="random: sin(angle)")
    ax.set_xlabel("angle between axis and vertical [deg]")
    ax.set_ylabel("probability density [1/deg]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, Path(out) / "orientation.png")


def plot_suspension(out) -> Path:
    """A periodic suspension: slip Reynolds number over time with the steady window and its mean
    (+- standard error) from summary.json, and the particle velocity fluctuations over the settling
    velocity."""
    import json
    series = read_timeseries(out)
    summary = json.loads((Path(out) / "summary.json").read_text()).get("suspension") or {}
    plt = _pyplot()
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(6.5, 5.5), sharex=True)
    t = series["time"]
    top.plot(t, series["slip_reynolds"], lw=0.8, label="slip Re")
    if summary:
        top.axvspan(summary["window_start"], summary["window_end"], color="tab:green", alpha=0.12,
                    label="steady window (MSER)")
        top.axhline(summary["slip_reynolds"], color="tab:green",
                    label=f"mean {summary['slip_reynolds']:.2f} +- {summary['slip_reynolds_standard_error']:.2f}")
    top.set_ylabel("Re = (<u_z> - <u_pz>) d_e / nu")
    top.legend(fontsize=8)
    top.grid(alpha=0.3)
    settling = np.where(np.abs(series["settling_velocity"]) > 0, series["settling_velocity"], np.nan)
    bottom.plot(t, series["velocity_fluctuation_vertical"] / settling, label="vertical")
    bottom.plot(t, series["velocity_fluctuation_horizontal"] / settling, label="horizontal")
    bottom.set_xlabel("time [s]")
    bottom.set_ylabel("velocity fluctuation / settling velocity")
    bottom.legend(fontsize=8)
    bottom.grid(alpha=0.3)
    return _save(fig, Path(out) / "suspension.png")


def _has_rods(out) -> bool:
    with np.load(Path(out) / "final_state.npz") as data:
        return bool(np.any(data["half_length"] > 0))


# the plots a scene's observables name (fvdem.scenes): name -> (plot function of a run folder, whether
# the folder holds what it needs)
PLOTS = {
    "timeseries": (plot_timeseries, lambda out: (out / "timeseries.csv").exists()),
    "colours": (plot_colour_slice, lambda out: (out / "final_state.npz").exists()),
    "orientation": (plot_orientation, lambda out: (out / "final_state.npz").exists() and _has_rods(out)),
    "gas_profile": (plot_gas_profile, lambda out: any(out.glob("gas_*.vtu"))),
    "void_fraction": (plot_void_fraction_histogram, lambda out: len(list(out.glob("gas_*.vtu"))) > 1),
    "mixing": (lambda out: plot_mixing([out], out / "mixing.png"),
               lambda out: "mixing_entropy" in read_timeseries(out)),
    "suspension": (plot_suspension, lambda out: (out / "summary.json").exists()
                   and "slip_reynolds" in read_timeseries(out)),
}


def report(out, plots=None) -> list:
    """The plots of a run folder (``plots``: names in ``PLOTS``; default: all of them) that its files
    support; returns the written paths. Those its scene declares: ``fvdem.scenes.plots_of(out)``."""
    out = Path(out)
    paths = []
    for name in plots or tuple(PLOTS):
        plot, available = PLOTS[name]
        if available(out):
            paths.append(plot(out))
    return paths
