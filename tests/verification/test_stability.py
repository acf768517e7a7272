"""The stability map's boundaries sit where theory puts them, and fvdem refuses the unstable side."""
import sys

import pytest

from paths import TOOLS

sys.path.insert(0, str(TOOLS))
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


def test_cfd_step_fails_at_one_courant_number_and_the_case_file_refuses_before_it():
    """The gas column diverges at the same inlet Courant number U dt / dx for 3.16 and 10 m/s (a
    Courant limit of the solver's explicit parts, not a time-scale one), between 1.0 and 1.6, and a
    case file above the limit of 1 is refused with the cause before anything runs."""
    result = stability_map.cfd_map([1.0, 1.6], scenes=((3.16, 0), (10.0, 0)), steps=60)
    for scene, boundary in result["boundaries"].items():
        assert boundary["largest_stable"] == 1.0 and boundary["diverged_from"] == 1.6, scene
    for p in result["points"]:
        if p["status"] == "diverged":
            assert "Courant number" in p["reason"]
    from fvdem.case import CaseError, case_from_dict
    table = {"particles": {"count": 0}, "domain": {"upper": [0.06, 0.06, 0.45]},
             "gas": {"enabled": True, "cells": [4, 4, 30], "inlet_velocity": 3.16, "cfd_step": 6e-3}}
    with pytest.raises(CaseError) as err:
        case_from_dict(table)
    assert "inlet Courant number U dt / dx = 1.26" in str(err.value) and "use cfd_step <= 0.00475" in str(err.value)
    table["gas"]["cfd_step"] = 4e-3
    case_from_dict(table)  # 0.84: accepted


def test_runtime_warns_once_when_a_cell_courant_number_exceeds_one():
    # 3.16 m/s through a fixed porous zone of voidage 0.6, 15 mm cells, CFD step 4.5 ms: inlet Courant
    # number 0.95 (accepted by the case check), 1.58 in the zone, where the gas runs at U / eps. (In an
    # empty column the warning came only from the start-up overshoot of the cell velocities, issue 14.)
    import warnings
    import fvdem
    from fvdem.case import case_from_dict
    case = case_from_dict({"particles": {"count": 0}, "domain": {"upper": [0.06, 0.06, 0.45]},
                           "output": {"progress": False},
                           "gas": {"enabled": True, "cells": [4, 4, 30], "inlet_velocity": 3.16, "cfd_step": 4.5e-3,
                                   "porous_zone": {"enabled": True, "lower": [0, 0, 0], "upper": [0.06, 0.06, 0.1],
                                                   "voidage": 0.6, "particle_diameter": 0.005}}})
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fvdem.Simulation(case).run(20 * 4.5e-3)
    messages = [str(w.message) for w in caught if "Courant" in str(w.message)]
    assert len(messages) == 1 and "exceeds 1" in messages[0]


def test_gas_running_away_stops_the_run_with_the_cause_and_the_setting():
    """A walled column whose gas runs at 10 x what its inlet (in the densest packing) or its particles
    drive is stopped (issue 19: the slow speed-accuracy point ran for hours with 26 m/s gas in a
    3.4 m/s inlet)."""
    import pytest
    import fvdem
    from fvdem.case import case_from_dict
    case = case_from_dict({"particles": {"count": 0}, "domain": {"upper": [0.06, 0.06, 0.45]},
                           "output": {"progress": False}, "gas": {"enabled": True, "cells": [4, 4, 30],
                                                                  "inlet_velocity": 1.0}})
    sim = fvdem.Simulation(case)
    sim.run(0.01)
    sim.gas.solver.velocity[5, 2] = 40.0  # 12 x U / 0.3
    with pytest.raises(fvdem.SimulationError, match="gas runs away.*gas.cfd_step"):
        sim._on_events(sim.schedules["timeseries"].next_after(sim.step_count))


def test_a_step_grown_far_costlier_than_the_recent_ones_is_warned_once():
    import pytest
    import fvdem
    from fvdem.case import case_from_dict
    case = case_from_dict({"particles": {"count": 20, "diameter": "5 mm"}, "domain": {"upper": [0.05, 0.05, 0.1]},
                           "output": {"progress": False}, "time": {"end": 1.0}})
    sim = fvdem.Simulation(case)
    sim.run(0.002)
    sim.watch.recent.clear()
    for _ in range(5):
        sim.watch.cost(100, 0.1)  # the typical step: 1 ms
    sim.watch.cost(100, 0.5)  # 5 x: nothing
    with pytest.warns(RuntimeWarning, match="costs 30 x the run's recent typical step.*reduce time.dem_step"):
        sim.watch.cost(100, 3.0)
    import warnings
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.watch.cost(100, 3.0)  # once only


def test_a_suspended_run_is_not_a_runaway(monkeypatch):
    """The run's wall clock jumps by an hour between any two readings (the process stopped with SIGSTOP,
    or the machine asleep): the runaway watch is given each chunk's CPU time, which did not jump, so no step looks
    costlier (issue 18's first ramps, paused for benchmarks, warned "a step costs 451 x
    the run's recent typical step")."""
    import types
    import fvdem
    import fvdem.simulation as simulation
    from fvdem.case import case_from_dict
    case = case_from_dict({"particles": {"count": 20, "diameter": "5 mm"}, "domain": {"upper": [0.05, 0.05, 0.1]},
                           "output": {"progress": False, "timeseries_interval": 0.001}, "time": {"end": 1.0}})
    sim = fvdem.Simulation(case)
    sim.run(0.005)
    real = simulation._time
    calls = {"n": 0}

    def jumping_clock():  # an hour lost between two readings
        calls["n"] += 1
        return real.perf_counter() + 3600.0 * calls["n"]

    given = []
    monkeypatch.setattr(simulation, "_time", types.SimpleNamespace(perf_counter=jumping_clock,
                                                                   process_time=real.process_time))
    monkeypatch.setattr(sim.watch, "cost", lambda steps, seconds: given.append(seconds))
    sim.run(0.02)
    assert calls["n"] > 20 and len(given) > 10
    assert max(given) < 60.0  # CPU seconds of a few steps of 20 particles, not the lost hour


