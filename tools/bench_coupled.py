"""Wall and CPU time per simulated second of a full-size coupled case at the paper's settings, at
fvdem's defaults, and as a fixed bed (issue 7: the defaults against the paper; what a fixed bed skips).

    python tools/bench_coupled.py --case cases/ar1.toml --duration 0.03 --json

Each variant starts from the case's initial state (the paper cases read the settled beds: run
``fvdem run cases/bed_ar1.toml --out runs/bed_ar1`` first), runs ``--duration`` simulated seconds
after a short warm-up (kernels loaded, first neighbour list built) and reports the rate. Prints one JSON
object as the last line.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import fvdem

VARIANTS = {
    "paper": {"contact.normal_stiffness": 2.0e4, "time.dem_step": 1e-5, "gas.cfd_step": 1e-4},
    "default": {"contact.normal_stiffness": 800.0, "time.dem_step": 5e-5, "gas.cfd_step": 5e-4},
    "fixed-bed": {"contact.normal_stiffness": 2.0e4, "time.dem_step": 1e-5, "gas.cfd_step": 1e-4,
                  "particles.fixed": True},
}


def measure(case_path, overrides, duration, threads):
    case = fvdem.load_case(case_path, dict(overrides, **{"output.progress": False}))
    sim = fvdem.Simulation(case, threads=threads, progress=False)
    sim.run(2 * case.gas.cfd_step)  # warm-up
    wall0, cpu0, t0 = time.perf_counter(), time.process_time(), sim.time
    sim.run(duration)
    simulated = sim.time - t0
    return {"wall_seconds_per_simulated_second": (time.perf_counter() - wall0) / simulated,
            "cpu_seconds_per_simulated_second": (time.process_time() - cpu0) / simulated,
            "simulated_seconds": simulated, "threads": sim.threads, "particles": case.particles.count}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default="cases/ar1.toml")
    parser.add_argument("--duration", type=float, default=0.03, help="simulated seconds per variant")
    parser.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=list(VARIANTS))
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    results = {}
    for name in args.variants:
        results[name] = measure(args.case, VARIANTS[name], args.duration, args.threads)
        print(f"{name:10s} {results[name]['wall_seconds_per_simulated_second']:8.1f} s wall per simulated s "
              f"(CPU {results[name]['cpu_seconds_per_simulated_second']:.1f})", flush=True)
    if "paper" in results:
        for name, r in results.items():
            r["speed_up_over_paper"] = (results["paper"]["wall_seconds_per_simulated_second"]
                                        / r["wall_seconds_per_simulated_second"])
    out = {"case": args.case, "variants": results, "load_average": os.getloadavg(),
           "date": time.strftime("%Y-%m-%d %H:%M")}
    print(json.dumps(out) if args.json else json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
