"""Scenes (issue 15): every case is exactly one registered scene, the scene decides what is measured,
and the orchestration holds no scene-specific name."""
import re

import pytest

from fvdem.case import case_from_dict
from fvdem.model import stepping_of
from fvdem.scenes import SCENES, scene_for
from output_keys import CASES, case_of
from paths import ROOT

EXPECTED = {"ar1": "fluidized_bed", "ar4_mp": "fluidized_bed", "ar4_mp_drag": "fluidized_bed",
            "ar4_sp": "fluidized_bed", "coupled_small": "fluidized_bed", "demo": "fluidized_bed",
            "bed_ar1": "settling", "bed_ar4": "settling", "fixed_bed_gas": "fixed_bed",
            "hindered_settling": "periodic_suspension"}


@pytest.mark.parametrize("name", CASES)
def test_each_case_is_one_scene(name):
    case = case_of(name)
    assert [n for n, kind in SCENES.items() if kind.applies(case)] == [EXPECTED[name]]
    assert scene_for(case).name == EXPECTED[name]


@pytest.mark.parametrize("particles, fixed, gas, coupled, periodic, scene, stepping", [
    (100, False, True, True, False, "fluidized_bed", "coupled"),
    (100, False, True, True, True, "periodic_suspension", "coupled"),
    (100, True, True, True, False, "fixed_bed", "coupled"),
    (100, True, True, False, False, "fixed_bed", "gas"),
    (0, False, True, True, False, "fixed_bed", "gas"),
    (100, False, True, False, False, "settling", "side-by-side"),
    (100, False, False, True, False, "settling", "dem"),
    (100, False, False, True, True, "settling", "dem"),
])
def test_every_combination_has_exactly_one_scene_and_one_stepping(particles, fixed, gas, coupled, periodic,
                                                                   scene, stepping):
    table = {"particles": {"count": particles, "fixed": fixed, "diameter": "5 mm"},
             "domain": {"upper": [0.05, 0.05, 0.2], "periodic": [periodic] * 3},
             "gas": {"enabled": gas, "cells": [2, 2, 8]}, "coupling": {"enabled": coupled}}
    if fixed and not gas:
        return
    case = case_from_dict(table)
    assert [n for n, kind in SCENES.items() if kind.applies(case)] == [scene]
    assert stepping_of(case) == stepping


def test_simulation_holds_no_scene_specific_name():
    source = (ROOT / "fvdem" / "simulation.py").read_text()
    words = ["suspension", "mixing", "pressure_drop", "bed_weight", "porous", "slip_reynolds", "fluidized",
             "colour", "periodic", "t95", "orientation"] + list(SCENES)
    found = [w for w in words if re.search(w, source, re.IGNORECASE)]
    assert not found, f"simulation.py names {found}: that belongs in fvdem/scenes/"
    assert len(source.splitlines()) <= 210  # issue 15: "at most ~200 lines"


def test_report_draws_what_the_scene_declares(tmp_path):
    import fvdem
    from fvdem.analysis.plots import report
    from fvdem.scenes import plots_of
    out = tmp_path / "demo"
    fvdem.Simulation(case_of("demo"), out, threads=1).run()
    assert plots_of(out) == ("timeseries", "colours", "orientation", "gas_profile", "void_fraction", "mixing",
                             "colour_layers")
    written = sorted(p.name for p in report(out, plots_of(out)))
    # spheres: no orientation plot
    assert written == ["colour_layers.png", "colours.png", "gas_profile.png", "mixing.png", "timeseries.png",
                       "void_fraction.png"]


def test_the_colour_by_layer_from_snapshots_and_from_its_archived_record_is_the_same(tmp_path):
    """The colour-1 fraction by layer of a run's particle snapshots: the last snapshot's layers agree with its
    final state binned directly (the mixing grid's layers over the column); an archive keeps the record as
    JSON without the snapshots, and the report draws the same chart from it."""
    import json
    import shutil

    import numpy as np
    import fvdem
    from fvdem.analysis.mixing import colour_by_layer, mixing_cells
    from fvdem.analysis.plots import COLOUR_LAYERS, report
    from fvdem.scenes.observables import colour_layer_record
    out = tmp_path / "demo"
    case = case_of("demo")
    fvdem.Simulation(case, out, threads=1).run()
    record = colour_layer_record(out)
    with np.load(out / "final_state.npz") as state:
        layers = mixing_cells(case)[2]
        count, fraction = colour_by_layer(state["position"], state["colour"], case.domain.lower, case.domain.upper,
                                          layers)
    kept = len(record["count"][-1])
    assert record["count"][-1] == count[:kept].tolist() and not count[kept:].any()
    assert record["fraction"][-1] == [None if np.isnan(x) else round(float(x), 4) for x in fraction[:kept]]
    assert record["layer_height"] == pytest.approx((case.domain.upper[2] - case.domain.lower[2]) / layers)
    archived = tmp_path / "archived"
    archived.mkdir()
    for name in ("case.toml", "timeseries.csv"):
        shutil.copy(out / name, archived / name)
    (archived / COLOUR_LAYERS).write_text(json.dumps(record))
    assert colour_layer_record(archived) == record
    assert [p.name for p in report(archived, ("colour_layers",))] == ["colour_layers.png"]


def test_the_vertical_momentum_column_is_the_particles_momentum_against_gravity(tmp_path):
    """``vertical_momentum`` (the pressure-drop averages' acceleration correction, tools/validate_umf.py)
    is sum m v . (-g/|g|), whatever the direction of gravity."""
    import numpy as np
    import fvdem
    from fvdem.scenes.observables import Particles
    table = {"particles": {"count": 30, "diameter": "5 mm"}, "domain": {"upper": [0.05, 0.05, 0.2]},
             "gas": {"enabled": False}, "output": {"progress": False}}
    sim = fvdem.Simulation(case_from_dict(table), tmp_path / "run", progress=False)
    p = sim.particles
    p.velocity[:] = np.random.default_rng(1).normal(size=p.velocity.shape)
    values = Particles().measure(sim.model, {})
    assert values["vertical_momentum"] == pytest.approx(float((p.mass * p.velocity[:, 2]).sum()), rel=1e-12)
    sim.model.dem.gravity[:] = (9.81, 0.0, 0.0)
    values = Particles().measure(sim.model, {})
    assert values["vertical_momentum"] == pytest.approx(-float((p.mass * p.velocity[:, 0]).sum()), rel=1e-12)


def test_the_wall_force_column_is_the_weight_a_resting_bed_puts_on_the_floor(tmp_path):
    """Particles settled on the floor of a closed box: the walls carry the whole weight, and the pair
    forces cancel in the column's sum (``wall_force_vertical`` = m g to the settling's residue)."""
    import numpy as np
    import fvdem
    from fvdem.scenes.observables import Particles
    table = {"particles": {"count": 4, "diameter": "5 mm"}, "domain": {"upper": [0.02, 0.02, 0.03]},
             "gas": {"enabled": False}, "output": {"progress": False}}
    sim = fvdem.Simulation(case_from_dict(table), tmp_path / "run", progress=False)
    sim.run(0.4)
    p = sim.particles
    weight = float(p.mass.sum()) * 9.81
    values = Particles().measure(sim.model, {})
    assert float(np.abs(p.velocity).max()) < 1e-2
    assert values["wall_force_vertical"] == pytest.approx(weight, rel=2e-2)
