"""Hindered settling of a periodic suspension against Richardson-Zaki (issue 6, Derksen).

For one particle shape (Derksen's cylinders of aspect ratio l/d, as equal-volume spherocylinders, or
spheres) and one Galileo number, runs the fully periodic, force-balanced suspension of
``cases/hindered_settling.toml`` at mean solids fractions 0.1, 0.2, 0.29, 0.4, 0.48, takes each run's
slip Reynolds number ``Re = (<u_z> - <u_pz>) d_e / nu`` over its automatically chosen steady window
(with the batch-means standard error), and fits ``Re = Re_inf (1 - phi)^N`` by least squares (in log
space). Compared with Richardson-Zaki for spheres, ``N = 4.45 Re_inf^-0.1`` (1 < Re_inf < 500), and
with the single particle's terminal Reynolds number under the same drag closure (the phi -> 0 limit,
from the drag balance, independent of the suspension runs).

    python tools/validate_hindered_settling.py --aspect-ratio 2 --ga-e 1296 --json
    python tools/validate_hindered_settling.py --aspect-ratio 4 --ga 864 --json
    python tools/validate_hindered_settling.py --sphere --ga 864 --json
    python tools/validate_hindered_settling.py --aspect-ratio 4 --ga-e 1296 --fractions 0.2 0.29 0.4 \
        --drag tang --stochastic-force force-langevin --json   (the particle velocity fluctuations with the
        stochastic drag force, fvdem/coupling/stochastic.py; --fluctuations OUTPUT ... charts saved sweeps)

The box is Derksen's 9 d x 9 d x 18 d where the periodic neighbour search allows it (box at least
3 x the particle length plus skin), else the smallest n d x n d x 2n d that does (14 x 14 x 28 for
l/d = 4); cells about 3 d. Writes ``hindered_<tag>_re.png`` (Re against 1 - phi, log axes),
``hindered_<tag>_orientation.png`` and ``hindered_<tag>_fluctuations.png``, and prints as its last
line one JSON object (``re_by_phi``, ``re_inf``, ``n_exponent``, ``fit_r2``, ...).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

FRACTIONS = (0.1, 0.2, 0.29, 0.4, 0.48)


def scene(aspect_ratio, sphere, ga, ga_e, phi, duration, seed=1, drag=None, stochastic_force=None,
          stochastic_scale=None, cfd_divisor=1, stochastic_along_scale=None, stochastic_zero_mean=None):
    d_over_length = 1.0 if sphere else aspect_ratio + 1.0 / 3.0  # particle length in d
    reach = d_over_length + 0.1
    side = max(9, math.ceil(3.0 * reach + 1e-9))
    cells = max(3, round(side / 3))
    suspension = {"enabled": True, "particle": "sphere" if sphere else "cylinder", "density_ratio": 2.0,
                  "solids_fraction": phi, "box": [side, side, 2 * side], "cells": [cells, cells, 2 * cells],
                  "duration": duration}
    if not sphere:
        suspension["aspect_ratio"] = aspect_ratio
    if ga is not None:
        suspension["galileo"] = ga
    else:
        suspension["galileo_equivalent"] = ga_e
    table = {"name": f"hindered_{phi:g}", "suspension": suspension,
             "particles": {"insertion": {"seed": seed}},
             "output": {"progress": False, "vtk": False, "timeseries_interval": "2 ms"}}
    if drag is not None:
        table["coupling"] = {"drag": drag}
    if stochastic_force is not None:
        table.setdefault("coupling", {}).update(stochastic_force=stochastic_force, stochastic_seed=seed)
    if stochastic_scale is not None:
        table.setdefault("coupling", {})["stochastic_scale"] = stochastic_scale
    if stochastic_along_scale is not None:
        table.setdefault("coupling", {})["stochastic_along_scale"] = stochastic_along_scale
    if stochastic_zero_mean is not None:
        table.setdefault("coupling", {})["stochastic_zero_mean"] = stochastic_zero_mean
    if cfd_divisor > 1:  # the scene's CFD step divided, to the nearest whole multiple of its DEM step
        from fvdem.case import case_from_dict
        case = case_from_dict(table)
        multiple = max(1, round(case.gas.cfd_step / case.time.dem_step / cfd_divisor))
        table.setdefault("gas", {})["cfd_step"] = multiple * case.time.dem_step
    return table


def run_one(table, threads):
    from fvdem.case import case_from_dict
    from fvdem.simulation import Simulation
    case = case_from_dict(table)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    sim = Simulation(case, threads=threads, progress=False)
    summary = sim.run()
    result = dict(summary["suspension"])
    # the mean drag's exchange number beta dt / (rho eps), beta = phi (1 - phi)^2 (rho_p - rho) g / u_s in a
    # force-balanced suspension: the exact exchange's explicit return needs it below about 1 (docs/coupling.md)
    phi, gravity = result["solids_fraction"], float(np.linalg.norm(case.domain.gravity))
    exchange = (phi * (1.0 - phi) * (case.particles.density - case.gas.density) / case.gas.density * gravity
                * case.gas.cfd_step / result["settling_velocity"])
    result.update(particles=case.particles.count, wall_seconds=time.perf_counter() - wall0, cfd_step=case.gas.cfd_step,
                  exchange_number=exchange,
                  cpu_seconds=time.process_time() - cpu0, simulated_seconds=sim.time,
                  box=list(case.suspension.box), cells=list(case.gas.cells),
                  max_overlap_over_diameter=summary["max_overlap_over_diameter"])
    return result


def terminal_reynolds(table):
    """phi -> 0 limit: the single particle's terminal Re (on d_e) under the case's drag closure, from
    m' g = c(v) v with buoyancy, isotropic orientation average of the drag (the closure at the
    particles' orientations is averaged over random axes)."""
    from fvdem.case import case_from_dict
    from fvdem.coupling.bridge import HydrodynamicModel
    case = case_from_dict(table)
    p, g = case.particles, case.gas
    model = HydrodynamicModel(case.coupling.drag, "none", "none", p.diameter,
                              p.length if p.shape != "sphere" else p.diameter, g.density, g.viscosity)
    rng = np.random.default_rng(0)
    axis = rng.normal(size=(400, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    weight = (p.density - g.density) * p.volume * 9.81
    v = 1e-3
    for _ in range(200):
        slip = np.tile([0.0, 0.0, v], (len(axis), 1))
        c = float(model.drag_coefficient(slip, np.ones(len(axis)), axis).mean())
        v = 0.5 * v + 0.5 * weight / c
    return v * p.equivalent_diameter * g.density / g.viscosity


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--aspect-ratio", type=float, default=2.0, help="cylinder l/d (1, 2, 4 in Derksen)")
    parser.add_argument("--sphere", action="store_true", help="spheres instead of cylinders")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--ga", type=float, help="Galileo number on d")
    group.add_argument("--ga-e", type=float, help="Galileo number on d_e")
    parser.add_argument("--fractions", type=float, nargs="+", default=list(FRACTIONS))
    parser.add_argument("--duration", type=float, default=20.0, help="viscous times d^2/nu per run")
    parser.add_argument("--jobs", "--workers", type=int, default=2, dest="jobs",
                        help="runs in parallel on a Dask LocalCluster (each on one thread)")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler to send the runs to")
    parser.add_argument("--quick", action="store_true", help="three fractions, 6 viscous times (a smoke run)")
    from fvdem.coupling.closures import law_names
    parser.add_argument("--drag", choices=tuple(n for n in law_names("drag") if n != "none"),
                        help="drag closure (fvdem laws drag; default: the case's, Hoelzer-Sommerfeld + Di Felice)")
    from fvdem.coupling.stochastic import stochastic_force_names
    parser.add_argument("--stochastic-force", choices=stochastic_force_names(),
                        help="stochastic drag fluctuation (fvdem laws stochastic_force; default: the case's, none)")
    parser.add_argument("--stochastic-scale", type=float,
                        help="factor on the stochastic force's standard deviations (default 1: as published)")
    parser.add_argument("--stochastic-along-scale", type=float,
                        help="factor on its standard deviation along the slip alone (default 1: as published)")
    parser.add_argument("--stochastic-zero-mean", choices=("box", "cell"),
                        help="over which particles the force's mean is removed (default 'box': as published; 'cell': "
                             "those sharing a grid cell)")
    parser.add_argument("--seed", type=int, default=1, help="insertion and stochastic-force seed of every run")
    parser.add_argument("--cfd-divisor", type=int, default=1,
                        help="divide the scene's CFD step by this (whole DEM steps): the exchange's explicit return "
                             "needs beta dt / (rho eps) below about 1 (docs/coupling.md), which a strong drag at "
                             "<phi> = 0.4 exceeds at the scene's step")
    parser.add_argument("--out", default=".")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--combine", nargs="+", metavar="OUTPUT",
                        help="draw saved outputs of this tool (their last lines) on one chart, run nothing")
    parser.add_argument("--fluctuations", nargs="+", metavar="OUTPUT",
                        help="draw the velocity fluctuations of saved outputs (with and without a stochastic force) "
                             "against <phi>, one panel per shape, into hindered_fluctuations.png; run nothing")
    args = parser.parse_args(argv)
    if args.combine:
        print(_combined_plot(Path(args.out) / "hindered_settling.png", args.combine))
        return
    if args.fluctuations:
        print(_fluctuation_plot(Path(args.out) / "hindered_fluctuations.png", args.fluctuations))
        return
    if args.ga is None and args.ga_e is None:
        args.ga_e = 1296.0
    if args.quick:
        args.fractions, args.duration = [0.1, 0.29, 0.48], 6.0
    Path(args.out).mkdir(parents=True, exist_ok=True)  # before the runs: a missing folder lost a sweep's result
    wall0 = time.perf_counter()
    tables = [scene(args.aspect_ratio, args.sphere, args.ga, args.ga_e, phi, args.duration, seed=args.seed,
                    drag=args.drag, stochastic_force=args.stochastic_force, stochastic_scale=args.stochastic_scale,
                    cfd_divisor=args.cfd_divisor, stochastic_along_scale=args.stochastic_along_scale,
                    stochastic_zero_mean=args.stochastic_zero_mean)
              for phi in args.fractions]
    # one task per fraction on fvdem's sweep engine (the Dask clients of fvdem study)
    from fvdem.study import map_tasks
    outcomes = map_tasks(run_one, tables, [f"phi={phi:g}" for phi in args.fractions], threads=1,
                         scheduler=args.scheduler, workers=max(1, args.jobs),
                         log=lambda line: print(line, file=sys.stderr, flush=True))
    failed = [f"{o['name']}: {o['error']}" for o in outcomes if o["status"] == "failed"]
    if failed:
        raise SystemExit("validate_hindered_settling: runs failed: " + "; ".join(failed))
    results = [o["value"] for o in outcomes]
    for phi, r in zip(args.fractions, results):
        print(f"<phi> = {phi:<5g} ({r['particles']} particles): Re = {r['slip_reynolds']:.3f} +- "
              f"{r['slip_reynolds_standard_error']:.3f} over {r['window_start']:.2f}-{r['window_end']:.2f} s; "
              f"sigma_z/u_s {r['velocity_fluctuation_vertical_over_settling']:.3f}, sigma_h/u_s "
              f"{r['velocity_fluctuation_horizontal_over_settling']:.3f}; {r['wall_seconds']:.0f} s wall", flush=True)
    from fvdem.analysis.suspension import richardson_zaki_exponent, richardson_zaki_fit
    phis = [r["solids_fraction"] for r in results]
    fit = richardson_zaki_fit(phis, [r["slip_reynolds"] for r in results])
    re_terminal = terminal_reynolds(scene(args.aspect_ratio, args.sphere, args.ga, args.ga_e, 0.1, args.duration,
                                          drag=args.drag))
    tag = ("sphere" if args.sphere else f"ar{args.aspect_ratio:g}") + (f"_ga{args.ga:g}" if args.ga else f"_gae{args.ga_e:g}")
    if args.drag:
        tag += f"_{args.drag}"
    if args.stochastic_force not in (None, "none"):
        tag += f"_{args.stochastic_force}" + (f"x{args.stochastic_scale:g}" if args.stochastic_scale else "") + (
            f"_along{args.stochastic_along_scale:g}" if args.stochastic_along_scale is not None else "") + (
            f"_{args.stochastic_zero_mean}" if args.stochastic_zero_mean not in (None, "box") else "")
    out = Path(args.out)
    plots = _plots(out, tag, results, fit)
    result = {
        "shape": "sphere" if args.sphere else "cylinder (equal-volume spherocylinder)",
        "aspect_ratio": None if args.sphere else args.aspect_ratio,
        "galileo": args.ga, "galileo_equivalent": args.ga_e, "drag": tables[0].get("coupling", {}).get("drag", "case"),
        "stochastic_force": args.stochastic_force or "none", "stochastic_scale": args.stochastic_scale or 1.0,
        "stochastic_along_scale": 1.0 if args.stochastic_along_scale is None else args.stochastic_along_scale,
        "stochastic_zero_mean": args.stochastic_zero_mean or "box",
        "seed": args.seed, "cfd_divisor": args.cfd_divisor,
        "re_by_phi": {f"{phi:g}": r["slip_reynolds"] for phi, r in zip(args.fractions, results)},
        "re_standard_error_by_phi": {f"{phi:g}": r["slip_reynolds_standard_error"] for phi, r in zip(args.fractions, results)},
        "re_inf": fit["re_inf"], "n_exponent": fit["n_exponent"], "fit_r2": fit["r2"],
        "richardson_zaki_n": richardson_zaki_exponent(fit["re_inf"]),
        "single_particle_terminal_re": re_terminal,
        "fluctuations_by_phi": {f"{phi:g}": {"vertical": r["velocity_fluctuation_vertical_over_settling"],
                                             "horizontal": r["velocity_fluctuation_horizontal_over_settling"],
                                             "anisotropy": r["velocity_fluctuation_vertical_over_settling"]
                                             / r["velocity_fluctuation_horizontal_over_settling"]}
                                for phi, r in zip(args.fractions, results)},
        "mean_abs_cos_vertical_by_phi": {f"{phi:g}": r.get("mean_abs_cos_vertical") for phi, r in zip(args.fractions, results)},
        "runs": results, "plots": plots, "duration_viscous_times": args.duration,
        "wall_seconds": time.perf_counter() - wall0,
    }
    print(json.dumps(result) if args.json else json.dumps(result, indent=2))


def _combined_plot(path, outputs):
    """Re against 1 - <phi> of several sweeps on one chart, with each fit and Richardson-Zaki."""
    from fvdem.analysis.plots import _pyplot, _save
    from fvdem.analysis.suspension import richardson_zaki_exponent
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(10, 4.2), sharey=True)
    for name in outputs:
        r = json.loads(Path(name).read_text().strip().splitlines()[-1])
        ax = axes[0] if r["galileo"] is not None else axes[1]
        label = "sphere" if r["aspect_ratio"] is None else f"l/d = {r['aspect_ratio']:g}"
        phi = np.array([run["solids_fraction"] for run in r["runs"]])
        re = np.array([run["slip_reynolds"] for run in r["runs"]])
        line, = ax.plot(1 - phi, re, "o", label=f"{label}: Re_inf {r['re_inf']:.1f}, N {r['n_exponent']:.2f}")
        x = np.linspace(0.5, 1.0, 30)
        ax.plot(x, r["re_inf"] * x ** r["n_exponent"], "-", color=line.get_color(), lw=1)
        ax.plot(x, r["re_inf"] * x ** richardson_zaki_exponent(r["re_inf"]), ":", color=line.get_color(), lw=1)
    for ax, title in zip(axes, ("Ga = 864 (on d)", "Ga_e = 1296 (on d_e)")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("1 - <phi>")
        ax.set_title(title + "; fit (-), Richardson-Zaki (:)", fontsize=9)
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("slip Reynolds number Re")
    return _save(fig, path)


def _fluctuation_points(outputs):
    """``{(shape, drag): {label: {phi: [(vertical, horizontal, Re, cfd_divisor), ...]}}}`` of saved sweeps: the
    runs of one shape, drag and stochastic force (with its calibration) at one <phi> are replicas (other seeds)
    where their CFD step is the same; an output at another step replaces the earlier ones' point at that <phi>
    (e.g. <phi> = 0.4 run again with a third of the step)."""
    lines = {}
    for name in outputs:
        r = json.loads(Path(name).read_text().strip().splitlines()[-1])
        shape = "sphere" if r["aspect_ratio"] is None else f"l/d = {r['aspect_ratio']:g}"
        model = r.get("stochastic_force", "none")
        scale, along = r.get("stochastic_scale", 1.0), r.get("stochastic_along_scale", 1.0)
        label = "no stochastic force" if model == "none" else model + ("" if scale == 1.0 else f" x {scale:g}") + (
            "" if along == 1.0 else f", along-slip x {along:g}") + (
            ", zero mean per cell" if r.get("stochastic_zero_mean", "box") == "cell" else "")
        points = lines.setdefault((shape, r["drag"]), {}).setdefault(label, {})
        divisor = r.get("cfd_divisor", 1)
        for phi, f in r["fluctuations_by_phi"].items():
            runs = points.setdefault(float(phi), [])
            if runs and runs[0][3] != divisor:
                runs.clear()
            runs.append((f["vertical"], f["horizontal"], r["re_by_phi"][phi], divisor))
    return lines


def _fluctuation_table(lines) -> str:
    """A Markdown table of the points: per shape, <phi> and force the replicas' mean and standard deviation
    (n > 1) of Re, sigma_z/u_s, sigma_h/u_s and sigma_z/sigma_h (the ratio's range too), and the mean Re's
    departure from the runs without a force at the same <phi> and step."""
    rows = ["| shape | <phi> | stochastic force | CFD step | runs | Re | dRe vs none | sigma_z/u_s | sigma_h/u_s | "
            "sigma_z/sigma_h (range) |", "|---|---|---|---|---|---|---|---|---|---|"]

    def stat(values):
        values = np.asarray(values, dtype=float)
        return f"{values.mean():.2f}" + (f" ± {values.std(ddof=1):.2f}" if len(values) > 1 else "")
    for (shape, drag), labels in sorted(lines.items()):
        none = labels.get("no stochastic force", {})
        for label, points in labels.items():
            for phi in sorted(points):
                runs = np.array(points[phi], dtype=float)
                vertical, horizontal, re, divisor = runs.T
                ratio = vertical / horizontal
                base = np.array(none.get(phi, []), dtype=float)
                same_step = base[base[:, 3] == divisor[0]] if len(base) else base
                change = (f"{100 * (re.mean() / same_step[:, 2].mean() - 1):+.1f} %"
                          if len(same_step) and label != "no stochastic force" else "-")
                rows.append(f"| {shape}, {drag} | {phi:g} | {label} | x 1/{int(divisor[0])} | {len(runs)} | {stat(re)} | "
                            f"{change} | {stat(vertical)} | {stat(horizontal)} | {stat(ratio)} "
                            f"({ratio.min():.2f}-{ratio.max():.2f}) |")
    return "\n".join(rows)


def _fluctuation_plot(path, outputs):
    """sigma_z/u_s, sigma_h/u_s and their ratio against <phi> of saved sweeps: one column of panels per shape,
    one colour per stochastic force (with its calibration), replicas averaged (bars: their range), the target
    band of the ratio shaded; the table of ``_fluctuation_table`` beside it (``hindered_fluctuations.md``)."""
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    lines = _fluctuation_points(outputs)
    Path(path).with_suffix(".md").write_text(_fluctuation_table(lines) + "\n")
    shapes = sorted(lines)
    labels = list(dict.fromkeys(label for shape in shapes for label in lines[shape]))
    colours = {label: f"C{k % 10}" if k < 10 else plt.get_cmap("tab20")(k % 20) for k, label in enumerate(labels)}
    fig, axes = plt.subplots(2, len(shapes), figsize=(5.5 * len(shapes), 8.0), squeeze=False, sharex=True)
    for column, (shape, drag) in enumerate(shapes):
        top, bottom = axes[0, column], axes[1, column]
        for label, points in lines[(shape, drag)].items():
            phi = sorted(points)
            runs = [np.array(points[p], dtype=float) for p in phi]
            vertical, horizontal = (np.array([r[:, k].mean() for r in runs]) for k in (0, 1))
            ratio = [r[:, 0] / r[:, 1] for r in runs]

            def bars(values, centre):
                return np.array([centre - [v.min() for v in values], [v.max() for v in values] - centre])
            line = top.errorbar(phi, vertical, yerr=bars([r[:, 0] for r in runs], vertical), fmt="o-", capsize=3,
                                color=colours[label], label=f"{label}: vertical")[0]
            top.errorbar(phi, horizontal, yerr=bars([r[:, 1] for r in runs], horizontal), fmt="s--", capsize=3,
                         color=line.get_color(), label=f"{label}: horizontal")
            middle = np.array([v.mean() for v in ratio])
            bottom.errorbar(phi, middle, yerr=bars(ratio, middle), fmt="o-", capsize=3, color=line.get_color(),
                            label=label)
        top.axhline(0.2, color="grey", lw=0.8, ls=":")
        top.set_title(f"{shape}, {drag} drag", fontsize=9)
        top.set_ylabel("velocity fluctuation / settling velocity")
        bottom.axhspan(1.5, 3.0, color="green", alpha=0.1, label="target 1.5-3")
        bottom.set_yscale("log")
        bottom.set_ylabel("sigma_z / sigma_h")
        bottom.set_xlabel("<phi>")
        for ax in (top, bottom):
            ax.grid(alpha=0.3, which="both")
            ax.legend(fontsize=6)
    return _save(fig, path)


def _plots(out, tag, results, fit):
    from fvdem.analysis.plots import _pyplot, _save
    from fvdem.analysis.suspension import richardson_zaki_exponent
    plt = _pyplot()
    paths = []
    phi = np.array([r["solids_fraction"] for r in results])
    re = np.array([r["slip_reynolds"] for r in results])
    err = np.array([r["slip_reynolds_standard_error"] for r in results])
    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.errorbar(1 - phi, re, yerr=err, fmt="o", label="fvdem (steady-window mean)")
    x = np.linspace(0.45, 1.0, 50)
    ax.plot(x, fit["re_inf"] * x ** fit["n_exponent"], "-",
            label=f"fit: Re_inf {fit['re_inf']:.1f}, N {fit['n_exponent']:.2f} (r2 {fit['r2']:.3f})")
    n_rz = richardson_zaki_exponent(fit["re_inf"])
    ax.plot(x, fit["re_inf"] * x ** n_rz, "--", color="grey", label=f"Richardson-Zaki N = {n_rz:.2f}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("1 - <phi>")
    ax.set_ylabel("slip Reynolds number Re")
    ax.set_title(tag)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7)
    paths.append(str(_save(fig, Path(out) / f"hindered_{tag}_re.png")))

    if any("orientation_density" in r for r in results):
        fig, ax = plt.subplots(figsize=(5.5, 4))
        for r in results:
            if "orientation_density" in r:
                ax.plot(np.degrees(r["orientation_angle_centres"]), r["orientation_density"], "o-", ms=3,
                        label=f"<phi> = {r['solids_fraction']:.2f}")
        centres = np.array(results[0].get("orientation_angle_centres", []))
        if len(centres):
            ax.plot(np.degrees(centres), np.sin(centres), "k--", label="random: sin(angle)")
        ax.set_xlabel("angle between axis and vertical [deg]")
        ax.set_ylabel("probability density [1/rad]")
        ax.set_title(tag)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        paths.append(str(_save(fig, Path(out) / f"hindered_{tag}_orientation.png")))

    fig, ax = plt.subplots(figsize=(5.5, 4))
    ax.plot(phi, [r["velocity_fluctuation_vertical_over_settling"] for r in results], "o-", label="vertical")
    ax.plot(phi, [r["velocity_fluctuation_horizontal_over_settling"] for r in results], "s-", label="horizontal")
    ax.set_xlabel("<phi>")
    ax.set_ylabel("particle velocity fluctuation / settling velocity")
    ax.set_title(tag)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    paths.append(str(_save(fig, Path(out) / f"hindered_{tag}_fluctuations.png")))
    return paths


if __name__ == "__main__":
    main()
