"""Cost of the coupled step of full-size paper cases, where it goes, and what the coupling adds to the DEM
(issue 16). All figures of one variant are measured in the same process, one after the other.

    python tools/bench_coupled.py --json
    python tools/bench_coupled.py --variants ar1-default --duration 0.02 --json

Per variant (a case file and contact/step settings):

- ``wall_seconds_per_simulated_second`` of the coupled run at ``--threads`` (default: all);
- ``timings``: its seconds per phase over the measured window (``fvdem.timing``), per simulated second;
- ``dem_only_wall_seconds_per_simulated_second``: the same particles and DEM step with the gas off;
- ``coupling_overhead`` = coupled wall / DEM-only wall;
- ``threads_speedup`` = coupled wall at 1 thread / at ``--threads`` (null when only 1 is available).

The three runs of a variant (coupled, DEM alone, coupled on 1 thread) are repeated ``--repeat`` times
(default 3), alternated, each from the case's start: the figures above are the medians of the rounds,
and ``rounds`` keeps each round's wall times and ratios. A single round of the default 0.02 s window
(40 CFD steps at the defaults) once read an overhead of 2.08 and a 2-thread speedup of 1.04 where the
next two read 1.41-1.45 and 1.45-1.46 (docs/benchmarks.md): one round is not a measurement.

Each run starts from the settled bed of its shape (``runs/bed_ar1``, ``runs/bed_ar4``: settled first when
missing, ``tools/_beds.py``), takes a short warm-up (kernels loaded, first neighbour list built) and
measures ``--duration`` simulated seconds of the bed's start. ``--quick``: 1,500-particle beds, 2 CFD
steps, one round (seconds; what the test suite runs). Prints one JSON object as the last line.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import time

import numba
import numpy as np

import fvdem
from _beds import ROOT, bed_overrides, settled_beds

SETTINGS = {
    "paper": {"contact.normal_stiffness": 2.0e4, "time.dem_step": 1e-5, "gas.cfd_step": 1e-4},
    "default": {"contact.normal_stiffness": 800.0, "time.dem_step": 5e-5, "gas.cfd_step": 5e-4},
}
VARIANTS = {
    "ar1-default": ("cases/ar1.toml", SETTINGS["default"]),  # relative to the repository (ROOT)
    "ar4_mp-default": ("cases/ar4_mp.toml", SETTINGS["default"]),
    "ar1-paper": ("cases/ar1.toml", SETTINGS["paper"]),
    "ar1-fixed-bed": ("cases/ar1.toml", dict(SETTINGS["paper"], **{"particles.fixed": True})),
}


def measure(case_path, overrides, duration, threads):
    """Wall and CPU seconds per simulated second over ``duration`` after a warm-up, and the phases."""
    case = fvdem.load_case(ROOT / case_path, dict(overrides, **{"output.progress": False}))
    sim = fvdem.Simulation(case, threads=threads, progress=False)
    sim.run(2 * sim.time_step if case.gas.enabled else 20 * case.time.dem_step)  # warm-up
    before = dict(sim.model.timings.seconds)
    wall0, cpu0, t0 = time.perf_counter(), time.process_time(), sim.time
    sim.run(duration)
    wall, simulated = time.perf_counter() - wall0, sim.time - t0
    phases = {k: (v - before[k]) / simulated for k, v in sim.model.timings.seconds.items()}
    phases["other"] = max(0.0, wall / simulated - sum(phases.values()))
    return {"wall_seconds_per_simulated_second": wall / simulated,
            "cpu_seconds_per_simulated_second": (time.process_time() - cpu0) / simulated,
            "simulated_seconds": simulated, "threads": sim.threads, "particles": case.particles.count,
            "timings": phases}


def bed_of(name: str) -> str:
    """The settled bed a variant starts from (its case's shape)."""
    return "ar4" if "ar4" in VARIANTS[name][0] else "ar1"


def variant(name, duration, threads, repeat=3, quick=False):
    """The variant's figures: medians over ``repeat`` alternated rounds of the coupled run, the DEM alone
    and the coupled run on 1 thread, with each round's figures in ``rounds``."""
    case_path, overrides = VARIANTS[name]
    overrides = dict(overrides, **bed_overrides(bed_of(name), quick))
    rounds = []
    for _ in range(repeat):
        coupled = measure(case_path, overrides, duration, threads)
        dem = measure(case_path, dict(overrides, **{"gas.enabled": False}), duration, threads)
        single = None
        if coupled["threads"] > 1:
            single = measure(case_path, overrides, duration, 1)["wall_seconds_per_simulated_second"]
        wall = coupled["wall_seconds_per_simulated_second"]
        dem_wall = dem["wall_seconds_per_simulated_second"]
        rounds.append({"coupled": coupled, "dem": dem, "wall": wall, "dem_wall": dem_wall, "single": single,
                       "coupling_overhead": wall / dem_wall,
                       "threads_speedup": None if single is None else single / wall})

    def median(values):
        return float(np.median(values))

    def median_phases(key):
        return {phase: median([r[key]["timings"][phase] for r in rounds]) for phase in rounds[0][key]["timings"]}

    timings = median_phases("coupled")
    single = None if rounds[0]["single"] is None else median([r["single"] for r in rounds])
    return {"case": case_path, "settings": overrides,
            "wall_seconds_per_simulated_second": median([r["wall"] for r in rounds]),
            "cpu_seconds_per_simulated_second": median([r["coupled"]["cpu_seconds_per_simulated_second"]
                                                        for r in rounds]),
            "dem_only_wall_seconds_per_simulated_second": median([r["dem_wall"] for r in rounds]),
            "coupling_overhead": median([r["coupling_overhead"] for r in rounds]),
            "threads": rounds[0]["coupled"]["threads"],
            "threads_speedup": None if single is None else median([r["threads_speedup"] for r in rounds]),
            "one_thread_wall_seconds_per_simulated_second": single,
            "gas_over_dem": (sum(timings[p] for p in ("gas_momentum", "gas_pressure", "gas_other"))
                             / max(1e-30, sum(timings[p] for p in ("neighbour_list", "contact_forces", "integration")))),
            "particles": rounds[0]["coupled"]["particles"], "simulated_seconds": rounds[0]["coupled"]["simulated_seconds"],
            "timings": timings, "dem_only_timings": median_phases("dem"),
            "rounds": [{"wall_seconds_per_simulated_second": r["wall"],
                        "dem_only_wall_seconds_per_simulated_second": r["dem_wall"],
                        "one_thread_wall_seconds_per_simulated_second": r["single"],
                        "coupling_overhead": r["coupling_overhead"], "threads_speedup": r["threads_speedup"]}
                       for r in rounds]}


def _spread(result, key):
    """A figure's range over the rounds, as text."""
    values = [r[key] for r in result["rounds"]]
    return f"{min(values):.2f}-{max(values):.2f}"


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--variants", nargs="+", default=["ar1-default", "ar4_mp-default", "ar1-paper"],
                        choices=list(VARIANTS), help="case and settings variants to measure")
    parser.add_argument("--duration", type=float, default=0.02, help="simulated seconds per measurement")
    parser.add_argument("--threads", type=int, default=0, help="numba threads (0: all)")
    parser.add_argument("--repeat", type=int, default=3, help="alternated rounds per variant (medians reported)")
    parser.add_argument("--quick", action="store_true",
                        help="1,500-particle beds, 2 CFD steps, one round: that the tool works, in seconds")
    parser.add_argument("--json", action="store_true", help="the result as one JSON line")
    args = parser.parse_args(argv)
    if args.repeat < 1 or args.duration <= 0.0:
        parser.error(f"--repeat must be at least 1 (got {args.repeat}) and --duration positive (got {args.duration})")
    if args.quick:
        args.duration, args.repeat = 1e-3, 1
        args.variants = [v for v in args.variants if v != "ar1-paper"] or args.variants
    settled_beds([bed_of(v) for v in args.variants], "bench_coupled", args.quick)  # before any measuring
    results = {}
    for name in args.variants:
        r = results[name] = variant(name, args.duration, args.threads, args.repeat, args.quick)
        print(f"{name:15s} {r['wall_seconds_per_simulated_second']:8.1f} s wall per simulated s; DEM alone "
              f"{r['dem_only_wall_seconds_per_simulated_second']:.1f}; coupling overhead {r['coupling_overhead']:.2f} "
              f"({_spread(r, 'coupling_overhead')}); "
              f"gas / DEM {r['gas_over_dem']:.2f}; {r['threads']} threads "
              + (f"{r['threads_speedup']:.2f} x one ({_spread(r, 'threads_speedup')})" if r["threads_speedup"] else "")
              + f"; medians of {len(r['rounds'])} rounds", flush=True)
    out = {"variants": results, "date": time.strftime("%Y-%m-%d %H:%M"), "load_average": os.getloadavg(),
           "cpu": platform.processor() or platform.machine(), "threads_available": numba.config.NUMBA_NUM_THREADS}
    print(json.dumps(out) if args.json else json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
