"""A poured bed of frictional spheres packs at the random-packing solids fraction."""
import fvdem
from fvdem.case import case_from_dict


def poured_sphere_bed(rolling_friction, duration=0.45):
    """2,000 spheres (d = 5.3 mm, mu = 0.46) poured into a laterally periodic 6 x 6 cm box.
    After 0.45 s the core packing is fixed (only a few spheres still roll on top when mu_r = 0)."""
    case = case_from_dict({
        "name": "packing",
        "domain": {"lower": [0, 0, 0], "upper": [0.06, 0.06, 0.2], "periodic": [True, True, False]},
        "particles": {"shape": "sphere", "count": 2000, "diameter": "5.3 mm", "density": 1442.0,
                      "insertion": {"upper": [0.06, 0.06, 0.14], "seed": 3}},
        "contact": {"rolling_friction": rolling_friction},
        "time": {"end": duration},
        "output": {"progress": False},
    })
    summary = fvdem.Simulation(case).run()
    assert summary["rms_speed"] < 0.02, "bed still moving"
    return summary


def test_random_packing_fraction_and_rolling_friction_packs_looser():
    dense = poured_sphere_bed(rolling_friction=0.0)
    loose = poured_sphere_bed(rolling_friction=0.46)
    print(f"\nsolids fraction: mu_r = 0: {dense['solids_fraction']:.4f} "
          f"(coordination {dense['contacts_per_particle']:.2f}); mu_r = 0.46: {loose['solids_fraction']:.4f} "
          f"(coordination {loose['contacts_per_particle']:.2f})")
    assert 0.58 <= dense["solids_fraction"] <= 0.64
    assert loose["solids_fraction"] < dense["solids_fraction"] - 0.01
