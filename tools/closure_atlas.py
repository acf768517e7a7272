"""Closure atlas: what every registered drag law predicts, without running a simulation (issue 18).

For each registered drag law (``fvdem laws drag``):

- **Umf of Mema et al.'s beds**: the superficial velocity at which the law alone holds a *uniform* bed of
  the packing of fvdem's settled beds (``cases/bed_ar1.toml``, ``cases/bed_ar4.toml``: core solids
  fraction and particle axes, recorded in ``tools/data/settled_beds.json`` by ``--measure-beds``),
  ``fvdem.analysis.bed.uniform_bed_umf``; beside Ergun's at the same packing (with the rods'
  sphericity) and the measured 1.58 (AR-1) and 1.7 m/s (AR-4).
- **Homogeneous hindered settling**: model A's balance of a particle in Derksen's force-balanced
  periodic box, ``c(u) u = (1 - phi) V_p (rho_p - rho) g`` (drag = weight less the mixture's buoyancy;
  averaged over isotropic orientations), solved for the interstitial slip ``u``; reported as the
  slip Reynolds number ``Re = (1 - phi) u d_e / nu`` that fvdem's suspension runs measure, at Ga = 864
  (on d) and Ga_e = 1296 (on d_e), for l/d = 1 (spheres), 2 and 4 (Derksen's cylinders as
  equal-volume spherocylinders) and phi = 0.1-0.48; beside Richardson-Zaki
  ``Re_t (1 - phi)^N``, ``N = 4.45 Re_t^-0.1``, with ``Re_t`` the isolated particle's terminal Re under
  Hoelzer-Sommerfeld (one reference curve for all laws).

A law the case checks refuse for a shape (Sanjeevi-Padding outside aspect ratio 4, say) is null there;
``outside_fitted_range`` lists the answers that lie outside the (Re, phi) range a law was fitted on.
Writes ``closure_atlas.png`` and prints one JSON object as the last line::

    python tools/closure_atlas.py --json --out docs/img
"""
from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parents[1]

from _beds import settled_beds, state_path  # noqa: E402
from fvdem.analysis.bed import uniform_bed_umf  # noqa: E402
from fvdem.analysis.suspension import richardson_zaki_exponent  # noqa: E402
from fvdem.case import CaseError, case_from_dict, load_case  # noqa: E402
from fvdem.correlations import ergun_umf  # noqa: E402
from fvdem.coupling.bridge import HydrodynamicModel  # noqa: E402
from fvdem.coupling.closures import law, law_names, sphericities, spherocylinder_shape  # noqa: E402

BEDS = ROOT / "tools" / "data" / "settled_beds.json"
MEASURED_UMF = {"ar1": 1.58, "ar4": 1.7}
BED_CASES = {"ar1": "cases/ar1.toml", "ar4": "cases/ar4_mp.toml"}
FRACTIONS = (0.1, 0.2, 0.29, 0.4, 0.48)
SHAPES = (1, 2, 4)  # l/d
GALILEO = {"ga_864": {"galileo": 864.0}, "ga_e_1296": {"galileo_equivalent": 1296.0}}
OUTSIDE: dict = {}  # law -> where its answer lies outside the range it was fitted on


def drag_laws() -> tuple:
    return tuple(n for n in law_names("drag") if n != "none")


