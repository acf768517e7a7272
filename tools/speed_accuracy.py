"""Speed against accuracy on a reduced fluidized bed (issue 7, part 1).

A reduced but representative bed of Mema et al.'s particles (2,000 AR-1 spheres or 2,000 AR-4
spherocylinders in a 0.06 x 0.06 x 0.45 m column, Mema et al.'s 15 mm cells, two colour layers,
2 Umf from a loosely inserted start) is run at the paper's settings (the reference: DEM step 1e-5 s,
k_n 2e4 N/m, CFD step 1e-4 s, 15 mm cells, divided voidage, 2 threads; AR-4 with the multi-particle
drag, lift and torque) and in variants that trade accuracy for speed, one setting at a time and in
combinations:

- DEM stiffness and step: ``k_n / f^2`` with ``dt x f`` (the collision time grows by ``f``, so the
  contact stays resolved by the same number of steps), f = 2, 5, 10 (factors that divide the CFD step);
- CFD step (coupling interval) x 2, 5, 10;
- grid: 30 mm and 7.5 mm cells against the paper's 15 mm;
- voidage: centroid and trilinear against divided;
- closures (AR-4): single-particle against multi-particle, drag only against drag + lift + torque;
- threads: 1 against 2;
- a replica: the reference from a different random insertion, i.e. the same physics and numerics in
  another realisation of a chaotic bed. Its errors are the noise floor: differences below them are
  not resolved by a run this short.

For each run: wall (and CPU) seconds per simulated second, and its errors against the reference in the
observables of issue 5 taken over a measuring window after a spin-up: time-averaged bed pressure drop
(relative), time-averaged mean particle height (relative), the void-fraction histogram of cells below
0.3 m accumulated over the window (total-variation distance, 0 = same, 1 = disjoint) and the mixing
entropy at fixed times (largest absolute difference; all runs on the same 2 x 2 x 15 analysis grid).

    python tools/speed_accuracy.py --json [--quick] [--shapes sphere spherocylinder] [--out DIR]

Writes ``speed_accuracy.png`` (wall time per simulated second against the budget-normalised error,
Pareto front highlighted) and prints, as the last line, one JSON object
``{"points": [...], "default": ..., "reference": ..., "budget": {...}, ...}``. ``--quick`` (1,000
particles, 0.3 s per run, fewer variants) is a smoke run of a few minutes; the full chart takes about
half an hour on 2 cores.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import fvdem
from fvdem.scenes.observables import weight_per_area
from fvdem.case import case_from_dict
from validate_umf import SETTINGS, reduced_bed_table

# Error budget of the defaults (docs/speed-accuracy.md): the pressure drop within issue 5's 3 % plateau
# tolerance, the bed height within 5 %, the void-fraction histogram within a total-variation distance
# of 0.15 and the mixing entropy within 0.1 at every fixed time -- or within 1.5 x the replica's error
# where the chaos of a short run alone exceeds that (an error below the noise floor is not resolved).
BUDGET = {"pressure_drop": 0.03, "bed_height": 0.05, "void_fraction_histogram": 0.15, "mixing_entropy": 0.1}
PAPER = SETTINGS["paper"]


def dem_factor(f, cfd=1):
    return {"time.dem_step": PAPER["dem_step"] * f, "contact.normal_stiffness": PAPER["normal_stiffness"] / f ** 2,
            "gas.cfd_step": PAPER["cfd_step"] * cfd}


def variants(shape, quick):
    """(name, overrides, what it changes) in run order; the reference first."""
    rows = [("reference", {}, "paper settings"),
            ("replica", {"particles.insertion.seed": 11}, "reference from another random insertion (noise floor)")]
    if not quick:
        if shape == "spherocylinder":  # the slower shape: the variants that matter for it
            rows += [("dem-x5", dem_factor(5), "k_n / 25, DEM step x 5"),
                     ("cfd-x5", {"gas.cfd_step": PAPER["cfd_step"] * 5}, "CFD step x 5"),
                     ("dem-x5-cfd-x5", dem_factor(5, 5), "k_n / 25, DEM step x 5, CFD step x 5"),
                     ("dem-x10-cfd-x5", dem_factor(10, 5), "k_n / 100, DEM step x 10, CFD step x 5"),
                     ("voidage-centroid", {"coupling.voidage": "centroid"}, "centroid voidage"),
                     ("voidage-trilinear", {"coupling.voidage": "trilinear"}, "trilinear voidage"),
                     ("sp-closures", {"coupling.drag": "hoelzer-sommerfeld", "coupling.lift": "zastawny",
                                      "coupling.torque": "zastawny"}, "single-particle closures"),
                     ("mp-drag-only", {"coupling.lift": "none", "coupling.torque": "none"},
                      "multi-particle drag only (no lift, no torque)")]
            return rows
        rows += [(f"dem-x{f}", dem_factor(f), f"k_n / {f * f}, DEM step x {f}") for f in (2, 5, 10)]
        rows += [(f"cfd-x{f}", {"gas.cfd_step": PAPER["cfd_step"] * f}, f"CFD step x {f}") for f in (2, 5, 10)]
        rows += [("dem-x5-cfd-x2", dem_factor(5, 2), "k_n / 25, DEM step x 5, CFD step x 2"),
                 ("dem-x5-cfd-x5", dem_factor(5, 5), "k_n / 25, DEM step x 5, CFD step x 5"),
                 ("dem-x10-cfd-x5", dem_factor(10, 5), "k_n / 100, DEM step x 10, CFD step x 5"),
                 ("grid-30mm", {"gas.cells": [2, 2, 15]}, "30 mm cells"),
                 ("grid-7.5mm", {"gas.cells": [8, 8, 60]}, "7.5 mm cells"),
                 ("voidage-centroid", {"coupling.voidage": "centroid"}, "centroid voidage"),
                 ("voidage-trilinear", {"coupling.voidage": "trilinear"}, "trilinear voidage"),
                 ("threads-1", {"run.threads": 1}, "1 thread")]
    else:
        rows += [("dem-x5", dem_factor(5), "k_n / 25, DEM step x 5"),
                 ("cfd-x5", {"gas.cfd_step": PAPER["cfd_step"] * 5}, "CFD step x 5"),
                 ("dem-x5-cfd-x5", dem_factor(5, 5), "k_n / 25, DEM step x 5, CFD step x 5"),
                 ("voidage-trilinear", {"coupling.voidage": "trilinear"}, "trilinear voidage")]
    if shape == "spherocylinder":
        rows += [("sp-closures", {"coupling.drag": "hoelzer-sommerfeld", "coupling.lift": "zastawny",
                                  "coupling.torque": "zastawny"}, "single-particle closures")]
    return rows


def build_case(shape, particles, overrides, threads):
    """validate_umf.py's reduced bed at the paper's settings, AR-4 with the MP closures, two colour
    layers on a 2 x 2 x 15 mixing grid, with ``overrides`` (dotted keys) applied."""
    table = reduced_bed_table(shape, "mp", particles, threads)
    table["name"] = "speed_accuracy"
    table["particles"]["colour"] = "by_height"
    table["output"]["mixing_cells"] = [2, 2, 15]
    return case_from_dict(table, overrides=overrides)


def measure(case, spin, window, sample, entropy_times):
    """Run spin-up + window; time series sampled every ``sample`` s in the window."""
    sim = fvdem.Simulation(case)
    weight = weight_per_area(sim.model)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    drops, heights, voids = [], [], []
    entropy = {}
    marks = sorted(set([round(t, 6) for t in entropy_times] + [round(spin + sample * k, 6)
                                                               for k in range(1, int(round(window / sample)) + 1)]))
    for mark in marks:
        sim.run(mark - sim.time)
        diag = sim.diagnostics()
        if any(abs(mark - t) < 1e-9 for t in entropy_times):
            entropy[f"{mark:g}"] = diag["mixing_entropy"]
        if mark > spin + 1e-9:
            drops.append(diag["bed_pressure_drop"])
            heights.append(float(sim.particles.position[:, 2].mean()))
            centres = sim.gas.mesh.cell_centers
            voids.append(np.asarray(sim.gas.voidage)[centres[:, 2] < 0.3].copy())
    wall, cpu = time.perf_counter() - wall0, time.process_time() - cpu0
    counts, _ = np.histogram(np.concatenate(voids), bins=20, range=(0.0, 1.0))
    return {"wall_seconds_per_simulated_second": wall / sim.time, "cpu_seconds_per_simulated_second": cpu / sim.time,
            "simulated_seconds": sim.time, "threads": sim.threads,
            "pressure_drop_over_weight": float(np.mean(drops)) / weight,
            "pressure_drop_fluctuation_over_weight": float(np.std(drops)) / weight,
            "mean_height": float(np.mean(heights)), "mixing_entropy": entropy,
            "void_fraction_histogram": (counts / counts.sum()).tolist()}


_WARM: set = set()  # shapes whose kernels this process has loaded


def measure_task(spec, _threads=None):
    """One variant as a sweep task: ``spec = (shape, particles, overrides, threads, spin, window, sample,
    entropy_times)``. The first task of a shape in a worker loads (or compiles) the kernels on a
    50-particle bed first, so that no measured run pays for it."""
    shape, particles, overrides, threads, spin, window, sample, entropy_times = spec
    if shape not in _WARM:
        fvdem.Simulation(build_case(shape, 50, {}, threads)).run(2e-3)
        _WARM.add(shape)
    return measure(build_case(shape, particles, overrides, threads), spin, window, sample, entropy_times)


def errors_against(run, ref):
    return {"pressure_drop": abs(run["pressure_drop_over_weight"] / ref["pressure_drop_over_weight"] - 1.0),
            "bed_height": abs(run["mean_height"] / ref["mean_height"] - 1.0),
            "void_fraction_histogram": 0.5 * float(np.abs(np.subtract(run["void_fraction_histogram"],
                                                                      ref["void_fraction_histogram"])).sum()),
            "mixing_entropy": max(abs(run["mixing_entropy"][t] - ref["mixing_entropy"][t]) for t in ref["mixing_entropy"])}


def pareto_front(points):
    """Names of the points no other point beats in both wall time and normalised error."""
    front = []
    for p in points:
        if p.get("failed"):
            continue
        dominated = any(q is not p and not q.get("failed")
                        and q["wall_seconds_per_simulated_second"] <= p["wall_seconds_per_simulated_second"]
                        and q["normalised_error"] <= p["normalised_error"]
                        and (q["wall_seconds_per_simulated_second"] < p["wall_seconds_per_simulated_second"]
                             or q["normalised_error"] < p["normalised_error"])
                        for q in points)
        if not dominated:
            front.append(p["label"])
    return front


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shapes", nargs="+", choices=("sphere", "spherocylinder"), default=["sphere", "spherocylinder"])
    parser.add_argument("--quick", action="store_true", help="1,000 particles, 0.3 s runs, fewer variants")
    parser.add_argument("--particles", type=int, default=None)
    parser.add_argument("--threads", type=int, default=2, help="threads of every run but 'threads-1'")
    parser.add_argument("--workers", type=int, default=1, help="Dask workers (LocalCluster); more than 1 puts timed "
                        "runs side by side on this machine, so only on a cluster of separate nodes")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler to send the variants to")
    parser.add_argument("--out", default=".")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--from-json", metavar="FILE", help="redraw the chart and choose the default again from a "
                        "saved output of this tool (its last line), without running anything")
    args = parser.parse_args(argv)
    if args.from_json:
        saved = json.loads(Path(args.from_json).read_text().strip().splitlines()[-1])
        finish(saved, Path(args.out), time.perf_counter(), args.json)
        return
    particles = args.particles or (1000 if args.quick else 2000)
    spin, window, sample = (0.1, 0.2, 0.01) if args.quick else (0.3, 0.7, 0.01)
    entropy_times = [0.1, 0.2, 0.3] if args.quick else [0.25, 0.5, 0.75, 1.0]
    wall0 = time.perf_counter()
    budget = dict(BUDGET)
    # every variant is a task on fvdem's sweep engine (fvdem.study.map_tasks, the Dask clients of fvdem
    # study); one worker by default, so that no two timed runs share the cores
    specs, labels, descriptions = [], [], []
    for shape in args.shapes:
        for name, overrides, what in variants(shape, args.quick):
            threads = overrides.get("run.threads", args.threads)
            specs.append((shape, particles, overrides, threads, spin, window, sample, entropy_times))
            labels.append(f"{'AR-1' if shape == 'sphere' else 'AR-4'} {name}")
            descriptions.append((shape, name, overrides, what))
    from fvdem.study import map_tasks
    outcomes = map_tasks(measure_task, specs, labels, scheduler=args.scheduler, workers=args.workers,
                         log=lambda line: print(line, file=sys.stderr, flush=True))
    points, runs = [], {}
    for label, (shape, name, overrides, what), outcome in zip(labels, descriptions, outcomes):
        point = {"variant": name, "label": label, "shape": shape, "changes": what,
                 "settings": {k: v for k, v in overrides.items() if k != "particles.insertion.seed"}}
        if outcome["status"] == "failed":
            point.update(failed=True, reason=outcome["error"])
            points.append(point)
            print(f"{label:32s} failed: {outcome['error']}", flush=True)
            continue
        run = runs[label] = outcome["value"]
        point.update({k: run[k] for k in ("wall_seconds_per_simulated_second", "cpu_seconds_per_simulated_second",
                                          "threads", "pressure_drop_over_weight", "mean_height", "mixing_entropy")})
        points.append(point)
        print(f"{label:32s} {run['wall_seconds_per_simulated_second']:7.1f} s wall per simulated s "
              f"(CPU {run['cpu_seconds_per_simulated_second']:.1f}); dP/W {run['pressure_drop_over_weight']:.3f}, "
              f"mean height {run['mean_height'] * 100:.2f} cm", flush=True)
    for shape in args.shapes:
        ref = runs[f"{'AR-1' if shape == 'sphere' else 'AR-4'} reference"]
        ref_wall = ref["wall_seconds_per_simulated_second"]
        for point in points:
            if point["shape"] != shape or point.get("failed"):
                continue
            point["errors"] = errors_against(runs[point["label"]], ref)
            point["speed_up"] = ref_wall / point["wall_seconds_per_simulated_second"]
    # the noise floor: a replica's error; a budget below it cannot be resolved by runs this short
    floor = {k: max(p["errors"][k] for p in points if p["variant"] == "replica" and "errors" in p) for k in BUDGET}
    effective = {k: max(budget[k], 1.5 * floor[k]) for k in BUDGET}
    for point in points:
        if "errors" in point:
            point["normalised_error"] = max(point["errors"][k] / effective[k] for k in BUDGET)
            point["within_budget"] = bool(point["normalised_error"] <= 1.0)
    result = {"points": points, "reference": "reference", "budget": budget, "noise_floor": floor,
              "effective_budget": effective,
              "bed": f"{particles} particles, 0.06 x 0.06 x 0.45 m, 2 Umf, spin-up {spin} s, window {window} s"}
    finish(result, Path(args.out), wall0, args.json)


def finish(result, out, wall0, as_json):
    """Pareto fronts (per shape), the default, the chart and the JSON line."""
    points = result["points"]
    front = []
    for shape in {p["shape"] for p in points}:
        front += pareto_front([p for p in points if p["shape"] == shape and "errors" in p and p["variant"] != "replica"])
    for point in points:
        point["on_front"] = point.get("label") in front
    result["default"] = choose_default(points)
    png = out / "speed_accuracy.png"
    _plot(png, points)
    result.update(plot=str(png), wall_seconds=time.perf_counter() - wall0 + result.get("wall_seconds", 0.0))
    print(json.dumps(result) if as_json else json.dumps(result, indent=2))


def choose_default(points):
    """The fastest variant within budget for every shape measured (its speed-up: the smaller of the
    shapes'); variants run for one shape only are not candidates; the reference when none is faster."""
    by_variant = {}
    shapes = {p["shape"] for p in points}
    for p in points:
        by_variant.setdefault(p["variant"], []).append(p)
    best, best_speed = None, 0.0
    for name, group in by_variant.items():
        if name in ("replica", "threads-1") or len(group) < len(shapes) or any(not p.get("within_budget") for p in group):
            continue
        speed = min(p["speed_up"] for p in group)
        if speed > best_speed:
            best, best_speed = name, speed
    return best


def _plot(path, points):
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 5))
    colours = {"sphere": "tab:blue", "spherocylinder": "tab:orange"}
    for shape in ("sphere", "spherocylinder"):
        group = [p for p in points if p["shape"] == shape and "normalised_error" in p]
        if not group:
            continue
        x = [max(p["normalised_error"], 1e-3) for p in group]
        y = [p["wall_seconds_per_simulated_second"] for p in group]
        ax.scatter(x, y, color=colours[shape], label="AR-1" if shape == "sphere" else "AR-4", zorder=3)
        for p, xi, yi in zip(group, x, y):
            ax.annotate(p["variant"], (xi, yi), fontsize=6, xytext=(3, 2), textcoords="offset points")
        front = sorted((xi, yi) for p, xi, yi in zip(group, x, y) if p["on_front"] or p["variant"] == "reference")
        if front:
            fx, fy = zip(*front)
            ax.step(fx, fy, where="post", color=colours[shape], alpha=0.5, lw=2)
    ax.axvline(1.0, color="k", ls="--", lw=0.8, label="error budget")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("error / budget (largest over the observables; 1e-3 = identical)")
    ax.set_ylabel("wall seconds per simulated second (2 cores)")
    ax.set_title("speed against accuracy, reduced bed at 2 Umf (front: lines)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    _save(fig, path)


if __name__ == "__main__":
    main()
