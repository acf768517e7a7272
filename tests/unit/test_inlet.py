"""The inlet's schedule (``gas.inlet_ramp``, ``gas.inlet_steps``; fvdem/gas/inlet.py): the velocity of each CFD
step, the case's checks, and a defluidization ramp as a case feature, the same run bit for bit as the one a tool
used to make by setting the solver's inlet between runs."""
import numpy as np
import pytest

import fvdem
from fvdem.analysis.defluidization import defluidization_steps
from fvdem.case import CaseError, case_from_dict, to_toml
from fvdem.gas.inlet import InletSchedule


def _table(**gas):
    return {"particles": {"count": 60, "diameter": "5 mm", "insertion": {"upper": [0.04, 0.04, 0.05]}},
            "domain": {"upper": [0.04, 0.04, 0.2]},
            "gas": {"enabled": True, "cells": [2, 2, 10], "inlet_velocity": 2.0, "cfd_step": 1e-3, **gas},
            "time": {"end": 0.05}, "output": {"progress": False}}


def test_the_velocity_of_each_step_ramp_full_then_steps():
    inlet = InletSchedule(2.0, 0.004, [(0.006, 1.5), (0.0081, 0.5)], 1e-3)
    # the ramp's steps take its value at their end; then the full velocity; each pair from its step on
    expected = [0.5, 1.0, 1.5, 2.0, 2.0, 2.0, 1.5, 1.5, 0.5, 0.5]
    assert [inlet.of_step(n) for n in range(10)] == pytest.approx(expected, rel=1e-12)
    # what a step changes: the ramp's steps and the pairs' first steps, nothing else
    assert [inlet.change_before(n) is not None for n in range(10)] == [True] * 4 + [False, False, True, False, True,
                                                                                   False]
    assert inlet.after(0) == 0.0 and inlet.after(7) == 1.5 and inlet.maximum == 2.0 and inlet.varies
    steady = InletSchedule(2.0, 0.0, (), 1e-3)
    assert not steady.varies and steady.change_before(0) is None and steady.after(5) == 2.0


def test_a_pair_at_the_ramp_s_end_takes_the_first_step_after_it():
    """A ramp that is not a whole number of steps ends inside one: a pair at its end starts at the first step
    past it rather than being lost."""
    inlet = InletSchedule(2.0, 0.0045, [(0.0045, 1.0)], 1e-3)
    assert [inlet.of_step(n) for n in range(4, 7)] == [2.0 * min(1.0, 5e-3 / 0.0045), 1.0, 1.0]


def test_steps_are_read_with_units_written_back_and_checked():
    case = case_from_dict(_table(inlet_ramp=0.01, inlet_steps=[["10 ms", "150 cm/s"], [0.02, 1.0]]))
    assert case.gas.inlet_steps == ((0.01, 1.5), (0.02, 1.0))
    assert "inlet_steps = [\n    [0.01, 1.5],\n    [0.02, 1.0],\n]" in to_toml(case)
    import tomllib
    assert case_from_dict(tomllib.loads(to_toml(case))) == case
    for steps, message in (([[0.005, 1.0]], "falls inside the start-up ramp"),
                           ([[0.02, 1.0], [0.015, 0.5]], "the times must increase"),
                           ([[0.02, 1.0], [0.0202, 0.5]], "fall in one CFD step"),
                           ([[0.02, -1.0]], r"inlet_steps\[0\]\[1\]"),
                           ([0.02, 1.0], "expected a list of \\[time, value\\] pairs"),
                           ([[0.02, 30.0]], "inlet Courant number")):
        with pytest.raises(CaseError, match=message):
            case_from_dict(_table(inlet_ramp=0.01, inlet_steps=steps))
    periodic = {"domain": {"upper": [0.04, 0.04, 0.04], "periodic": [True, True, True]},
                "gas": {"enabled": True, "cells": [2, 2, 2], "inlet_steps": [[0.01, 1.0]]}}
    with pytest.raises(CaseError, match="gas.inlet_steps: a periodic box has no inlet"):
        case_from_dict(periodic)


def _fields(sim):
    return {"position": sim.particles.position, "velocity": sim.particles.velocity,
            "gas_velocity": sim.gas.velocity, "pressure": sim.gas.pressure}


def test_a_defluidization_schedule_is_the_former_tool_s_run_bit_for_bit(tmp_path):
    """tools/validate_umf.py used to set the solver's inlet velocity at each hold's start between runs; the
    case's steps make the same run, bit for bit, and a run stopped inside a hold resumes to it."""
    start, velocities, holds = 0.01, [2.0, 1.4, 0.8], [0.004, 0.003, 0.005]
    steps, ends = defluidization_steps(start, velocities, holds)
    assert steps == [(0.01, 2.0), (0.014, 1.4), (0.017, 0.8)] and ends == pytest.approx([0.014, 0.017, 0.022])
    by_hand = fvdem.Simulation(case_from_dict(_table(inlet_ramp=start)))
    by_hand.run(start)
    for u, end in zip(velocities, ends):
        by_hand.gas.solver.set_inlet_velocity(u)  # what the tool did
        by_hand.run(end - by_hand.time)
    table = _table(inlet_ramp=start, inlet_steps=[list(pair) for pair in steps])
    scheduled = fvdem.Simulation(case_from_dict(table))
    inlet = InletSchedule(2.0, start, steps, 1e-3)
    for n in range(int(round(ends[-1] / 1e-3))):
        scheduled.run(1e-3)
        assert scheduled.gas.inlet_velocity == inlet.of_step(n), n
    assert scheduled.step_count == by_hand.step_count == 22
    for name, value in _fields(by_hand).items():
        np.testing.assert_array_equal(_fields(scheduled)[name], value, err_msg=name)
    fvdem.Simulation(case_from_dict(table, overrides={"time.end": 0.0155}), tmp_path / "split").run()
    resumed = fvdem.Simulation(case_from_dict(table, overrides={"time.end": ends[-1]}), tmp_path / "split",
                               resume=True)
    assert resumed.gas.inlet_velocity == 1.4
    resumed.run()
    for name, value in _fields(by_hand).items():
        np.testing.assert_array_equal(_fields(resumed)[name], value, err_msg=name)