# --------------------------------------------------------------------------- Umf of the paper's beds
def measure_beds(path=BEDS, sample=400) -> dict:
    """Record the packing of fvdem's settled beds (runs/bed_ar1, runs/bed_ar4: run the two cases first)."""
    from fvdem.analysis.bed import bed_packing
    from fvdem.dem.particles import ParticleArrays
    beds = {}
    for key, name in (("ar1", "bed_ar1"), ("ar4", "bed_ar4")):
        case = load_case(ROOT / "cases" / f"{name}.toml")
        with np.load(state_path(key)) as data:
            particles = ParticleArrays.from_dict({k: data[k] for k in data.files})
        d = case.domain
        packing = bed_packing(particles, d.lower, d.upper, d.periodic)
        axes = packing["axes"][np.random.default_rng(0).permutation(len(packing["axes"]))[:sample]]
        beds[key] = {"source": f"cases/{name}.toml, final state ({particles.count} particles, settled)",
                     "solids_fraction": round(float(packing["solids_fraction"]), 5),
                     "bed_top": round(float(packing["bed_top"]), 5), "sin2_from_vertical": packing["sin2"],
                     "axes": np.round(axes, 5).tolist()}
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(beds) + "\n")
    return beds


def bed_umf(beds: dict) -> dict:
    """Per bed: packing, Ergun's and the measured Umf, and each law's uniform-bed Umf (None if refused)."""
    out = {}
    for key, case_file in BED_CASES.items():
        case = load_case(ROOT / case_file, {"particles.initial_state": None})
        p, g = case.particles, case.gas
        length = p.length if p.shape != "sphere" else p.diameter
        eps = 1.0 - beds[key]["solids_fraction"]
        axes = np.asarray(beds[key]["axes"], float)
        sphericity = float(sphericities(p.diameter, length, 0.0)[0])
        d_p = float(spherocylinder_shape(p.diameter, length)[0])
        laws = {}
        for name in drag_laws():
            try:
                case_from_dict(_table(case_file), overrides={"coupling.drag": name, "coupling.lift": "none",
                                                             "coupling.torque": "none"})
            except CaseError:
                laws[name] = None
                continue
            model = HydrodynamicModel(name, "none", "none", p.diameter, length, g.density, g.viscosity)
            laws[name] = uniform_bed_umf(model, eps, axes, p.density)
            outside = law("drag", name).outside(g.density * d_p * laws[name] / g.viscosity, 1.0 - eps)
            if outside:
                OUTSIDE.setdefault(name, []).append(f"{key} Umf: " + ", ".join(outside))
        out[key] = {"solids_fraction": beds[key]["solids_fraction"], "measured": MEASURED_UMF[key],
                    "ergun": ergun_umf(d_p, p.density, eps, sphericity, g.density, g.viscosity), "laws": laws}
    return out


def _table(case_file):
    import tomllib
    table = tomllib.loads((ROOT / case_file).read_text())
    table["particles"].pop("initial_state", None)
    return table


# --------------------------------------------------------------------------- homogeneous hindered settling
def suspension_case(ratio, galileo, phi, drag):
    """Derksen's suspension (cases/hindered_settling.toml) at l/d ``ratio`` (1: spheres)."""
    import tomllib
    table = tomllib.loads((ROOT / "cases" / "hindered_settling.toml").read_text())
    s = table["suspension"]
    s.pop("galileo", None), s.pop("galileo_equivalent", None)
    s.update(GALILEO[galileo], solids_fraction=phi)
    if ratio == 1:
        s["particle"] = "sphere"
        s.pop("aspect_ratio", None)
    else:
        s["particle"], s["aspect_ratio"] = "cylinder", float(ratio)
    side = max(9, int(np.ceil(3.0 * (ratio + 1.0 / 3.0 + 0.1))))  # as tools/validate_hindered_settling.py
    s["box"], s["cells"] = [side, side, 2 * side], [max(3, round(side / 3))] * 2 + [2 * max(3, round(side / 3))]
    table["coupling"] = {"drag": drag}
    return case_from_dict(table)


def _isotropic_axes(n=200):
    axes = np.random.default_rng(0).normal(size=(n, 3))
    return axes / np.linalg.norm(axes, axis=1)[:, None]


