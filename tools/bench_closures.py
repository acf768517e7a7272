#!/usr/bin/env python
"""Benchmark the hydrodynamic closures as the bridge calls them: ns per particle of each registered law
(``Law.evaluate``) and of the paper's sets of laws (``closures.evaluate_set``: AR-1 Hoelzer-Sommerfeld,
AR-4 SP Hoelzer-Sommerfeld + Zastawny, AR-4 MP Sanjeevi-Padding), on 32,500 particles of the paper's beds
with random slips (0.5 m/s spread), voidages 0.45-1 and orientations.

Usage:
    python tools/bench_closures.py [--json] [--particles 32500] [--calls 40] [--rounds 3]

It uses only the public API of ``fvdem.coupling.closures``, so the same tool times another checkout
(``PYTHONPATH=<checkout> python tools/bench_closures.py``) for ABA comparisons. Rounds alternate the laws;
medians over calls, then over rounds. ``--quick``: 2,000 particles, 3 calls, one round (seconds). The last
line of output is one JSON object: ``{"laws": {"drag/hoelzer-sommerfeld/sphere": ns, ...}, "sets": {"ar1":
ns, "ar4_sp": ns, "ar4_mp": ns}, "machine": {...}}``.
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import sys
import time
import warnings

import numpy as np

AIR = (1.2, 1.8e-5)
SHAPES = {"sphere": (5.3e-3, 5.3e-3), "rod": (3.2e-3, 12.8e-3)}  # the paper's AR-1 and AR-4 particles
SETS = {"ar1": ("sphere", ("hoelzer-sommerfeld", "none", "none")),
        "ar4_sp": ("rod", ("hoelzer-sommerfeld", "zastawny", "zastawny")),
        "ar4_mp": ("rod", ("sanjeevi-padding", "sanjeevi-padding", "sanjeevi-padding"))}


def _median_ns(call, calls: int, n: int) -> float:
    call()  # compiled, caches warm
    times = []
    for _ in range(calls):
        start = time.perf_counter()
        call()
        times.append(time.perf_counter() - start)
    return float(np.median(times)) / n * 1e9


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--particles", type=int, default=32500)
    parser.add_argument("--calls", type=int, default=40, help="timed calls per law and round (median)")
    parser.add_argument("--rounds", type=int, default=3, help="alternated rounds (median)")
    parser.add_argument("--quick", action="store_true", help="2,000 particles, 3 calls, one round")
    parser.add_argument("--json", action="store_true", help="only the JSON line")
    args = parser.parse_args(argv)
    if args.quick:
        args.particles, args.calls, args.rounds = 2000, 3, 1
    import numba

    import fvdem
    from fvdem.coupling import closures
    rng = np.random.default_rng(1)
    n = args.particles
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    slip, voidage = rng.normal(0.0, 0.5, (n, 3)), rng.uniform(0.45, 1.0, n)
    particles = {name: closures.ParticleShape(d, length, *AIR) for name, (d, length) in SHAPES.items()}
    calls = {}
    for kind, laws in closures.LAWS.items():
        for name, law in laws.items():
            for shape in ("sphere", "rod"):
                if name != "none" and ("sphere" if shape == "sphere" else "spherocylinder") in law.shapes:
                    calls[f"laws/{kind}/{name}/{shape}"] = (lambda law=law, p=particles[shape]:
                                                            law.evaluate(p, slip, voidage, axis))
    for label, (shape, names) in SETS.items():
        calls[f"sets/{label}"] = lambda p=particles[shape], names=names: closures.evaluate_set(p, *names, slip,
                                                                                              voidage, axis)
    rounds: dict[str, list] = {key: [] for key in calls}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # the dense laws' range warnings
        for _ in range(args.rounds):
            for key, call in calls.items():
                rounds[key].append(_median_ns(call, args.calls, n))
    out = {"laws": {}, "sets": {}}
    for key, values in rounds.items():
        group, name = key.split("/", 1)
        out[group][name] = round(float(np.median(values)), 1)
    out.update(particles=n, calls=args.calls, rounds=args.rounds,
               machine={"date": datetime.datetime.now().isoformat(timespec="seconds"),
                        "cpu": platform.processor() or platform.machine(), "cores": os.cpu_count(),
                        "load_average": os.getloadavg(), "numba": numba.__version__,
                        "threads": numba.get_num_threads(), "fvdem": getattr(fvdem, "__version__", "?"),
                        "fvdem_path": os.path.dirname(fvdem.__file__)})
    if not args.json:
        for group in ("sets", "laws"):
            for name, value in out[group].items():
                print(f"{group[:-1]} {name}: {value} ns per particle", file=sys.stderr)
    print(json.dumps(out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
