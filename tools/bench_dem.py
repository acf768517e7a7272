#!/usr/bin/env python
"""Benchmark the DEM on the settled 32,500-particle beds of seed 000 (no gas).

Usage:
    python tools/bench_dem.py [--json] [--steps 300] [--shapes sphere spherocylinder]

The settled beds come from ``fvdem run cases/bed_ar1.toml`` and ``cases/bed_ar4.toml``
(``runs/bed_ar1/final_state.npz``, ``runs/bed_ar4/final_state.npz``; ``--state-dir`` to change);
the tool runs those cases first if the states are missing (minutes to tens of minutes).
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

ROOT = Path(__file__).resolve().parents[1]
BEDS = {"sphere": ("bed_ar1", ROOT / "cases" / "bed_ar1.toml"),
        "spherocylinder": ("bed_ar4", ROOT / "cases" / "bed_ar4.toml")}


def worker(shape: str, state: Path, steps: int) -> dict:
    import numba
    import numpy as np

    import fvdem
    from fvdem.dem.particles import ParticleArrays
    from fvdem.model import build_dem

    case = fvdem.load_case(BEDS[shape][1])
    with np.load(state) as data:
        particles = ParticleArrays.from_dict({k: data[k] for k in data.files})
    dem = build_dem(case, particles)
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


def ensure_state(shape: str, state_dir: Path) -> Path:
    name, case = BEDS[shape]
    state = state_dir / name / "final_state.npz"
    if not state.exists():
        print(f"settling {name} first (fvdem run {case.relative_to(ROOT)}); this takes a while", file=sys.stderr)
        subprocess.run([sys.executable, "-m", "fvdem.cli", "run", str(case), "--out", str(state.parent),
                        "--overwrite"], check=True)
    return state


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="print only the JSON line on stdout")
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--shapes", nargs="+", default=list(BEDS), choices=list(BEDS))
    parser.add_argument("--state-dir", type=Path, default=ROOT / "runs")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--state", type=Path, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        print(json.dumps(worker(args.worker, args.state, args.steps)))
        return 0
    results = {}
    for shape in args.shapes:
        state = ensure_state(shape, args.state_dir)
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
