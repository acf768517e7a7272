"""Observables of a periodic suspension (Derksen): slip Reynolds number, velocity fluctuations,
orientation distribution, and the automatic choice of a statistically steady window.

Slip velocity. Derksen defines ``Re = (<u_z> - <u_pz>) d_e / nu`` with ``<u_z>`` the liquid
velocity averaged over the whole box, particle interiors included (its immersed-boundary fluid
moves with the particles there), so ``<u_z> = (1 - phi) u_f + phi u_p`` is the mixture's volume
flux and ``<u_z> - <u_pz> = (1 - phi) (u_f - u_p)`` -- the settling velocity of a Richardson-Zaki
experiment (the particles' velocity in the frame of zero volume flux). In an unresolved model ``u_f``
is the liquid's interstitial mean, ``sum(eps u V) / sum(eps V)`` over the cells, and ``u_p`` the
particles' mean velocity.
"""
from __future__ import annotations

import numpy as np

from .mixing import orientation_angles


def settling_velocity(voidage, cell_volumes, fluid_velocity, particle_velocity) -> tuple[float, float]:
    """``((1 - phi) (u_f - u_p), phi)`` along z [m/s]: the settling velocity and the solids fraction
    ``phi = 1 - sum(eps V) / sum(V)``. ``fluid_velocity`` (C, 3) interstitial [m/s]."""
    eps = np.asarray(voidage, float)
    volume = np.asarray(cell_volumes, float)
    fluid_volume = eps * volume
    phi = 1.0 - fluid_volume.sum() / volume.sum()
    u_f = float((fluid_volume * np.asarray(fluid_velocity)[:, 2]).sum() / fluid_volume.sum())
    u_p = float(np.asarray(particle_velocity)[:, 2].mean())
    return (1.0 - phi) * (u_f - u_p), float(phi)


def velocity_fluctuations(particle_velocity) -> tuple[float, float]:
    """Root-mean-square particle velocity fluctuation [m/s]: vertical, and horizontal (per
    horizontal component, ``sqrt((var u_x + var u_y) / 2)``)."""
    v = np.asarray(particle_velocity, float)
    var = v.var(axis=0)
    return float(np.sqrt(var[2])), float(np.sqrt(0.5 * (var[0] + var[1])))


def orientation_histogram(axis, bins: int = 18):
    """Density of the angle [rad] between the particle axes and the vertical, folded to [0, pi/2]
    (an axis has no sign). Random orientations give ``sin(angle)``. Returns ``(density, edges)``."""
    return np.histogram(orientation_angles(axis), bins=bins, range=(0.0, 0.5 * np.pi), density=True)


def steady_window(times, values, batches: int = 10) -> dict:
    """The statistically steady part of a series and its mean with an uncertainty.

    The start of the window is the MSER-5 truncation point (White 1997; White, Cobb & Spratt 2000):
    on means ``y`` of 5 consecutive samples, the ``d`` minimising ``sum_{i>=d} (y_i - mean_d)^2 /
    (m - d)^2``, searched over the first half of the series, which
    drops an initial transient without a hand-set threshold. The uncertainty is the standard error of
    the mean from ``batches`` batch means (batches long against the correlation time give
    independent means). Returns ``{"start", "mean", "standard_error", "samples", "std"}``."""
    t = np.asarray(times, float)
    x = np.asarray(values, float)
    n = len(x)
    if n < 2 * batches:
        raise ValueError(f"a steady window needs at least {2 * batches} samples, got {n}")
    # MSER-5: the statistic on means of 5 consecutive samples (less noisy than on single samples)
    m = n // 5
    y = x[: 5 * m].reshape(m, 5).mean(axis=1)
    tail_sum = np.cumsum(y[::-1])[::-1]
    tail_sq = np.cumsum((y * y)[::-1])[::-1]
    remaining = m - np.arange(m)
    tail_mean = tail_sum / remaining
    statistic = (tail_sq - remaining * tail_mean ** 2) / remaining ** 2
    start = 5 * int(np.argmin(statistic[: m // 2]))
    window = x[start:]
    usable = (len(window) // batches) * batches
    means = window[len(window) - usable:].reshape(batches, -1).mean(axis=1)
    return {"start": float(t[start]), "mean": float(window.mean()),
            "standard_error": float(means.std(ddof=1) / np.sqrt(batches)),
            "samples": int(len(window)), "std": float(window.std())}


def richardson_zaki_fit(solids_fraction, reynolds) -> dict:
    """Least-squares fit of ``Re = Re_inf (1 - phi)^N`` in log space: ``{"re_inf", "n_exponent",
    "r2"}`` (``r2`` of the log-linear fit)."""
    x = np.log(1.0 - np.asarray(solids_fraction, float))
    y = np.log(np.asarray(reynolds, float))
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (slope * x + intercept)
    total = ((y - y.mean()) ** 2).sum()
    return {"re_inf": float(np.exp(intercept)), "n_exponent": float(slope),
            "r2": float(1.0 - (residual ** 2).sum() / total) if total > 0 else 1.0}


def richardson_zaki_exponent(re_inf: float) -> float:
    """Richardson-Zaki for spheres in the intermediate regime, ``N = 4.45 Re_inf^-0.1``
    (1 < Re_inf < 500)."""
    return 4.45 * re_inf ** -0.1
