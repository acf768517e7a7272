"""tools/validate_umf.py and its fits (``fvdem.analysis.defluidization``) on synthetic defluidization curves;
the ramp's schedule as the case's inlet steps; a short ramp resumed bit for bit."""
import json
import sys

import numpy as np
import pytest

from fvdem.analysis.defluidization import defluidization_steps, fit_umf, hold_statistics
from fvdem.analysis.plots import read_timeseries

from paths import TOOLS

sys.path.insert(0, str(TOOLS))
import validate_umf as tool  # noqa: E402


def _ramp(a, b, weight, umf_exp, dips=()):
    ratios = np.array([2.0, 1.7, 1.45, 1.3, 1.15, 1.05, 0.95, 0.85, 0.75, 0.65, 0.5, 0.4])
    velocity = ratios * umf_exp
    drop = np.minimum(a * velocity + b * velocity ** 2, weight)
    for index, value in dips:  # a slugging bed's short-hold mean below W/A
        drop[index] = value
    return velocity, drop


def test_fit_recovers_the_intersection_of_an_ergun_branch_with_the_plateau():
    a, b, weight = 150.0, 400.0, 1600.0
    velocity, drop = _ramp(a, b, weight, 1.58)
    plateau, umf, (fa, fb) = fit_umf(velocity, drop, weight, 1.58)
    exact = (-a + np.sqrt(a * a + 4 * b * weight)) / (2 * b)
    assert plateau == pytest.approx(weight)
    assert (fa, fb) == pytest.approx((a, b), rel=1e-9)
    assert umf == pytest.approx(exact, rel=1e-9)


def test_a_slugging_dip_above_umf_is_not_taken_for_the_fixed_branch():
    a, b, weight = 150.0, 400.0, 1600.0
    velocity, drop = _ramp(a, b, weight, 1.58, dips=[(1, 0.72 * weight)])
    plateau, umf, (fa, fb) = fit_umf(velocity, drop, weight, 1.58)
    exact = (-a + np.sqrt(a * a + 4 * b * weight)) / (2 * b)
    assert (fa, fb) == pytest.approx((a, b), rel=1e-9)  # the dip at 1.7 Umf_exp is left out of the branch
    assert plateau < weight
    assert umf < exact  # the lower plateau is met earlier; umf_at_weight in the tool's output uses W/A


def test_holds_whose_bed_touched_the_roof_are_left_out_of_the_plateau():
    """A bed pressed against the roof has the roof carry part of it: its pressure drop (here 1.9 W/A at
    2 Umf_exp) is not the fluidized bed's. Flagged, it is left out; all flagged, all are kept."""
    a, b, weight = 150.0, 400.0, 1600.0
    velocity, drop = _ramp(a, b, weight, 1.58, dips=[(0, 1.9 * weight)])
    roof = [True] + [False] * (len(velocity) - 1)
    plateau, umf, _ = fit_umf(velocity, drop, weight, 1.58, roof)
    assert plateau == pytest.approx(weight)
    assert umf == pytest.approx((-a + np.sqrt(a * a + 4 * b * weight)) / (2 * b), rel=1e-9)
    assert fit_umf(velocity, drop, weight, 1.58)[0] > 1.2 * weight  # unflagged, it moves the plateau
    everywhere = [True] * len(velocity)
    assert fit_umf(velocity, drop, weight, 1.58, everywhere)[0] == fit_umf(velocity, drop, weight, 1.58)[0]


@pytest.mark.parametrize("width, particles, column", [(0.06, 2000, 0.51), (0.15, 32500, 1.05), (0.09, 4500, 0.51)])
def test_the_column_leaves_the_bed_room_to_rise(width, particles, column):
    """The column is at least twice the height the particles are inserted to (and 0.3 m above it): the
    paper's bed gets the paper's own 1.05 m column, the small beds keep theirs."""
    table = tool.reduced_bed_table("sphere", "mp", particles, 1, width)
    assert table["domain"]["upper"][2] == pytest.approx(column)
    height = table["particles"]["insertion"]["upper"][2]
    assert column >= 2.0 * height - 1e-9 and column >= height + 0.3 - 1e-9


