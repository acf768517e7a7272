"""A poured bed of frictional spheres packs at the random-packing solids fraction."""
import pytest

import fvdem
from fvdem.case import case_from_dict


def settled_sphere_bed(rolling_friction):
    """2,000 spheres (d = 5.3 mm) poured into a laterally periodic 6 x 6 cm box and settled."""
    case = case_from_dict({
        "name": "packing",
        "domain": {"lower": [0, 0, 0], "upper": [0.06, 0.06, 0.25], "periodic": [True, True, False]},
        "particles": {"shape": "sphere", "count": 2000, "diameter": "5.3 mm", "density": 1442.0,
                      "insertion": {"upper": [0.06, 0.06, 0.2], "seed": 3}},
        "contact": {"rolling_friction": rolling_friction},
        "time": {"end": 1.0, "stop_when_settled": True, "settled_speed": 0.005, "min_time": 0.25},
        "output": {"progress": False},
    })
    sim = fvdem.Simulation(case)
    summary = sim.run()
    assert summary["settled"], "bed did not come to rest"
    return summary


@pytest.mark.slow
def test_random_packing_fraction_without_rolling_friction():
    summary = settled_sphere_bed(rolling_friction=0.0)
    print(f"\nsolids fraction, mu_r = 0: {summary['solids_fraction']:.4f} "
          f"(coordination {summary['contacts_per_particle']:.2f}, settled at t = {summary['simulated_time']:.3f} s)")
    assert 0.58 <= summary["solids_fraction"] <= 0.64


@pytest.mark.slow
def test_rolling_friction_packs_looser():
    loose = settled_sphere_bed(rolling_friction=0.46)
    print(f"\nsolids fraction, mu_r = 0.46: {loose['solids_fraction']:.4f} "
          f"(coordination {loose['contacts_per_particle']:.2f})")
    assert 0.50 <= loose["solids_fraction"] < 0.60
