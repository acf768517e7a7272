"""Where each method fails, found by sweeping (issue 7, part 2).

Three maps, each swept rather than assumed, with the boundary found and the theory it should match:

- ``dem``: a head-on binary collision of two seed-000 spheres at DEM steps ``dt = t_c / N``:
  restitution error and whether the contact is resolved. Theory: velocity Verlet on a linear
  spring is stable for ``w dt < 2`` (``dt < 2 t_c / pi`` undamped); fvdem refuses ``dt > t_c / 2``
  outright and a case above ``t_c / 10``.
- ``drag``: one particle relaxing to its terminal velocity with the drag held over the coupling
  step (explicit) or integrated implicitly (semi-implicit), at ``dt / tau_p`` from 0.5 to 20,
  ``tau_p = m / c`` at the terminal state. Theory: explicit (forward Euler) diverges beyond
  ``dt = 2 m / (dF/dv)``, slightly below ``2 tau_p`` because the drag grows faster than linearly
  with the slip (``dF/dv = c (1 + dln c / dln v)``); semi-implicit never.
- ``cfd``: the gas column of the reduced bed, empty and through a fixed bed, at CFD steps giving
  inlet Courant numbers ``U dt / dx`` from 0.5 to 3. Theory: the implicit parts are unconditionally
  stable, the explicit ones (old-flux Rhie-Chow correction, exchange return) limit the Courant
  number, so the failure sits at one Courant number for every velocity. fvdem refuses an inlet
  Courant number above 1 in the case file and warns at run time when a cell's exceeds 1.
- ``voidage``: the largest voidage change of a cell while one particle crosses a cell face in small
  steps, for each voidage method and cell size / particle length. Theory: ``V_p / V_cell``
  (centroid), ``V_p / (satellites V_cell)`` (divided), continuous (trilinear).

    python tools/stability_map.py --json [--quick]

Writes ``stability_<map>.png`` and prints, as the last line, one JSON object with every point and
the boundaries found.
"""
from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

from fvdem.case import Case
from fvdem.coupling import closures
from fvdem.coupling.bridge import particle_response
from fvdem.coupling.voidage import voidage
from fvdem.dem.particles import ParticleArrays
from fvdem.dem.system import Box, ContactModel, DEMSystem, SimulationError
from fvdem.gas.mesh import GasMesh

GAS = Case().gas  # the gas of every map: a case's default (air), as the cfd map's column has it


# --------------------------------------------------------------------------- DEM step vs collision time
def dem_map(divisors):
    contact = ContactModel(normal_stiffness=2.0e4)  # the seed's spring (Mema et al. (2020) Table 5)
    d = 5.3e-3
    points = []
    for n in divisors:
        particles = ParticleArrays.create(np.array([[0.05, 0.05, 0.05], [0.05 + d * 1.001, 0.05, 0.05]]), d / 2, 0.0,
                                          1442.0, velocity=np.array([[0.5, 0, 0], [-0.5, 0, 0]]))
        tc = contact.collision_time(float(particles.mass[0]))
        dt = tc / n
        point = {"dt_over_collision_time": 1.0 / n}
        try:
            system = DEMSystem(particles, Box((0, 0, 0), (0.1, 0.1, 0.1), (True, True, True)), contact, dt, (0, 0, 0))
        except SimulationError as exc:
            point.update(status="refused", reason=str(exc))
            points.append(point)
            continue
        max_overlap = 0.0
        for _ in range(int(20 * n) + 50):
            system.step()
            max_overlap = max(max_overlap, system.diagnostics()["max_overlap_over_diameter"])
        v = system.particles.velocity[np.argsort(system.particles.ids)]
        restitution = float((v[1, 0] - v[0, 0]) / 1.0)
        point.update(status="ran", restitution=restitution, restitution_error=restitution / contact.restitution - 1.0,
                     max_overlap_over_diameter=max_overlap)
        points.append(point)
    ran = [p for p in points if p["status"] == "ran"]
    accurate = [p["dt_over_collision_time"] for p in ran if abs(p["restitution_error"]) < 0.01]
    return {"points": points, "largest_dt_within_1_percent": max(accurate) if accurate else None,
            "refused_above": min((p["dt_over_collision_time"] for p in points if p["status"] == "refused"), default=None),
            "case_file_limit": 0.1, "theory_undamped_stability": 2 / math.pi}


