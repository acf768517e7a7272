#!/usr/bin/env python
"""The DEM step in a fluidized bed, rods against spheres (issue 31): where the AR-4 study's time goes.

    python tools/bench_fluidized.py --json
    python tools/bench_fluidized.py --state-ar1 RUN/checkpoint.npz --state-ar4 RUN/checkpoint.npz --coupled

Each shape starts from a fluidized state: by default its 32,500-particle bed run once at 2.0 x fvdem's own
Umf from a full-speed start for ``--fluidize`` simulated seconds (``tools/_beds.py``, ``fluidized_states``;
about 5 and 10 minutes of wall time per simulated second on 2 cores, then reused), or any coupled run's
checkpoint (``--state-ar1``, ``--state-ar4``: the run's ``case.toml`` must lie beside it).

A round measures ``--steps`` DEM steps of each shape from that state, the gas held as the checkpoint
left it (each particle's drag coefficient and fluid velocity integrated implicitly, as in the coupled run,
lift and torque held): the neighbour list, the contact forces and the integration per particle-step, from
the DEM's own phase timers. The shapes alternate (rods, spheres, spheres, rods, ...) in one process, each
round from a fresh copy of the state, so both see the same machine; the figures are medians over
``--rounds``. ``--coupled`` adds the coupled step (gas, bridge and DEM) over ``--cfd-steps`` CFD steps
from the same checkpoint, per simulated second, and its timed phases (the DEM's, the gas's and the
bridge's voidage mapping, closures and deposition) in ms per CFD step.

Compare builds ABA (``PYTHONPATH`` pointing at each build's checkout, this file from either): only ratios
measured in one run mean anything (docs/benchmarks.md). ``--quick``: the 1,500-particle beds fluidized
for 0.02 s, a few steps, one round (seconds; the test suite runs it). The last line of output is JSON:

    {"shapes": {"ar1": {"ns_per_particle_step": {"neighbour_list": .., "contact_forces": .., "integration": ..,
                         "dem": ..}, "rounds": [...], "listed_pairs_per_particle": .., ...,
                 "coupled_wall_seconds_per_simulated_second": .., "coupled_ms_per_cfd_step": {"closures": .., ...}},
              "ar4": {...}},
     "rods_over_spheres": {"neighbour_list": .., "contact_forces": .., "integration": .., "dem": ..},
     "machine": {...}}
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import resource
import sys
import time
from pathlib import Path

import numpy as np

from _beds import fluidized_states

PHASES = ("neighbour_list", "contact_forces", "integration")
SHAPES = ("ar4", "ar1")  # rods first: the order alternates round by round


def load_state(checkpoint: Path):
    """``(case, arrays)`` of a coupled run's checkpoint (its case.toml beside it)."""
    import fvdem
    case_file = checkpoint.parent / "case.toml"
    if not case_file.exists():
        raise SystemExit(f"bench_fluidized: {case_file} is missing: a state must be a coupled run's checkpoint.npz "
                         "with the run's case.toml beside it")
    case = fvdem.load_case(case_file, {"particles.initial_state": None} if _has_initial_state(case_file) else None)
    with np.load(checkpoint) as data:
        arrays = {k: data[k] for k in data.files if k != "__meta__"}
    return case, arrays


def _has_initial_state(case_file: Path) -> bool:
    import tomllib
    return "initial_state" in tomllib.loads(case_file.read_text()).get("particles", {})


def fresh_dem(case, arrays):
    """A DEM system holding the checkpoint's particles, lists and histories, the gas's drag on (implicit,
    as the coupling bridge sets it)."""
    from fvdem.dem.particles import ParticleArrays
    from fvdem.model import build_dem
    particles = ParticleArrays.from_dict({k.split(".", 1)[1]: v.copy() for k, v in arrays.items()
                                          if k.startswith("particles.")})
    dem = build_dem(case, particles)
    dem.restore({k: v.copy() for k, v in arrays.items()})
    dem.implicit_drag = True
    return dem


def measure_dem(case, arrays, steps: int) -> dict:
    """ns per particle-step of each DEM phase over ``steps`` steps from the state."""
    dem = fresh_dem(case, arrays)
    before = {k: dem.timings.seconds.get(k, 0.0) for k in PHASES}
    rebuilds = dem.rebuild_count
    wall = time.perf_counter()
    dem.step(steps)
    wall = time.perf_counter() - wall
    scale = 1e9 / (steps * dem.particles.count)
    result = {k: (dem.timings.seconds[k] - before[k]) * scale for k in PHASES}
    result["dem"] = wall * scale
    result["steps_per_rebuild"] = steps / max(1, dem.rebuild_count - rebuilds)
    result["listed_pairs_per_particle"] = len(dem.neighbours) / dem.particles.count
    result["contacts_per_particle"] = dem.diagnostics()["contacts_per_particle"]
    return result


