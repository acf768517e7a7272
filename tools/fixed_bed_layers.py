"""Where the CFD-DEM's own Umf error comes from, layer by layer (issue 18, point 3).

The closure's uniform-bed Umf (``fvdem.analysis.bed.uniform_bed_umf``) assumes a bed of one voidage
everywhere. A simulated bed has a looser layer on the distributor, partly filled cells at its surface
and looser cells along the walls, where the gas channels. This tool freezes the settled paper bed
(``cases/bed_ar1.toml``'s final state, 32,500 spheres in the 0.15 x 0.15 m column on the 10 x 10 x 70
grid; or another case's initial state), blows gas through it at a few velocities until steady, and
compares, without any particle motion:

- the **fixed-bed Umf of the simulated structure**: the superficial velocity at which the bed's
  pressure drop equals its weight per area (interpolated between the solved velocities), against the
  closure's uniform-bed Umf at the bed's core packing -- if these differ by the CFD-DEM ramp's
  excess, the bed's structure (not its motion) is the cause;
- **layer by layer** (each cell layer of the bed): its mean voidage, its measured pressure gradient,
  the gradient the closure gives a uniform bed of that layer's voidage at the same superficial velocity,
  and the wall cells' superficial velocity over the interior cells' (channelling);
- for every ``--voidage`` method (divided, centroid, trilinear...): the same, so that a mapping's
  effect is seen before and after.

    python tools/fixed_bed_layers.py --json [--voidage divided trilinear] [--drag NAME] [--case cases/ar1.toml]
        [--state umf_sphere_defluidized.npz]

The paper bed is settled first when missing (``tools/_beds.py``); ``--quick``: a 1,500-sphere bed, one
method, 5 ms per velocity (seconds; that the tool works, not a result). Prints a table per method, writes ``fixed_bed_layers.png`` and, as the last line, one JSON object
``{"methods": {"<voidage>": {"umf_fixed_bed": ..., "umf_closure_uniform_bed": ..., "layers": [...]}}}``.
"""
from __future__ import annotations

import argparse
import json
import time
import warnings
from pathlib import Path

import numpy as np

import fvdem
from fvdem.analysis.bed import bed_packing, uniform_bed_pressure_gradient, uniform_bed_umf
from fvdem.coupling.voidage import voidage_names
from fvdem.scenes.observables import weight_per_area

from _beds import ROOT, bed_of_case, bed_overrides, settled_beds

RATIOS = (0.9, 1.0, 1.1, 1.2)  # velocities solved, over the closure's uniform-bed Umf


def steady(case_path, overrides, duration):
    """The frozen bed with the gas run ``duration`` s: the simulation at its end."""
    case = fvdem.load_case(case_path, dict(overrides, **{"particles.fixed": True, "output.progress": False}))
    sim = fvdem.Simulation(case, progress=False)
    drops = []
    step = duration / 10
    for _ in range(10):
        sim.run(step)
        drops.append(sim.diagnostics()["bed_pressure_drop"])
    return sim, drops