# --------------------------------------------------------------------------- drag treatment vs response time
def drag_map(ratios, steps=200):
    """Particle (20 um sphere) starting at rest in still gas; drag linearised at its terminal state.
    Explicit: v_{k+1} = v_k + dt (g - c v_k / m) with c from the closure at the current slip;
    semi-implicit: the kicks' closed form with the same c (what fvdem's kicks do)."""
    d = 2e-5
    m = 1442.0 * math.pi / 6 * d ** 3

    def coefficient(speed):
        slip = np.array([[0, 0, max(speed, 1e-12)]])
        return float(closures.single_particle_drag_coefficient(slip, 1.0, d, GAS.density, GAS.viscosity)[0])

    v_t = m * 9.81 / coefficient(0.0)
    for _ in range(50):
        v_t = m * 9.81 / coefficient(v_t)
    tau = m / coefficient(v_t)
    points = []
    for ratio in ratios:
        dt = ratio * tau
        result = {"dt_over_response_time": ratio}
        for scheme in ("explicit", "semi-implicit"):
            v = 0.0
            for _ in range(steps):
                c = coefficient(abs(v))
                if scheme == "explicit":
                    v = v + dt * (9.81 - c * v / m)
                else:
                    one_minus_r, k = particle_response(np.array([m]), np.array([c]), dt / 10, 10)
                    v = v + one_minus_r[0] * (0.0 - v) + 9.81 * k[0] * dt + 9.81 * dt  # v0 + (J + m g dt) / m
                if not math.isfinite(v) or abs(v) > 1e6 * v_t:
                    break
            error = abs(v / v_t - 1.0) if math.isfinite(v) else float("inf")
            # it starts at rest (error 1): stable if the error has shrunk, unstable if it has grown
            result[scheme] = {"final_error": error, "stable": bool(error < 1.0)}
        points.append(result)
    explicit_unstable = [p["dt_over_response_time"] for p in points if not p["explicit"]["stable"]]
    return {"points": points, "response_time": tau, "terminal_velocity": v_t,
            "explicit_unstable_from": min(explicit_unstable) if explicit_unstable else None,
            "semi_implicit_unstable_from": min((p["dt_over_response_time"] for p in points
                                                if not p["semi-implicit"]["stable"]), default=None),
            "theory_explicit": 2.0}


# --------------------------------------------------------------------------- voidage jumps
def voidage_map(cell_over_length, samples=200):
    """AR-4 rod (d 3 mm, L 12 mm) moved along x across a cell face, axis along x."""
    diameter, length = 3e-3, 12e-3
    points = []
    for ratio in cell_over_length:
        cell = ratio * length
        mesh = GasMesh.box((4, 1, 1), (0, 0, 0), (4 * cell, cell, cell))
        volume = math.pi / 4 * diameter ** 2 * (length - diameter) + math.pi / 6 * diameter ** 3
        for method in ("centroid", "divided", "trilinear"):
            path = np.linspace(1.0 * cell, 3.0 * cell, samples)
            previous, largest = None, 0.0
            for x in path:
                particles = ParticleArrays.create(np.array([[x, 0.5 * cell, 0.5 * cell]]), diameter / 2,
                                                  (length - diameter) / 2, 1442.0, axis=np.array([[1.0, 0, 0]]))
                eps, _ = voidage(particles, mesh, method, minimum=0.0)
                if previous is not None:
                    largest = max(largest, float(np.abs(eps - previous).max()))
                previous = eps
            step_change = volume / cell ** 3 * (path[1] - path[0]) / cell  # what smooth motion alone changes
            points.append({"cell_over_length": ratio, "method": method,
                           "largest_jump_over_particle_fraction": largest / (volume / cell ** 3),
                           "smooth_limit": step_change / (volume / cell ** 3)})
    return {"points": points,
            "theory": {"centroid": 1.0, "divided": 0.2, "trilinear": "continuous (jump -> 0 with the step)"}}