def homogeneous_re(case, phi, axes):
    """Re = (1 - phi) u d_e / nu of model A's homogeneous balance (module docstring)."""
    p, g = case.particles, case.gas
    length = p.length if p.shape != "sphere" else p.diameter
    model = HydrodynamicModel(case.coupling.drag, "none", "none", p.diameter, length, g.density, g.viscosity)
    held = (1.0 - phi) * p.volume * (p.density - g.density) * 9.81
    eps = np.full(len(axes), 1.0 - phi)

    def excess(u):
        slip = np.zeros_like(axes)
        slip[:, 2] = u
        return float(np.mean(model.drag_coefficient(slip, eps, axes)) * u - held)

    u = brentq(excess, 1e-9, 100.0, xtol=1e-12, rtol=1e-10)
    return (1.0 - phi) * u * p.equivalent_diameter * g.density / g.viscosity


def hindered(fractions=FRACTIONS) -> dict:
    """Per Galileo number, l/d and law: Re at each phi; and the Richardson-Zaki reference."""
    axes = _isotropic_axes()
    out = {"laws": {}, "richardson_zaki": {}}
    for galileo in GALILEO:
        for ratio in SHAPES:
            reference = suspension_case(ratio, galileo, fractions[0], "hoelzer-sommerfeld")
            re_t = homogeneous_re(reference, 0.0, axes)
            n = richardson_zaki_exponent(re_t)
            out["richardson_zaki"].setdefault(galileo, {})[str(ratio)] = {
                "re_terminal": re_t, "n": n, "re": {f"{phi:g}": re_t * (1 - phi) ** n for phi in fractions}}
            for name in drag_laws():
                row = {}
                for phi in fractions:
                    try:
                        case = suspension_case(ratio, galileo, phi, name)
                    except CaseError:
                        row = None
                        break
                    row[f"{phi:g}"] = homogeneous_re(case, phi, axes)
                    outside = law("drag", name).outside(row[f"{phi:g}"], phi)
                    if outside:
                        OUTSIDE.setdefault(name, []).append(f"{galileo} l/d {ratio} phi {phi:g}: " + ", ".join(outside))
                out["laws"].setdefault(name, {}).setdefault(galileo, {})[str(ratio)] = row
    return out


