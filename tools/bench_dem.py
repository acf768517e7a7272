#!/usr/bin/env python
"""Benchmark the DEM on the settled 32,500-particle beds of Mema et al. (2020) (no gas).

Usage:
    python tools/bench_dem.py [--json] [--steps 300] [--shapes sphere spherocylinder]

The settled beds come from ``fvdem run cases/bed_ar1.toml`` and ``cases/bed_ar4.toml``
(``runs/bed_ar1/final_state.npz``, ``runs/bed_ar4/final_state.npz``; ``--state-dir`` to change);
the tool settles them first if the states are missing (minutes to tens of minutes, ``tools/_beds.py``).
``--quick``: 1,500-particle beds and 5 steps, that the tool works (seconds).
Each shape is measured in its own subprocess (so peak memory is per bed), at 1 and 2 threads in
the same process, wall and CPU time side by side. The last line of output is one JSON object:

    {"sphere": {"threads_1": {"ns_per_particle_step": ..., "cpu_ns_per_particle_step": ...},
                "threads_2": {...}, "contacts_per_particle": ..., "peak_memory_mb": ...},
     "spherocylinder": {...}, "machine": {...}}
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

from _beds import CASES, settled_beds

ROOT = Path(__file__).resolve().parents[1]
BEDS = {"sphere": ("ar1", CASES["ar1"]), "spherocylinder": ("ar4", CASES["ar4"])}


def worker(shape: str, state: Path, steps: int) -> dict:
    import numba

    from _beds import settled_dem
    case, dem = settled_dem(BEDS[shape][0], state)
    particles = dem.particles
    numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
    dem.step(50)  # compile and warm up
    result = {}
    for threads in (1, 2):
        if threads > numba.config.NUMBA_NUM_THREADS:
            continue
        numba.set_num_threads(threads)
        dem.step(10)
        rebuilds = dem.rebuild_count
        wall, cpu = time.perf_counter(), time.process_time()
        dem.step(steps)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        result[f"threads_{threads}"] = {
            "ns_per_particle_step": 1e9 * wall / (steps * particles.count),
            "cpu_ns_per_particle_step": 1e9 * cpu / (steps * particles.count),
            "neighbour_rebuilds": dem.rebuild_count - rebuilds,
        }
    diag = dem.diagnostics()
    result.update({
        "particles": particles.count,
        "steps": steps,
        "contacts_per_particle": diag["contacts_per_particle"],
        "wall_contacts_per_particle": diag["wall_contacts"] / particles.count,
        "peak_memory_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0,
        "state": str(state.relative_to(ROOT) if state.is_relative_to(ROOT) else state),
    })
    return result


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print only the JSON line on stdout")
    parser.add_argument("--steps", type=int, default=300, help="measured DEM steps per thread count")
    parser.add_argument("--shapes", nargs="+", default=list(BEDS), choices=list(BEDS), help="the beds to measure")
    parser.add_argument("--state-dir", type=Path, help="where the settled beds are (default runs/)")
    parser.add_argument("--quick", action="store_true", help="1,500-particle beds and 5 steps (seconds)")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--state", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.worker, args.state, args.steps)))
        return 0
    if args.state_dir:
        os.environ["FVDEM_BEDS_DIR"] = str(args.state_dir)
    if args.quick:
        args.steps = 5
    states = settled_beds([BEDS[shape][0] for shape in args.shapes], "bench_dem", args.quick)
    results = {}
    for shape in args.shapes:
        state = states[BEDS[shape][0]]
        proc = subprocess.run([sys.executable, __file__, "--worker", shape, "--state", str(state),
                               "--steps", str(args.steps)], capture_output=True, text=True, check=True)
        results[shape] = json.loads(proc.stdout.strip().splitlines()[-1])
        if not args.json:
            print(f"{shape}: {json.dumps(results[shape])}", file=sys.stderr)
    import numba
    results["machine"] = {
        "date": datetime.datetime.now().isoformat(timespec="seconds"),
        "cpu": platform.processor() or platform.machine(),
        "cores": os.cpu_count(),
        "load_average": os.getloadavg(),
        "numba": numba.__version__,
        "threading_layer": numba.config.THREADING_LAYER,
    }
    print(json.dumps(results))
    return 0


if __name__ == "__main__":
    sys.exit(main())
