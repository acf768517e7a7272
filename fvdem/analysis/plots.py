"""PNG plots of a run folder: time series and a side view of the particle colours."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np


def _pyplot():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def read_timeseries(out) -> dict:
    with open(Path(out) / "timeseries.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header, data = rows[0], np.array([[float(v) for v in r] for r in rows[1:] if r])
    return {name: data[:, k] for k, name in enumerate(header)}


def plot_timeseries(out) -> Path:
    """Kinetic energy, bed top, contacts per particle and max overlap against time."""
    plt = _pyplot()
    ts = read_timeseries(out)
    fig, axes = plt.subplots(2, 2, figsize=(9, 6), sharex=True)
    panels = [("kinetic_energy", "kinetic energy [J]", True), ("bed_top", "bed top [m]", False),
              ("contacts_per_particle", "contacts per particle", False),
              ("max_overlap_over_diameter", "max overlap / diameter", True)]
    for ax, (key, label, log) in zip(axes.flat, panels):
        values = ts[key]
        if log:
            ax.semilogy(ts["time"], np.maximum(values, 1e-30))
        else:
            ax.plot(ts["time"], values)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("time [s]")
    fig.tight_layout()
    path = Path(out) / "timeseries.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_colour_slice(out, state_file="final_state.npz", thickness=None) -> Path:
    """Side view (x-z) of the particles in a slab around the mid-plane y, coloured by tracer colour
    (as in Fig. 1 of seed 000)."""
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
    fig.tight_layout()
    path = Path(out) / "colours.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def report(out) -> list:
    """All plots for a run folder; returns the written paths."""
    return [plot_timeseries(out), plot_colour_slice(out)]
