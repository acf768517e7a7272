"""The settled beds several tools start from: the final states of ``cases/bed_ar1.toml`` (32,500 spheres)
and ``cases/bed_ar4.toml`` (32,500 AR-4 rods), in ``runs/bed_ar1/`` and ``runs/bed_ar4/`` (where
``fvdem run cases/bed_ar1.toml --out runs/bed_ar1`` puts them; ``FVDEM_BEDS_DIR`` moves the folder).

A tool calls ``settled_beds`` before it measures anything: a missing bed is settled there and then,
as ``fvdem study`` prepares its beds (with a progress bar and a line saying what it costs), and later
runs reuse it. ``quick``: small beds of the same particles (1,500, fvdem's default spring and steps,
seconds to settle) in ``bed_<name>_quick/``, for the tools' ``--quick`` modes and the test suite.

``fluidized_states``: the same beds fluidized, the coupled cases (``cases/ar1.toml``, ``cases/ar4_mp.toml``)
at 2.0 x fvdem's own Umf from a full-speed start at the defaults, run once for ``duration`` simulated seconds
into ``fluidized_<name>[_quick]_<duration>s/checkpoint.npz`` (the DEM's and the gas's state, with the drag the
particles last felt): what the fluidized-step benchmark (``bench_fluidized.py``) measures from.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CASES = {"ar1": ROOT / "cases" / "bed_ar1.toml", "ar4": ROOT / "cases" / "bed_ar4.toml"}
# wall time to settle the full bed, one run of fvdem on 2 cores (docs/studies.md, "What a run costs")
COST = {"ar1": "a few minutes", "ar4": "about 15-30 minutes"}
QUICK = {"particles.count": 1500, "domain.upper": [0.15, 0.15, 0.2], "particles.insertion.upper": [0.15, 0.15, 0.06],
         "contact.normal_stiffness": 800.0, "time.dem_step": 5e-5, "time.min_time": 0.1, "time.end": 0.3,
         "output.timeseries_interval": 0.01, "run.threads": 1}
QUICK_COUNT = QUICK["particles.count"]
# the coupled case of each bed, and fvdem's own simulated Umf of the paper's closures for it [m/s]
# (docs/validation.md, "Minimum fluidization velocity"): 2.0 x this fluidizes fvdem's bed as the paper's
# 2.0 Umf fluidized the experiment's
COUPLED = {"ar1": ROOT / "cases" / "ar1.toml", "ar4": ROOT / "cases" / "ar4_mp.toml"}
OWN_UMF = {"ar1": 1.914, "ar4": 1.896}
# fvdem's defaults (docs/speed-accuracy.md) and a full-speed start: the bed lifts within 0.5 s and bubbles
FLUIDIZE = {"contact.normal_stiffness": 800.0, "time.dem_step": 5e-5, "gas.cfd_step": 5e-4, "gas.inlet_ramp": 0.0,
            "gas.u_over_umf": 2.0, "output.vtk": False, "output.timeseries_interval": 0.01}


def beds_dir() -> Path:
    return Path(os.environ.get("FVDEM_BEDS_DIR") or ROOT / "runs")


def state_path(name: str, quick: bool = False) -> Path:
    return beds_dir() / f"bed_{name}{'_quick' if quick else ''}" / "final_state.npz"


def bed_overrides(name: str, quick: bool = False) -> dict:
    """Case keys that start a run of the paper's column from this bed (its state, and its count)."""
    return {"particles.initial_state": str(state_path(name, quick)),
            **({"particles.count": QUICK_COUNT} if quick else {})}


def bed_of_case(case_path) -> str | None:
    """The bed (``ar1``, ``ar4``) whose settled state a case file starts from, or None (its own state,
    or insertion)."""
    import tomllib
    state = tomllib.loads(Path(case_path).read_text()).get("particles", {}).get("initial_state")
    name = Path(state).parent.name if isinstance(state, str) else ""
    return name.removeprefix("bed_") if name in ("bed_ar1", "bed_ar4") else None


def settled_beds(names, tool: str, quick: bool = False) -> dict:
    """``{name: final_state.npz}`` of each bed, settling the missing ones first (before any measuring)."""
    import fvdem
    states = {}
    for name in dict.fromkeys(names):
        state = state_path(name, quick)
        if not state.exists():
            size = "1,500-particle quick" if quick else "32,500-particle"
            print(f"{tool}: settling the {size} bed {name} once into {state.parent} ({'seconds' if quick else COST[name]}; "
                  "later runs reuse it)", file=sys.stderr, flush=True)
            case = fvdem.load_case(CASES[name], dict(QUICK, **{"output.vtk": False}) if quick else None)
            resume = (state.parent / "checkpoint.npz").exists()  # a settling stopped earlier goes on
            fvdem.Simulation(case, state.parent, resume=resume, overwrite=not resume, progress=not quick).run()
        states[name] = state
    return states


def fluidized_path(name: str, duration: float, quick: bool = False) -> Path:
    return beds_dir() / f"fluidized_{name}{'_quick' if quick else ''}_{duration:g}s" / "checkpoint.npz"


def fluidized_states(names, tool: str, duration: float, quick: bool = False, threads: int = 1) -> dict:
    """``{name: checkpoint.npz}`` of each bed fluidized for ``duration`` simulated seconds (``FLUIDIZE``),
    run first where missing (the settled bed too); a fluidization stopped earlier goes on from its checkpoint.
    The full beds cost about 5 (AR-1) and 10 (AR-4) minutes of wall time per simulated second on 2 cores."""
    import fvdem
    settled = settled_beds(names, tool, quick)
    states = {}
    for name in dict.fromkeys(names):
        state = fluidized_path(name, duration, quick)
        if not (state.parent / "summary.json").exists():
            print(f"{tool}: fluidizing the {'quick' if quick else 'full'} bed {name} once for {duration:g} s into "
                  f"{state.parent} (later runs reuse it)", file=sys.stderr, flush=True)
            overrides = dict(FLUIDIZE, **{"particles.initial_state": str(settled[name]), "gas.umf": OWN_UMF[name],
                                          "time.end": duration, "output.checkpoint_interval": min(0.5, duration),
                                          "run.threads": threads, **({"particles.count": QUICK_COUNT} if quick else {})})
            case = fvdem.load_case(COUPLED[name], overrides)
            resume = state.exists()
            fvdem.Simulation(case, state.parent, resume=resume, overwrite=not resume, progress=not quick).run()
        states[name] = state
    return states


def settled_dem(name: str, state: Path):
    """``(case, DEMSystem)`` of the bed case ``name`` holding the settled bed saved in ``state`` (no gas)."""
    import numpy as np

    import fvdem
    from fvdem.dem.particles import ParticleArrays
    from fvdem.model import build_dem
    case = fvdem.load_case(CASES[name])
    with np.load(state) as data:
        particles = ParticleArrays.from_dict({k: data[k] for k in data.files})
    return case, build_dem(case, particles)
