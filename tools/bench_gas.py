#!/usr/bin/env python
"""Benchmark full CFD steps of the gas solver on the 10 x 10 x 70 bed grid.

Usage: python tools/bench_gas.py [--json] [--steps 30] [--reference-steps 3]

A bed region (z < 0.3 m) with non-uniform voidage and interphase coefficient that change every step
like a bubbling bed (a few Hz, so d(eps)/dt stays physical), gas inlet at 2 U_mf of the AR-1
particles, CFD step 1e-4 s, PISO with two pressure correctors. Reports the fast path (cached
operators, warm-started Krylov solvers) and the reference path (the same steps with every system
rebuilt from plain FiPy terms and solved directly), and their largest relative difference after
the reference steps. ``preconditioners`` compares the pressure correction's two preconditioners
(``gas.pressure_preconditioner``) on the same steps, run in alternating chunks of 10 steps so that
the machine's drift falls on both: per preconditioner the median ms per CFD step, the pressure
phase's ms per step and the CG iterations per step. The last line of output is one JSON object:

    {"ms_per_cfd_step": ..., "assembly_ms": ..., "solve_ms": ..., "reference_ms_per_cfd_step": ...,
     "max_relative_difference_to_reference": ..., "direct_fallbacks": ...,
     "preconditioners": {"multigrid": {...}, "factorization": {...}, "factorization_over_multigrid": ...},
     "machine": {...}}
"""
from __future__ import annotations

import argparse
import datetime
import json
import os
import sys
import time
import warnings

import numpy as np

warnings.filterwarnings("ignore", category=DeprecationWarning)

from fvdem.gas.mesh import GasMesh  # noqa: E402
from fvdem.gas.solver import GasProperties, GasSolver  # noqa: E402

DT = 1e-4
AIR = GasProperties()  # the solver's gas (a case's default)


def bed_fields(mesh, t):
    """Voidage and beta of a bubbling bed region below 0.3 m at time t (smooth in space and time)."""
    x, y, z = mesh.cell_centers.T
    wave = np.sin(2 * np.pi * (5.0 * t + 3.0 * z + 2.0 * x)) * np.cos(2 * np.pi * (4.0 * t + 2.5 * y))
    voidage = np.where(z < 0.3, 0.5 + 0.08 * wave, 1.0)
    solids = 1.0 - voidage
    beta = np.where(z < 0.3, 150 * solids ** 2 * AIR.viscosity / (voidage * 5.3e-3 ** 2)
                    + 1.75 * solids * AIR.density * 3.0 / 5.3e-3, 0.0)
    return voidage, beta


def run(solver, mesh, steps, start=0):
    timings = []
    for k in range(start, start + steps):
        voidage, beta = bed_fields(mesh, k * DT)
        solver.voidage_old[:] = solver.voidage
        solver.voidage[:] = voidage
        solver.beta[:] = beta
        t0 = time.perf_counter()
        solver.step(DT)
        timings.append(time.perf_counter() - t0)
    return timings


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", action="store_true", help="the result as one JSON line")
    parser.add_argument("--steps", type=int, default=100, help="timed CFD steps")
    parser.add_argument("--reference-steps", type=int, default=3, help="steps of FiPy's own reference solve")
    parser.add_argument("--quick", action="store_true", help="3 steps and 1 reference step (seconds)")
    args = parser.parse_args()
    if args.quick:
        args.steps, args.reference_steps = 3, 1
    mesh = GasMesh.box((10, 10, 70), (0.0, 0.0, 0.0), (0.15, 0.15, 1.05))
    settings = dict(inlet_velocity=2 * 1.58, scheme="piso", correctors=2)

    def fresh(**extra):
        solver = GasSolver(mesh, **settings, **extra)
        voidage, beta = bed_fields(mesh, 0.0)
        solver.voidage[:] = solver.voidage_old[:] = voidage
        solver.beta[:] = beta
        return solver

    fast = fresh(linear_solver="iterative", linear_tolerance=1e-8)
    run(fast, mesh, 3)  # warm-up (allocations, caches)
    # time the assembly alone (the operators' cached patterns) on the warm state
    eps_face = fast._face_average(fast.voidage)
    t0 = time.perf_counter()
    for _ in range(10):
        for c in range(3):
            fast._momentum_system(c, fast.voidage / DT + fast.beta, fast.face_flux, AIR.viscosity * eps_face,
                                  np.zeros(mesh.face_count))
        fast._pressure_system(eps_face)
    assembly_ms = 1e3 * (time.perf_counter() - t0) / 10
    cpu0 = time.process_time()
    timings = run(fast, mesh, args.steps, start=3)
    cpu = time.process_time() - cpu0
    step_ms = 1e3 * float(np.median(timings))

    # reference and fast path from the same start over the same steps
    reference = fresh(assembly="fipy", linear_solver="direct")
    check = fresh(linear_solver="iterative", linear_tolerance=1e-8)
    t0 = time.perf_counter()
    run(reference, mesh, args.reference_steps)
    reference_ms = 1e3 * (time.perf_counter() - t0) / args.reference_steps
    run(check, mesh, args.reference_steps)
    scale = np.abs(reference.velocity).max()
    difference = float(max(np.abs(check.velocity - reference.velocity).max() / scale,
                           np.abs(check.pressure - reference.pressure).max() / np.abs(reference.pressure).max()))
    # the two pressure preconditioners on the same steps, alternating chunks
    pair = {name: fresh(linear_solver="iterative", linear_tolerance=1e-8, pressure_preconditioner=name)
            for name in ("multigrid", "factorization")}
    steps = {name: [] for name in pair}
    iterations = {name: 0 for name in pair}
    for solver in pair.values():
        run(solver, mesh, 3)
        solver.timings.seconds["gas_pressure"] = 0.0
    for start in range(3, 3 + args.steps, 10):
        for name, solver in pair.items():
            for k in range(start, min(start + 10, 3 + args.steps)):
                steps[name] += run(solver, mesh, 1, start=k)
                iterations[name] += solver._step_iterations
    preconditioners = {name: {"ms_per_cfd_step": 1e3 * float(np.median(steps[name])),
                              "pressure_ms_per_cfd_step": 1e3 * pair[name].timings.seconds["gas_pressure"] / args.steps,
                              "cg_iterations_per_cfd_step": iterations[name] / args.steps,
                              "direct_fallbacks": pair[name].direct_fallbacks} for name in pair}
    preconditioners["factorization_over_multigrid"] = (preconditioners["factorization"]["ms_per_cfd_step"]
                                                       / preconditioners["multigrid"]["ms_per_cfd_step"])
    result = {
        "ms_per_cfd_step": step_ms,
        "cpu_ms_per_cfd_step": 1e3 * cpu / args.steps,
        "assembly_ms": assembly_ms,
        "solve_ms": step_ms - assembly_ms,
        "reference_ms_per_cfd_step": reference_ms,
        "max_relative_difference_to_reference": difference,
        "direct_fallbacks": fast.direct_fallbacks,
        "pressure_factorizations": fast.factorizations,
        "preconditioners": preconditioners,
        "cells": mesh.cell_count,
        "machine": {"date": datetime.datetime.now().isoformat(timespec="seconds"), "cores": os.cpu_count(),
                    "load_average": os.getloadavg()},
    }
    if not args.json:
        for key, value in result.items():
            print(f"{key}: {value}", file=sys.stderr)
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