# --------------------------------------------------------------------------- CFD step vs Courant number
def _column_case(cfd_step, velocity, particles):
    """The column validated at a CFD step the case check accepts, then given ``cfd_step`` (which it may
    refuse: the map looks for where the solver itself fails)."""
    from dataclasses import replace
    from fvdem.case import case_from_dict
    case = case_from_dict({
        "name": "courant", "domain": {"upper": [0.06, 0.06, 0.45]},
        "particles": {"shape": "sphere", "count": particles, "diameter": "5.3 mm", "density": 1442.0,
                      "colour": "single", "fixed": True, "insertion": {"upper": [0.06, 0.06, 0.2], "seed": 7}},
        "gas": {"enabled": True, "cells": [4, 4, 30], "cfd_step": 1e-5, "inlet_velocity": velocity},
        "time": {"dem_step": 1e-5},
        "coupling": {"drag": "hoelzer-sommerfeld"}, "output": {"progress": False}, "run": {"threads": 1}})
    return replace(case, gas=replace(case.gas, cfd_step=cfd_step))


def cfd_map(courants, scenes=((3.16, 0), (10.0, 0), (1.5, 1000)), steps=100):
    """The gas column of the reduced bed (0.06 x 0.06 x 0.45 m, 15 mm cells) at CFD steps giving inlet
    Courant numbers ``U dt / dx`` in ``courants``: empty at two inlet velocities, and through a fixed
    bed of 1,000 spheres, each for ``steps`` steps. The case-file check (it refuses inlet Courant
    numbers above 1) is bypassed to find where the solver itself fails. Theory: implicit upwind
    convection with implicit pressure is unconditionally stable; the explicit parts (the old-flux
    Rhie-Chow correction, the exact-exchange return) are not, so a failure must scale with the
    Courant number: at the same ``U dt / dx`` for every velocity."""
    import warnings
    from fvdem.simulation import Simulation
    points = []
    for velocity, particles in scenes:
        for courant in courants:
            dt = courant * 0.015 / velocity
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                sim = Simulation(_column_case(dt, velocity, particles))
                largest, status, reason = 0.0, "stable", None
                with np.errstate(all="ignore"):
                    try:
                        for _ in range(steps):
                            sim.run(dt)
                            largest = max(largest, sim.gas.courant_number())
                    except SimulationError as exc:
                        status, reason = "diverged", str(exc)
            points.append({"inlet_velocity": velocity, "particles": particles, "inlet_courant": courant,
                           "cfd_step": dt, "largest_cell_courant": largest if status == "stable" else None,
                           "status": status, "reason": reason})
    boundaries = {}
    for velocity, particles in scenes:
        pts = [p for p in points if p["inlet_velocity"] == velocity and p["particles"] == particles]
        failed = [p["inlet_courant"] for p in pts if p["status"] == "diverged"]
        stable = [p["inlet_courant"] for p in pts if p["status"] == "stable"
                  and (not failed or p["inlet_courant"] < min(failed))]
        boundaries[f"U={velocity:g} m/s, {particles} fixed particles"] = {
            "largest_stable": max(stable) if stable else None, "diverged_from": min(failed) if failed else None,
            "largest_stable_cell_courant": max((p["largest_cell_courant"] for p in pts if p["status"] == "stable"
                                                and p["inlet_courant"] in stable), default=None)}
    return {"points": points, "boundaries": boundaries, "case_file_limit": 1.0, "runtime_warning_cell_courant": 1.0}


