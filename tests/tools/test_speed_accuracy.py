"""The speed-accuracy tool's bookkeeping: errors, the Pareto front and the choice of the default."""
import sys

import pytest

from paths import TOOLS

sys.path.insert(0, str(TOOLS))
import speed_accuracy as tool  # noqa: E402


def _run(drop, height, hist, entropy):
    return {"pressure_drop_over_weight": drop, "mean_height": height, "void_fraction_histogram": hist,
            "mixing_entropy": entropy}


def test_errors_against_the_reference():
    ref = _run(1.0, 0.1, [0.5, 0.5, 0.0], {"0.5": 0.3, "1": 0.6})
    run = _run(0.97, 0.105, [0.25, 0.5, 0.25], {"0.5": 0.35, "1": 0.5})
    e = tool.errors_against(run, ref)
    assert e["pressure_drop"] == pytest.approx(0.03)
    assert e["bed_height"] == pytest.approx(0.05)
    assert e["void_fraction_histogram"] == pytest.approx(0.25)  # total variation: half the L1 distance
    assert e["mixing_entropy"] == pytest.approx(0.1)
    assert tool.errors_against(ref, ref) == {k: 0.0 for k in e}


def _point(name, shape, wall, error):
    return {"variant": name, "label": f"{shape} {name}", "shape": shape, "wall_seconds_per_simulated_second": wall,
            "normalised_error": error, "within_budget": error <= 1.0, "speed_up": 100.0 / wall}


def test_front_holds_exactly_the_undominated_points():
    points = [_point("reference", "s", 100, 0.0), _point("a", "s", 50, 0.5), _point("b", "s", 60, 0.6),
              _point("c", "s", 20, 2.0), _point("d", "s", 20, 3.0)]
    assert sorted(tool.pareto_front(points)) == ["s a", "s c", "s reference"]


def test_default_is_the_fastest_variant_within_budget_for_every_shape():
    points = [_point("reference", "s", 100, 0.0), _point("reference", "r", 200, 0.0),
              _point("fast", "s", 20, 0.9), _point("fast", "r", 90, 1.2),        # out of budget for r
              _point("medium", "s", 40, 0.8), _point("medium", "r", 80, 0.7),
              _point("sphere-only", "s", 10, 0.1),                                # not run for r
              _point("replica", "s", 5, 0.1), _point("replica", "r", 5, 0.1)]    # never a candidate
    assert tool.choose_default(points) == "medium"