def test_a_gradual_rise_of_the_cost_is_not_a_runaway():
    """Pouring a bed: contacts form and the cost per step rises 40-fold over the run (issue 15's
    settling of 32,500 rods warned at 36 x its contact-free start); no jump, no warning."""
    import warnings
    import fvdem
    from fvdem.case import case_from_dict
    case = case_from_dict({"particles": {"count": 20, "diameter": "5 mm"}, "domain": {"upper": [0.05, 0.05, 0.1]},
                           "output": {"progress": False}, "time": {"end": 1.0}})
    sim = fvdem.Simulation(case)
    sim.watch.recent.clear()
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for k in range(400):
            sim.watch.cost(100, 0.1 * 1.01 ** k)  # x 53 over the run


def _small_coupled(**gas):
    from fvdem.case import case_from_dict
    return case_from_dict({"particles": {"count": 60, "diameter": "5 mm", "insertion": {"upper": [0.04, 0.04, 0.05]}},
                           "domain": {"upper": [0.04, 0.04, 0.2]},
                           "gas": {"enabled": True, "cells": [2, 2, 10], "inlet_velocity": 2.0, **gas},
                           "time": {"end": 0.05}, "output": {"progress": False}})


def test_the_inlet_ramp_rises_linearly_then_holds_and_leaves_the_inlet_alone_after():
    import fvdem
    sim = fvdem.Simulation(_small_coupled(inlet_ramp=0.01, cfd_step=1e-3))
    s = sim.gas.solver
    assert s.inlet_velocity == 0.0
    for k in range(1, 15):
        sim.run(sim.time_step)
        assert s.inlet_velocity == pytest.approx(2.0 * min(1.0, k * 1e-3 / 0.01), rel=1e-12), k
        inflow = -s.face_flux[sim.gas.mesh.boundary_faces["z-"]].sum() / (0.04 * 0.04)
        assert inflow == pytest.approx(s.inlet_velocity, rel=1e-9)
    s.set_inlet_velocity(1.0)  # a tool's own ramp (tools/validate_umf.py) after the start-up
    sim.run(sim.time_step)
    assert s.inlet_velocity == 1.0


def test_a_ramped_run_resumes_bit_for_bit(tmp_path):
    """Stopped inside the ramp (0.011 of 0.02 s) and resumed: the ramp continues where it was."""
    import dataclasses
    import numpy as np
    import fvdem
    case = _small_coupled(inlet_ramp=0.02)
    fvdem.Simulation(case, tmp_path / "straight").run()
    fvdem.Simulation(dataclasses.replace(case, time=dataclasses.replace(case.time, end=0.011)), tmp_path / "split").run()
    fvdem.Simulation(case, tmp_path / "split", resume=True).run()
    for name in ("position", "velocity"):
        a = np.load(tmp_path / "straight" / "final_state.npz")[name]
        b = np.load(tmp_path / "split" / "final_state.npz")[name]
        np.testing.assert_array_equal(a, b)


def test_large_overlaps_and_particles_against_the_roof_are_warned_once_with_the_setting():
    import warnings
    import fvdem
    sim = fvdem.Simulation(_small_coupled())
    values = sim.diagnostics()
    sim.watch.particles(dict(values, max_overlap_over_diameter=0.072))  # what the defaults reach: no warning
    with pytest.warns(RuntimeWarning, match=r"largest overlap is 8.8 % .*raise contact.normal_stiffness.*"
                                            r"mixed no faster with a 4x stiffer spring"):
        sim.watch.particles(dict(values, max_overlap_over_diameter=0.088))
    p = sim.particles
    p.position[:10, 2] = 0.2 - p.radius[:10]  # ten of sixty pressed against the roof
    with pytest.warns(RuntimeWarning, match=r"10 particles \(16.7 %\) are against the outlet.*gas.inlet_ramp"):
        sim.watch.particles(values)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        sim.watch.particles(dict(values, max_overlap_over_diameter=0.09))  # each once only
    # the advice follows the cause: within an inlet ramp, a plug lifted at the start (a longer ramp); after it, a
    # fluidized bed throwing particles up (a taller column or a lower velocity; the ramp is no remedy)
    for ramp, steps, cause in ((1.0, 0, r"rose as a plug.*within 1 s\); a longer gas.inlet_ramp"),
                               (1e-3, 3, r"threw them up to the roof after the inlet's 0.001 s ramp.*taller domain.upper")):
        sim = fvdem.Simulation(_small_coupled(inlet_ramp=ramp, cfd_step=5e-4))
        if steps:
            sim.run(steps * sim.time_step)
        p = sim.particles
        p.position[:10, 2] = 0.2 - p.radius[:10]
        with pytest.warns(RuntimeWarning, match=cause):
            sim.watch.particles(sim.diagnostics())
