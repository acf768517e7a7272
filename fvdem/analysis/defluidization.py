"""The minimum fluidization velocity from a defluidization ramp: the inlet velocity stepped down from above Umf,
each velocity held and the bed pressure drop averaged over the second half of the hold (tools/validate_umf.py
runs it; the schedule is a case feature, ``gas.inlet_steps``).

- ``defluidization_steps``: the holds as ``gas.inlet_steps`` pairs, and when each ends;
- ``hold_statistics``: a hold's mean pressure drop from a run's time series, and the same corrected for the
  bed's acceleration over the window;
- ``plateau_of`` and ``fit_umf``: the fluidized plateau, the fixed-bed branch ``dP = a U + b U^2`` (Ergun's form,
  ``a, b >= 0``) and where the two meet (``fvdem.correlations.quadratic_crossing``).
"""
from __future__ import annotations

import numpy as np

from ..correlations import quadratic_crossing

FLUIDIZED_FROM = 1.3  # holds at and above this multiple of the experimental Umf make the plateau
FIXED_BRANCH_BELOW = 0.85  # the fixed-bed branch: the lowest velocities up to the first hold at this fraction of W/A


def defluidization_steps(start: float, velocities, holds):
    """``(steps, ends)``: the ``gas.inlet_steps`` pairs ``(time [s], velocity [m/s])`` of holds of ``holds`` [s]
    at ``velocities`` [m/s] in turn, the first from ``start`` [s] (the start-up ramp's end), and the time each
    hold ends [s] (``start + cumsum(holds)``)."""
    ends = start + np.cumsum(np.asarray(holds, float))
    begins = [float(start), *(float(t) for t in ends[:-1])]
    return [(t, float(u)) for t, u in zip(begins, velocities)], ends


def plateau_of(velocity, drop, umf_experiment, touched_roof=None) -> float:
    """The mean of ``drop`` [Pa] over the holds at and above ``FLUIDIZED_FROM`` x ``umf_experiment`` [m/s], less
    those where the bed touched the roof (``touched_roof``, a flag per hold; all of them when every fluidized
    hold did)."""
    velocity, drop = np.asarray(velocity), np.asarray(drop)
    fluidized = velocity >= FLUIDIZED_FROM * umf_experiment
    if touched_roof is not None:
        free = fluidized & ~np.asarray(touched_roof, bool)
        if free.any():
            fluidized = free
    return float(drop[fluidized].mean())


def fit_umf(velocity, drop, weight, umf_experiment, touched_roof=None):
    """``(plateau, Umf, (a, b))`` of a defluidization curve (hold velocities [m/s], mean pressure drops [Pa],
    the bed's weight per area ``weight`` [Pa]): the plateau is ``plateau_of`` the holds; the fixed-bed branch
    ``a U + b U^2`` (least squares with ``a, b >= 0``) runs through the lowest velocities up to the first hold at
    ``FIXED_BRANCH_BELOW`` W/A (a slugging bed's short-hold mean can dip below that at high velocity: it is
    not part of the branch); Umf [m/s] is where the branch meets the plateau (None without a branch)."""
    velocity, drop = np.asarray(velocity), np.asarray(drop)
    plateau = plateau_of(velocity, drop, umf_experiment, touched_roof)
    order = np.argsort(velocity)
    below = drop[order] < FIXED_BRANCH_BELOW * weight
    count = len(below) if below.all() else int(np.argmin(below))
    fixed = np.zeros(len(velocity), bool)
    fixed[order[:count]] = True
    if fixed.sum() >= 2:
        from scipy.optimize import nnls  # Ergun's form: both coefficients non-negative
        design = np.stack([velocity[fixed], velocity[fixed] ** 2], axis=1)
        (a, b), _ = nnls(design, drop[fixed])
    elif fixed.sum() == 1:
        a, b = drop[fixed][0] / velocity[fixed][0], 0.0
    else:
        return plateau, None, (0.0, 0.0)
    return plateau, quadratic_crossing(a, b, plateau), (float(a), float(b))


def hold_statistics(series: dict, end_time: float, hold: float, sample: float, area=None):
    """The bed pressure drop over the second half of the hold of ``hold`` [s] that ended at ``end_time`` [s], from
    a run's time series (``series``: columns by name, samples every ``sample`` [s]): its mean and standard
    deviation [Pa], the highest bed top [m] (99 % of the particle tops below it) over the same samples, the mean
    corrected for the bed's acceleration [Pa] (None without ``area`` [m^2] or without the ``vertical_momentum``
    column), and the mean force the walls (distributor included) exert on the particles against gravity [N]
    (None without the ``wall_force_vertical`` column).

    The correction: the particles' momentum balance against gravity reads ``A dp = W - F_wall + dP/dt``
    (``dp`` the bed pressure drop, ``W`` the weight, ``F_wall`` what the walls carry, ``P`` the particles'
    upward momentum), so ``(1/T) int dp dt - (P(t1) - P(t0)) / (A T)`` has the long-time mean of ``dp`` and none
    of the swing of a slugging bed caught mid-rise or mid-fall by a short window: a control variate, exact in
    expectation, whose remainder is the walls' share ``-F_wall / A``."""
    t = series["time"]
    steps = int(round(hold / sample))
    first = end_time - hold + (steps // 2 + 1) * sample
    window = (t >= first - 0.25 * sample) & (t <= end_time + 0.25 * sample)
    values = series["bed_pressure_drop"][window]
    corrected = None
    momentum = series.get("vertical_momentum")
    if area is not None and momentum is not None and window.sum() > 1 and np.all(np.isfinite(momentum[window])):
        tw, mw = t[window], momentum[window]
        span = float(tw[-1] - tw[0])
        corrected = float(np.trapezoid(values, tw) / span - (mw[-1] - mw[0]) / (area * span))
    walls = series.get("wall_force_vertical")
    walls = None if walls is None or not np.all(np.isfinite(walls[window])) else float(np.mean(walls[window]))
    return (float(np.mean(values)), float(np.std(values)), float(np.max(series["bed_top"][window])),
            corrected, walls)


__all__ = ["FLUIDIZED_FROM", "FIXED_BRANCH_BELOW", "defluidization_steps", "plateau_of", "fit_umf",
           "hold_statistics"]