# --------------------------------------------------------------------------- plots and main
def _plots(out, dem, drag, void, cfd=None):
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    paths = []
    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    ran = [p for p in dem["points"] if p["status"] == "ran"]
    ax.semilogx([p["dt_over_collision_time"] for p in ran], [100 * abs(p["restitution_error"]) for p in ran], "o-")
    for p in dem["points"]:
        if p["status"] == "refused":
            ax.axvspan(p["dt_over_collision_time"], 1.0, color="tab:red", alpha=0.15)
    ax.axvline(0.1, color="k", ls=":", label="case-file limit t_c/10")
    ax.set_xlabel("DEM step / collision time")
    ax.set_ylabel("restitution error [%]")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    paths.append(_save(fig, Path(out) / "stability_dem.png"))

    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    ratios = [p["dt_over_response_time"] for p in drag["points"]]
    for scheme, marker in (("explicit", "s"), ("semi-implicit", "o")):
        errors = [min(p[scheme]["final_error"], 1e6) for p in drag["points"]]
        ax.loglog(ratios, np.maximum(errors, 1e-16), marker + "-", label=scheme)
    ax.axvline(2.0, color="k", ls=":", label="theory: explicit unstable beyond 2")
    ax.set_xlabel("coupling step / particle response time")
    ax.set_ylabel("|v / v_t - 1| after 200 steps (from rest: 1)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    paths.append(_save(fig, Path(out) / "stability_drag.png"))

    fig, ax = plt.subplots(figsize=(5.5, 3.8))
    for method in ("centroid", "divided", "trilinear"):
        pts = [p for p in void["points"] if p["method"] == method]
        ax.plot([p["cell_over_length"] for p in pts], [p["largest_jump_over_particle_fraction"] for p in pts],
                "o-", label=method)
    ax.set_xlabel("cell size / particle length")
    ax.set_ylabel("largest voidage jump / (V_p / V_cell)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    paths.append(_save(fig, Path(out) / "stability_voidage.png"))

    if cfd is not None:
        fig, ax = plt.subplots(figsize=(5.5, 3.8))
        scenes = sorted({(p["inlet_velocity"], p["particles"]) for p in cfd["points"]})
        for k, (velocity, particles) in enumerate(scenes):
            pts = [p for p in cfd["points"] if p["inlet_velocity"] == velocity and p["particles"] == particles]
            for p in pts:
                ax.scatter(p["inlet_courant"], k, marker="o" if p["status"] == "stable" else "x",
                           color="tab:green" if p["status"] == "stable" else "tab:red")
        ax.set_yticks(range(len(scenes)), [f"U {v:g} m/s, {n} fixed" for v, n in scenes], fontsize=7)
        ax.axvline(1.0, color="k", ls=":", label="case-file limit (refused above)")
        ax.set_xlabel("inlet Courant number U dt / dx  (o stable, x diverged)")
        ax.legend(fontsize=8)
        ax.grid(alpha=0.3)
        fig.tight_layout()
        paths.append(_save(fig, Path(out) / "stability_cfd.png"))
    return [str(p) for p in paths]


def run(quick=False, out="."):
    wall0, cpu0 = time.perf_counter(), time.process_time()
    divisors = [50, 14, 10, 5, 3, 2.2, 1.9, 1.5] if not quick else [14, 3, 1.9]
    ratios = [0.5, 1.0, 1.5, 1.8, 1.95, 2.05, 2.2, 3.0, 5.0, 10.0, 20.0] if not quick else [0.5, 1.9, 2.1, 5.0]
    lengths = [0.75, 1.25, 2.0, 3.0] if not quick else [1.25]
    courants = [0.5, 1.0, 1.2, 1.4, 1.6, 2.0, 3.0] if not quick else [1.0, 1.6]
    dem, drag, void = dem_map(divisors), drag_map(ratios), voidage_map(lengths, 200 if not quick else 60)
    cfd = cfd_map(courants, steps=100 if not quick else 60)
    plots = _plots(out, dem, drag, void, cfd)
    return {"dem": dem, "drag": drag, "voidage": void, "cfd": cfd, "plots": plots,
            "wall_seconds": time.perf_counter() - wall0, "cpu_seconds": time.process_time() - cpu0}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fewer points (a smoke test, seconds)")
    parser.add_argument("--out", default=".")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    result = run(args.quick, args.out)
    d = result["drag"]
    print(f"explicit drag unstable from dt/tau = {d['explicit_unstable_from']} (theory 2); semi-implicit: "
          f"{d['semi_implicit_unstable_from'] or 'stable everywhere'}", flush=True)
    print(json.dumps(result) if args.json else json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