# --------------------------------------------------------------------------- chart
def chart(result, path):
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    laws = list(result["laws"])
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    ax = axes[0]
    width = 0.8 / max(1, len(laws))
    for i, bed in enumerate(("ar1", "ar4")):
        b = result["beds"][bed]
        for k, name in enumerate(laws):
            value = result["laws"][name]["umf"][bed]
            if value is not None:
                ax.bar(i + (k - (len(laws) - 1) / 2) * width, value, width, color=f"C{k}",
                       label=name if i == 0 or bed == "ar4" and result["laws"][name]["umf"]["ar1"] is None else None)
        ax.hlines(b["measured"], i - 0.45, i + 0.45, colors="k", lw=2)
        ax.hlines(b["ergun"], i - 0.45, i + 0.45, colors="k", linestyles="--", lw=1)
    ax.set_xticks([0, 1], [f"AR-1 (solids {result['beds']['ar1']['solids_fraction']:.3f})",
                           f"AR-4 (solids {result['beds']['ar4']['solids_fraction']:.3f})"])
    ax.set_ylabel("uniform-bed Umf [m/s]")
    ax.set_title("Mema et al.'s beds: measured (-), Ergun (--)", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, axis="y")
    for ax, galileo, title in ((axes[1], "ga_864", "Ga = 864 (on d)"), (axes[2], "ga_e_1296", "Ga_e = 1296 (on d_e)")):
        for ratio, marker in zip(SHAPES, ("o", "s", "^")):
            rz = result["richardson_zaki"][galileo][str(ratio)]
            phi = np.array([float(k) for k in rz["re"]])
            ax.plot(1 - phi, list(rz["re"].values()), "k:", lw=1)
            for k, name in enumerate(laws):
                row = result["laws"][name]["hindered"][galileo][str(ratio)]
                if row is not None:
                    ax.plot(1 - phi, list(row.values()), marker + "-", color=f"C{k}", ms=4, lw=1,
                            label=f"{name}, l/d {ratio}" if ratio == 2 or name == laws[0] else None)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("1 - phi")
        ax.set_ylabel("slip Reynolds number Re")
        ax.set_title(f"homogeneous settling, {title}; Richardson-Zaki (:)\nl/d 1 (o), 2 (s), 4 (^)", fontsize=9)
        ax.grid(alpha=0.3, which="both")
    axes[2].legend(fontsize=6)
    return _save(fig, path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default=".", help="folder for closure_atlas.png")
    parser.add_argument("--json", action="store_true", help="one JSON object as the last line")
    parser.add_argument("--beds", type=Path, default=BEDS, help="the settled beds' packing (JSON)")
    parser.add_argument("--measure-beds", action="store_true",
                        help="record the settled beds' packing in --beds (runs/bed_ar1 and runs/bed_ar4, settled "
                             "first when missing)")
    parser.add_argument("--quick", action="store_true", help="the same atlas (it takes seconds already)")
    parser.add_argument("--solids-fraction", type=float, nargs="+", metavar="PHI", default=[],
                        help="each law's uniform-bed Umf also at these packings (the beds' recorded axes): e.g. "
                             "the packing a simulated bed defluidized at, where the solver meets its closure")
    args = parser.parse_args(argv)
    if any(not 0.0 < phi < 0.74 for phi in args.solids_fraction):
        parser.error(f"--solids-fraction {args.solids_fraction}: each between 0 and 0.74 (a packing of spheres "
                     "or rods)")
    if args.measure_beds:
        settled_beds(["ar1", "ar4"], "closure_atlas")
    wall0, cpu0 = time.perf_counter(), time.process_time()
    beds = measure_beds(args.beds) if args.measure_beds else json.loads(args.beds.read_text())
    with warnings.catch_warnings():  # the root finders try far outside the ranges: judged at the answers
        warnings.simplefilter("ignore", RuntimeWarning)
        umf = bed_umf(beds)
        at_packing = {f"{phi:g}": {name: {bed: entry["laws"][name] for bed, entry in
                                          bed_umf({k: {**b, "solids_fraction": phi} for k, b in beds.items()}).items()}
                                   for name in drag_laws()} for phi in args.solids_fraction}
        settling = hindered()
    result = {"beds": {k: {kk: v for kk, v in b.items() if kk != "laws"} for k, b in umf.items()},
              "richardson_zaki": settling["richardson_zaki"],
              "laws": {name: {"umf": {bed: umf[bed]["laws"][name] for bed in umf},
                              "hindered": settling["laws"][name]} for name in drag_laws()},
              "umf_at_solids_fraction": at_packing,
              "outside_fitted_range": OUTSIDE,
              "wall_seconds": None, "cpu_seconds": None}
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    result["chart"] = str(chart(result, out / "closure_atlas.png"))
    result["wall_seconds"] = time.perf_counter() - wall0
    result["cpu_seconds"] = time.process_time() - cpu0  # the atlas's own cost, whatever else runs beside it
    for name, entry in result["laws"].items():
        cells = [f"{bed} {v:.3f} m/s ({100 * (v / MEASURED_UMF[bed] - 1):+.0f} %)" if v is not None else f"{bed} -"
                 for bed, v in entry["umf"].items()]
        row = entry["hindered"]["ga_e_1296"]["2"]
        print(f"{name:20s} Umf {', '.join(cells)}; Re(phi 0.2, l/d 2, Ga_e 1296) "
              + (f"{row['0.2']:.2f}" if row else "-"))
    for phi, laws in at_packing.items():
        print(f"at solids fraction {phi}: " + "; ".join(
            f"{name} " + ", ".join(f"{bed} {v:.3f}" if v is not None else f"{bed} -" for bed, v in by_bed.items())
            for name, by_bed in laws.items()))
    if args.json:
        print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