def test_fixed_branch_coefficients_are_non_negative():
    velocity = np.array([3.0, 2.0, 1.0, 0.8, 0.6, 0.4])
    drop = np.array([1000.0, 1000.0, 700.0, 600.0, 480.0, 330.0])  # concave: an unconstrained b < 0
    _, umf, (fa, fb) = fit_umf(velocity, drop, 1000.0, 1.5)
    assert fa >= 0 and fb >= 0 and np.isfinite(umf)


def test_a_killed_ramp_resumes_from_its_last_hold_bit_for_bit(tmp_path, monkeypatch):
    """A ramp checkpoints every 0.05 s and at a stop. Killed after a hold's last checkpoint but before
    its point was recorded (the worst moment), `resume` completes that hold from the time series and
    the restored bed; stopped inside a hold, it runs the hold's rest: either way the curve and the
    fitted Umf are the uninterrupted ramp's, bit for bit."""
    spec = {"shape": "sphere", "closures": "mp", "particles": 500, "threads": 1, "width": 0.06,
            "settings": "default", "drag": "paper", "hold": 0.06, "start": 0.15, "quick": True,
            "plateau_hold": 0.08, "out": str(tmp_path / "straight")}
    straight = tool.ramp(spec)
    original, calls = tool._hold_entry, []

    def killed_at_the_third_hold(*args, **kwargs):
        calls.append(1)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return original(*args, **kwargs)
    monkeypatch.setattr(tool, "_hold_entry", killed_at_the_third_hold)
    killed = dict(spec, out=str(tmp_path / "killed"))
    with pytest.raises(KeyboardInterrupt):
        tool.ramp(killed)
    monkeypatch.setattr(tool, "_hold_entry", original)
    progress = json.loads((tmp_path / "killed" / "ramp_sphere" / "ramp.json").read_text())
    assert len(progress["curve"]) == 2
    resumed = tool.ramp(dict(killed, resume=True))
    assert resumed["curve"] == straight["curve"] and len(resumed["curve"]) == 5
    # the plateau's holds (2.0 and 1.3 Umf,exp) took --plateau-hold, the others --hold
    ends = [c["end_time"] for c in straight["curve"]]
    assert np.allclose(np.diff([0.15] + ends), [0.08, 0.08, 0.06, 0.06, 0.06])
    assert resumed["umf_simulated"] == straight["umf_simulated"]
    # stopped (SIGTERM) inside the start or inside a hold: the checkpoint falls mid-way, the ramp says
    # so and records nothing; resumed, it runs the rest and ends as the straight ramp
    import fvdem
    original_run = fvdem.Simulation.run
    for stop_in, recorded in ((1, 0), (4, 2)):  # the start; the third hold
        runs = []

        def stopped_in_a_run(self, duration=None):
            runs.append(duration)
            if len(runs) == stop_in:
                summary = original_run(self, 0.5 * duration)
                self._stop_requested = True  # what the SIGTERM handler sets
                return summary
            return original_run(self, duration)
        monkeypatch.setattr(fvdem.Simulation, "run", stopped_in_a_run)
        stopped = dict(spec, out=str(tmp_path / f"stopped_{stop_in}"))
        with pytest.raises(tool.RampStopped, match="--resume"):
            tool.ramp(stopped)
        monkeypatch.setattr(fvdem.Simulation, "run", original_run)
        progress = json.loads((tmp_path / f"stopped_{stop_in}" / "ramp_sphere" / "ramp.json").read_text())
        assert len(progress["curve"]) == recorded
        assert tool.ramp(dict(stopped, resume=True))["curve"] == straight["curve"]
    # without --resume an existing ramp folder is started again, not mixed into
    again = tool.ramp(dict(killed))
    assert again["curve"] == straight["curve"]


def _write_series(folder, t, columns):
    names = ["time", *columns]
    rows = np.column_stack([t, *columns.values()])
    lines = [",".join(names)] + [",".join(repr(float(v)) for v in row) for row in rows]
    (folder / "timeseries.csv").write_text("\n".join(lines) + "\n")