def measure_coupled(case, arrays, cfd_steps: int) -> tuple:
    """Wall seconds per simulated second of the coupled step from the checkpoint, and the run's timed phases
    (``fvdem.timing.PHASES``: the DEM's, the gas's, the bridge's voidage mapping, closures and deposition)
    in ms per CFD step."""
    from fvdem.model import Model
    model = Model(case, {k: v.copy() for k, v in arrays.items()})
    before = dict(model.timings.seconds)
    wall = time.perf_counter()
    model.advance(cfd_steps)
    wall = time.perf_counter() - wall
    phases = {k: 1e3 * (v - before.get(k, 0.0)) / cfd_steps for k, v in model.timings.seconds.items()}
    return wall / (cfd_steps * model.time_step), phases


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--state-ar1", type=Path, help="a fluidized AR-1 run's checkpoint.npz (default: made once)")
    parser.add_argument("--state-ar4", type=Path, help="a fluidized AR-4 run's checkpoint.npz (default: made once)")
    parser.add_argument("--fluidize", type=float, default=1.0, help="simulated seconds of the default states")
    parser.add_argument("--steps", type=int, default=200, help="measured DEM steps per shape and round")
    parser.add_argument("--rounds", type=int, default=3, help="alternated rounds (medians reported)")
    parser.add_argument("--coupled", action="store_true", help="also the coupled step from each checkpoint")
    parser.add_argument("--cfd-steps", type=int, default=10, help="CFD steps of each coupled measurement")
    parser.add_argument("--threads", type=int, default=1, help="numba threads (default 1)")
    parser.add_argument("--quick", action="store_true", help="1,500-particle beds, 5 steps, one round (seconds)")
    parser.add_argument("--json", action="store_true", help="print only the JSON line")
    args = parser.parse_args(argv)
    import numba
    if not 1 <= args.threads <= numba.config.NUMBA_NUM_THREADS:
        parser.error(f"--threads must be within 1..{numba.config.NUMBA_NUM_THREADS} (got {args.threads})")
    if args.steps < 1 or args.rounds < 1 or args.cfd_steps < 1 or args.fluidize <= 0.0:
        parser.error("--steps, --rounds and --cfd-steps must be at least 1 and --fluidize positive")
    if args.quick:
        args.fluidize, args.steps, args.rounds, args.cfd_steps = 0.02, 5, 1, 1
    numba.set_num_threads(args.threads)
    given = {"ar1": args.state_ar1, "ar4": args.state_ar4}
    missing = [name for name in SHAPES if given[name] is None]
    made = fluidized_states(missing, "bench_fluidized", args.fluidize, args.quick, args.threads) if missing else {}
    states = {name: given[name] or made[name] for name in SHAPES}
    loaded = {name: load_state(Path(states[name])) for name in SHAPES}
    for name in SHAPES:  # compile and warm up
        measure_dem(*loaded[name], 2)
    rounds = {name: [] for name in SHAPES}
    coupled = {name: [] for name in SHAPES}
    for r in range(args.rounds):
        for name in (SHAPES if r % 2 == 0 else SHAPES[::-1]):
            rounds[name].append(measure_dem(*loaded[name], args.steps))
            if args.coupled:
                coupled[name].append(measure_coupled(*loaded[name], args.cfd_steps))
        if not args.json:
            print(f"round {r + 1}: " + "; ".join(f"{n} DEM {rounds[n][-1]['dem']:.0f} ns" for n in SHAPES),
                  file=sys.stderr, flush=True)
    shapes = {}
    for name in SHAPES:
        case, arrays = loaded[name]
        median = {k: float(np.median([x[k] for x in rounds[name]])) for k in rounds[name][0]}
        shapes[name] = {
            "state": str(states[name]), "particles": int(arrays["particles.mass"].shape[0]),
            "simulated_time": float(arrays["dem.counters"][0]) * case.time.dem_step,
            "ns_per_particle_step": {k: median[k] for k in (*PHASES, "dem")},
            "steps_per_rebuild": median["steps_per_rebuild"],
            "listed_pairs_per_particle": median["listed_pairs_per_particle"],
            "contacts_per_particle": median["contacts_per_particle"],
            "rounds": rounds[name]}
        if args.coupled:
            shapes[name]["coupled_wall_seconds_per_simulated_second"] = float(np.median([c[0] for c in coupled[name]]))
            shapes[name]["coupled_ms_per_cfd_step"] = {k: float(np.median([c[1][k] for c in coupled[name]]))
                                                       for k in coupled[name][0][1]}
            shapes[name]["coupled_rounds"] = [c[0] for c in coupled[name]]
    ratios = {k: shapes["ar4"]["ns_per_particle_step"][k] / shapes["ar1"]["ns_per_particle_step"][k]
              for k in (*PHASES, "dem")}
    import fvdem
    out = {"shapes": shapes, "rods_over_spheres": ratios, "steps": args.steps, "rounds": args.rounds,
           "threads": args.threads,
           "machine": {"date": datetime.datetime.now().isoformat(timespec="seconds"),
                       "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                       "load_average": os.getloadavg(), "numba": numba.__version__,
                       "fvdem": getattr(fvdem, "__version__", "?"), "fvdem_path": str(Path(fvdem.__file__).parent),
                       "peak_memory_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0}}
    if not args.json:
        print("rods / spheres per particle-step: " + ", ".join(f"{k} {v:.2f}" for k, v in ratios.items()),
              file=sys.stderr)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