def layers(sim, top, model, axes, superficial):
    """Per cell layer below the bed top: voidage, measured -dp/dz, the uniform-bed closure's at that
    voidage, and the wall cells' over the interior cells' superficial velocity."""
    mesh, s = sim.gas.mesh, sim.gas
    nx, ny, nz = mesh.shape
    eps = np.asarray(s.voidage).reshape(nz, ny, nx)
    w = (np.asarray(s.voidage) * s.velocity[:, 2]).reshape(nz, ny, nx)  # superficial vertical velocity
    p = np.asarray(s.pressure).reshape(nz, ny, nx).mean(axis=(1, 2))
    dz = mesh.spacing[2]
    g = -sim.case.domain.gravity[2]
    wall = np.zeros((ny, nx), bool)
    wall[0, :] = wall[-1, :] = wall[:, 0] = wall[:, -1] = True
    out = []
    for k in range(nz):
        z = float(mesh.cell_centers[k * nx * ny, 2])
        if z > top + dz:
            break
        lo, hi = max(k - 1, 0), min(k + 1, nz - 1)
        measured = -(p[hi] - p[lo]) / ((hi - lo) * dz) - sim.case.gas.density * g  # less the gas head
        layer_eps = float(eps[k].mean())
        expected = uniform_bed_pressure_gradient(model, layer_eps, superficial, axes) if layer_eps < 0.999 else 0.0
        out.append({"z": z, "voidage": layer_eps, "voidage_wall": float(eps[k][wall].mean()),
                    "voidage_interior": float(eps[k][~wall].mean()), "pressure_gradient": float(measured),
                    "closure_uniform_gradient": float(expected),
                    "wall_over_interior_velocity": float(w[k][wall].mean() / max(w[k][~wall].mean(), 1e-12))})
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--case", default=str(ROOT / "cases" / "ar1.toml"),
                        help="a bed case whose initial state is a settled bed (default: cases/ar1.toml)")
    parser.add_argument("--voidage", nargs="+", choices=voidage_names(), default=["divided", "trilinear"])
    parser.add_argument("--drag", help="drag law (fvdem laws drag; default: the case's)")
    parser.add_argument("--state", help="particle state to freeze instead of the case's initial state (e.g. the "
                        "defluidized bed validate_umf.py writes, umf_<tag>_defluidized.npz)")
    parser.add_argument("--duration", type=float, default=0.3, help="simulated seconds per velocity (to steady)")
    parser.add_argument("--cfd-step", type=float, default=5e-4)
    parser.add_argument("--out", default=".", help="folder for fixed_bed_layers.png")
    parser.add_argument("--quick", action="store_true", help="a 1,500-sphere bed, one method, 5 ms a velocity")
    parser.add_argument("--json", action="store_true", help="the result as one JSON line")
    args = parser.parse_args(argv)
    wall0 = time.perf_counter()
    bed = None if args.state else bed_of_case(args.case)
    if args.quick:
        args.duration, args.voidage = 0.005, args.voidage[:1]
    if bed is not None:  # settled before anything is measured
        settled_beds([bed], "fixed_bed_layers", args.quick)
    # fvdem's defaults for the steps (the particles do not move: only the gas step matters)
    base = {"gas.cfd_step": args.cfd_step, "time.dem_step": args.cfd_step / 10, "contact.normal_stiffness": 800.0,
            "gas.inlet_ramp": 0.0}
    if args.drag:
        base["coupling.drag"] = args.drag
    if args.state:
        base["particles.initial_state"] = str(Path(args.state).resolve())
    elif bed is not None:
        base.update(bed_overrides(bed, args.quick))
    probe, _ = steady(args.case, base, 2 * args.cfd_step)
    packing = bed_packing(probe.particles, probe.case.domain.lower, probe.case.domain.upper, probe.case.domain.periodic)
    model, density = probe.bridge.model, probe.case.particles.density
    umf_uniform = uniform_bed_umf(model, 1.0 - packing["solids_fraction"], packing["axes"], density)
    umf_case = probe.case.gas.umf
    weight = weight_per_area(probe.model)
    methods = {}
    for method in args.voidage:
        curve = []
        for ratio in RATIOS:
            u = ratio * umf_uniform
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                sim, drops = steady(args.case, dict(base, **{"coupling.voidage": method, "gas.u_over_umf": u / umf_case}),
                                    args.duration)
            drift = abs(drops[-1] - drops[-2]) / max(abs(drops[-1]), 1e-12)
            curve.append({"velocity": u, "pressure_drop_over_weight": drops[-1] / weight, "last_change": drift,
                          "layers": layers(sim, packing["bed_top"], model, packing["axes"], u)})
            print(f"{method:10s} U = {u:.3f} m/s ({ratio:.2f} x closure Umf): dP = {drops[-1] / weight:.4f} W/A "
                  f"(last change {drift:.1e})", flush=True)
        x = np.array([c["velocity"] for c in curve])
        y = np.array([c["pressure_drop_over_weight"] for c in curve])
        umf_fixed = float(np.interp(1.0, y, x)) if y.min() <= 1.0 <= y.max() and np.all(np.diff(y) > 0) else None
        at_uniform = curve[RATIOS.index(1.0)]
        methods[method] = {"umf_fixed_bed": umf_fixed, "umf_closure_uniform_bed": umf_uniform,
                           "relative_difference": None if umf_fixed is None else umf_fixed / umf_uniform - 1.0,
                           "curve": [{k: v for k, v in c.items() if k != "layers"} for c in curve],
                           "layers_at_closure_umf": at_uniform["layers"]}
        print(f"{method:10s} fixed-bed Umf {umf_fixed if umf_fixed is None else round(umf_fixed, 3)} m/s against the "
              f"closure's uniform-bed {umf_uniform:.3f} m/s" + ("" if umf_fixed is None else
                                                                f" ({umf_fixed / umf_uniform - 1:+.1%})"), flush=True)
        print(f"{'z [m]':>7s} {'eps':>6s} {'wall':>6s} {'inner':>6s} {'-dp/dz':>9s} {'uniform':>9s} {'ratio':>6s} "
              f"{'w_wall/w_in':>11s}")
        for row in at_uniform["layers"]:
            ratio = row["pressure_gradient"] / row["closure_uniform_gradient"] if row["closure_uniform_gradient"] else float("nan")
            print(f"{row['z']:7.4f} {row['voidage']:6.3f} {row['voidage_wall']:6.3f} {row['voidage_interior']:6.3f} "
                  f"{row['pressure_gradient']:9.1f} {row['closure_uniform_gradient']:9.1f} {ratio:6.3f} "
                  f"{row['wall_over_interior_velocity']:11.3f}")
    png = _plot(Path(args.out) / "fixed_bed_layers.png", methods)
    result = {"case": args.case, "drag": model.drag, "packing_solids_fraction": packing["solids_fraction"],
              "bed_top": packing["bed_top"], "weight_per_area": weight, "methods": methods, "plot": str(png),
              "wall_seconds": time.perf_counter() - wall0}
    print(json.dumps(result) if args.json else json.dumps(result, indent=1))


def _plot(path, methods):
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(9, 4.5), sharey=True)
    for name, m in methods.items():
        rows = m["layers_at_closure_umf"]
        z = [r["z"] for r in rows]
        axes[0].plot([r["voidage"] for r in rows], z, "o-", ms=3, label=f"{name}: layer mean")
        axes[0].plot([r["voidage_wall"] for r in rows], z, ":", lw=1, color=axes[0].lines[-1].get_color(),
                     label=f"{name}: wall cells")
        full = [r for r in rows if r["closure_uniform_gradient"] > 0 and r["voidage"] < 0.9]  # not the surface cell
        axes[1].plot([r["pressure_gradient"] / r["closure_uniform_gradient"] for r in full], [r["z"] for r in full],
                     "o-", ms=3, label=f"{name}: fixed-bed Umf {m['relative_difference']:+.1%} from the closure's"
                     if m["relative_difference"] is not None else name)
    axes[0].set_xlabel("cell-layer voidage")
    axes[0].set_ylabel("z [m]")
    axes[1].axvline(1.0, color="k", lw=0.8)
    axes[1].set_xlim(0.6, 1.4)
    axes[1].set_xlabel("measured -dp/dz / uniform-bed closure at the layer voidage")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("frozen bed at the closure's uniform-bed Umf (layers below the partly filled surface cell)",
                 fontsize=9)
    return _save(fig, path)


if __name__ == "__main__":
    main()