def test_the_acceleration_correction_recovers_the_long_time_mean_from_a_fraction_of_a_slug(tmp_path):
    """A plug of mass M rising and falling with a 0.5 s period, the walls carrying 3 % of its weight:
    its momentum balance ``A dp = W - F_wall + M dv/dt`` sets the pressure drop. A window of 0.3 of a
    period catches the plug mid-swing (raw mean far from the long-time mean); less the plug's momentum
    change over the window, the mean is the long-time one, ``(W - F_wall) / A``, to the trapezoid's error."""
    area, mass, g = 0.0225, 3.6, 9.81
    weight = mass * g
    omega, amplitude = 2 * np.pi / 0.5, 0.05
    t = np.arange(0.0, 1.0 + 1e-9, tool.SAMPLE)
    velocity = amplitude * omega * np.cos(omega * t + 0.4)
    acceleration = -amplitude * omega ** 2 * np.sin(omega * t + 0.4)
    drop = (weight - 0.03 * weight + mass * acceleration) / area
    _write_series(tmp_path, t, {"bed_pressure_drop": drop, "bed_top": np.full_like(t, 0.3),
                                "vertical_momentum": mass * velocity,
                                "wall_force_vertical": np.full_like(t, 0.03 * weight)})
    hold = 0.3  # the tool averages its second half: 0.15 s, 0.3 of a period
    mean, std, top, corrected, walls = hold_statistics(read_timeseries(tmp_path), 0.8, hold, tool.SAMPLE, area)
    exact = 0.97 * weight / area
    assert abs(mean - exact) > 0.05 * exact  # the raw mean of the window is off by the swing
    assert corrected == pytest.approx(exact, rel=1e-4)
    assert std > 0.1 * exact and top == pytest.approx(0.3)
    assert walls == pytest.approx(0.03 * weight)  # what remains: the walls' share, measured apart
    assert corrected == pytest.approx((weight - walls) / area, rel=1e-4)
    # without the momentum column (a time series of an older run) there is no correction
    _write_series(tmp_path, t, {"bed_pressure_drop": drop, "bed_top": np.full_like(t, 0.3)})
    assert hold_statistics(read_timeseries(tmp_path), 0.8, hold, tool.SAMPLE, area)[3] is None
    assert hold_statistics(read_timeseries(tmp_path), 0.8, hold, tool.SAMPLE)[0] == pytest.approx(mean)


def test_a_rising_ramp_steps_up_from_the_prepared_bed_and_a_frictionless_settling_packs_denser(tmp_path):
    """--rising: the bed settles without gas first, then the inlet steps up from rest (no start-up ramp). Settled
    frictionless (the screenings' denser "packing") the bed packs denser and lower than settled with friction, as
    frictionless spheres approach random close packing (Scott & Kilgour 1969: 0.64) and frictional ones settle
    looser; the ramp itself runs at the case's own friction. A second call reuses the settled bed."""
    import tomllib
    spec = {"shape": "sphere", "closures": "mp", "particles": 500, "threads": 1, "width": 0.06,
            "settings": "default", "drag": "paper", "hold": 0.06, "start": 0.15, "quick": True,
            "plateau_hold": None, "rising": True, "preparation": "friction", "out": str(tmp_path)}
    loose = tool.ramp(spec)
    dense = tool.ramp(dict(spec, preparation="frictionless"))
    assert dense["prepared_solids_fraction"] > loose["prepared_solids_fraction"] + 0.02
    assert dense["prepared_bed_height"] < loose["prepared_bed_height"]
    # a denser bed holds its weight at less gas (Ergun: Umf grows about as voidage^3 / (1 - voidage)): the closure's
    # uniform-bed Umf at the prepared packing falls with it
    assert 0 < dense["prepared_umf_closure_uniform_bed"] < loose["prepared_umf_closure_uniform_bed"]
    for r in (loose, dense):
        velocity = [c["velocity"] for c in r["curve"]]
        assert velocity == sorted(velocity) and r["inlet_ramp_seconds"] == 0.0 and r["direction"] == "rising"
        assert r["curve"][0]["end_time"] == pytest.approx(0.06)
    case = tomllib.loads((tmp_path / "ramp_sphere_rising_frictionless" / "case.toml").read_text())
    assert case["contact"]["friction"] == 0.46 and case["contact"]["rolling_friction"] == 0.46
    state = tmp_path / "settle_sphere_rising_frictionless" / "final_state.npz"
    before = state.stat().st_mtime_ns
    assert tool.ramp(dict(spec, preparation="frictionless"))["curve"] == dense["curve"]
    assert state.stat().st_mtime_ns == before
