"""The stability map's boundaries sit where theory puts them, and fvdem refuses the unstable side."""
import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import stability_map  # noqa: E402


def test_explicit_drag_fails_just_below_two_response_times_and_semi_implicit_never():
    """Forward Euler on the drag diverges beyond dt = 2 m / (dF/dv) = 2 tau_p / (1 + dln c / dln v);
    at Re ~ 0.04 the Hoelzer-Sommerfeld coefficient rises by ~1 % of the rate: boundary ~1.98 tau_p."""
    result = stability_map.drag_map([0.5, 1.0, 1.9, 1.95, 2.0, 2.05, 3.0, 10.0, 20.0])
    assert result["explicit_unstable_from"] in (1.95, 2.0)
    assert result["semi_implicit_unstable_from"] is None
    assert all(p["semi-implicit"]["final_error"] < 1e-6 for p in result["points"])


def test_voidage_jumps_are_the_methods_theoretical_bounds():
    result = stability_map.voidage_map([0.75, 1.25, 2.0], samples=80)
    for p in result["points"]:
        jump = p["largest_jump_over_particle_fraction"]
        if p["method"] == "centroid":
            assert jump == pytest.approx(1.0, rel=1e-9)
        elif p["method"] == "divided":
            assert jump == pytest.approx(0.2, rel=1e-9)
        else:  # continuous: no more than what the smooth motion of one sample step changes
            assert jump <= p["smooth_limit"] * (1 + 1e-9)


def test_dem_steps_beyond_the_resolvable_are_refused_with_the_cause():
    result = stability_map.dem_map([14, 3, 1.9])
    by_ratio = {round(1 / p["dt_over_collision_time"], 3): p for p in result["points"]}
    assert by_ratio[14]["status"] == "ran" and abs(by_ratio[14]["restitution_error"]) < 0.01
    assert by_ratio[3]["status"] == "refused" and "cannot be reached" in by_ratio[3]["reason"]
    assert by_ratio[1.9]["status"] == "refused" and "exceeds half the collision time" in by_ratio[1.9]["reason"]
