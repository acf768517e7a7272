"""Minimum fluidization velocity from a defluidization ramp (issue 5).

A shallow bed of Mema et al.'s particles (spheres, or AR-4 spherocylinders with single- or
multi-particle closures) in a narrow column with Mema et al.'s 15 mm cells is fluidized above Umf,
then the gas velocity is stepped down to about 0.4 Umf; each velocity is held and the bed pressure
drop averaged over the second half of the hold. Umf is where the fixed-bed branch (least-squares
``dP = a U + b U^2``, Ergun's form with a, b >= 0, through the lowest velocities up to the first
point at 0.85 W/A) meets the fluidized plateau
(the mean of the points at and above 1.3 x the experimental Umf, less those whose bed touched the roof,
``touched_roof``); ``umf_at_weight`` meets W/A itself. A slugging bed's pressure drop swings with the
plug's rise and fall, so each hold's mean is also given less what the bed's acceleration over the
averaged window owes it (``over_weight_acceleration_corrected``, from the particles' momentum balance;
``hold_statistics``), and the plateau of those (``plateau_over_weight_acceleration_corrected``); what
remains of the departure from W/A is the weight the walls carry (``walls_share_of_weight``, measured:
side-wall friction and the distributor). The inlet rises linearly from 0 over the start
(``--start``): a full-speed start lifts a packed bed as one plug. Start and holds are the case's inlet schedule
(``gas.inlet_ramp``, ``gas.inlet_steps``); the fits are ``fvdem.analysis.defluidization``'s.
Umf is a property of particles and gas, so a shallower bed than the paper's may be used: the output
says which bed was used (``--width 0.15 --particles 32500`` is the paper's own bed).

The output also separates the closure from the CFD-DEM solution: the packing of the defluidized bed
(core solids fraction, wall regions kept; mean sin^2 of the rods' angle from the vertical) and
``umf_closure_uniform_bed``, the velocity at which the drag closure alone holds a uniform bed of that
packing (``fvdem.analysis.bed.uniform_bed_umf``), next to Ergun's at the same packing. ``--drag gidaspow``
repeats the ramp with Gidaspow's closure (Ergun / Wen-Yu) instead of Mema et al.'s.

    python tools/validate_umf.py --shape sphere --json
    python tools/validate_umf.py --shape spherocylinder --closures mp --json
    python tools/validate_umf.py --shape sphere spherocylinder --drag paper beetstra --workers 2 --threads 1 --json

Several shapes or drag laws give one ramp each, run as tasks on fvdem's sweep engine (the Dask
clients of ``fvdem study``: ``--workers`` for a LocalCluster, ``--scheduler`` for a running one); each
ramp stays sequential. The last line is then ``{"ramps": [...], "plot": ..., "wall_seconds": ...}``.

Each ramp runs in its own run folder, ``OUT/ramp_<tag>`` (time series, a checkpoint every 0.05 s and at
a stop, the holds done in ``ramp.json``); ``--resume`` continues killed or stopped ramps from their last
checkpoint, bit for bit (a ramp of the paper's AR-4 bed takes hours). Ctrl-C or SIGTERM stop a ramp
with its checkpoint written (exit code 130).

``--rising`` measures the fluidization branch instead: the bed settled without gas first (``--preparation
friction``, as the study's beds settle; or ``frictionless``, denser, its friction given back for the ramp: the
screenings' "packing" factor), then the inlet stepped up from 0.4 to 2.0 Umf,exp from rest, each velocity held as
above. Umf is fitted the same way; the output gives the prepared bed's packing (``prepared_solids_fraction``,
``prepared_bed_height``) and the closure's uniform-bed Umf at it (``prepared_umf_closure_uniform_bed``: the end's
``umf_closure_uniform_bed`` is of the fluidized bed the ramp ends in). A settled bed's interlocking may hold the pressure drop
above W/A just past Umf (an overshoot): the fixed-bed branch ends at the first hold at 0.85 W/A, before it.

    python tools/validate_umf.py --rising --preparation frictionless --json

Prints progress, writes ``umf_<shape>[_<closures>].png`` (pressure drop over weight against U)
and, as the last line, one JSON object.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import fvdem
from fvdem.analysis.bed import bed_packing, uniform_bed_pressure_gradient, uniform_bed_umf
from fvdem.analysis.defluidization import FLUIDIZED_FROM, defluidization_steps, fit_umf, hold_statistics, plateau_of
from fvdem.analysis.plots import read_timeseries
from fvdem.case import case_from_dict
from fvdem.coupling.closures import law_names, spherocylinder_shape, sphericities
from fvdem.correlations import ergun_umf, quadratic_crossing, wen_yu_umf
from fvdem.dem.particles import spherocylinder_volume
from fvdem.scenes.observables import weight_per_area

EXPERIMENT = {"sphere": 1.58, "spherocylinder": 1.7}


SETTINGS = {"paper": {"normal_stiffness": 2.0e4, "dem_step": 1e-5, "cfd_step": 1e-4},
            "default": {"normal_stiffness": 800.0, "dem_step": 5e-5, "cfd_step": 5e-4}}


# the rising ramp's bed preparations: the contact settings it settles at (the ramp itself at the case's own)
PREPARATIONS = {"friction": {}, "frictionless": {"friction": 0.0, "rolling_friction": 0.0}}
RISING = [0.4, 0.5, 0.65, 0.75, 0.85, 0.95, 1.05, 1.15, 1.3, 1.45, 1.7, 2.0]  # x Umf,exp
FALLING = [2.0, 1.7, 1.45, 1.3, 1.15, 1.05, 0.95, 0.85, 0.75, 0.65, 0.5, 0.4]


def settled_state(table: dict, folder: Path, preparation: str) -> Path:
    """The ramp's bed settled without gas (``time.stop_when_settled``) at the ``preparation``'s contact settings,
    its ``final_state.npz`` in ``folder`` (kept: a resumed ramp settles nothing again; a settling killed midway
    continues from its checkpoint)."""
    state = folder / "final_state.npz"
    if state.exists():
        return state
    settle = json.loads(json.dumps(table))
    settle["name"] = f"settle_{preparation}"
    settle["gas"] = {"enabled": False}
    settle["coupling"] = {}
    settle["contact"].update(PREPARATIONS[preparation])
    settle["time"].update(end=3.0, stop_when_settled=True, settled_speed=0.005, min_time=0.3)
    settle["output"] = {"progress": False, "vtk": False, "checkpoint_interval": 0.05}
    resume = (folder / "checkpoint.npz").exists()
    fvdem.Simulation(case_from_dict(settle), folder, resume=resume, overwrite=not resume, progress=False).run()
    return state


def build_case(shape, closures, particles, threads, width=0.06, settings="paper", drag="paper"):
    return case_from_dict(reduced_bed_table(shape, closures, particles, threads, width, settings, drag))


def reduced_bed_table(shape, closures, particles, threads, width=0.06, settings="paper", drag="paper"):
    """Case table of the reduced bed (also tools/speed_accuracy.py's): Mema et al.'s particles (AR-1, or AR-4
    with SP or MP closures) in a ``width`` square column of 15 mm cells at 2 Umf,experiment, inserted
    below 0.2 m (higher when more particles than 2,000 per 0.06 x 0.06 m need the room); the column is
    0.45 m tall, or the insertion height + 0.3 m, or twice the insertion height, whichever is tallest
    (the paper's bed: its own 1.05 m column; at 0.82 m the bed rose to the roof at 2 Umf,exp and stayed
    pinned there, a plateau of 1.2-2.0 W/A). ``drag`` other than ``"paper"`` (a
    registered name, e.g. ``"gidaspow"`` or ``"tenneti"``) replaces the paper's drag closure, keeping
    lift and torque."""
    cells = max(1, round(width / 0.015))
    height = 0.2 * max(1.0, (0.06 / width) ** 2 * particles / 2000)
    column = max(0.45, *(0.015 * np.ceil(h / 0.015 - 1e-9) for h in (height + 0.3, 2.0 * height)))  # whole cells
    p = {"shape": shape, "count": particles, "density": 1442.0, "colour": "single",
         "insertion": {"upper": [width, width, height], "seed": 7}}
    coupling = {"drag": "hoelzer-sommerfeld"}
    if shape == "sphere":
        p["diameter"] = "5.3 mm"
    else:
        p.update(diameter="3 mm", length="12 mm")
        name = "sanjeevi-padding" if closures == "mp" else "zastawny"
        coupling = {"drag": "sanjeevi-padding" if closures == "mp" else "hoelzer-sommerfeld",
                    "lift": name, "torque": name}
    if drag != "paper":
        coupling["drag"] = drag
    k = SETTINGS[settings]
    return {
        "name": "umf",
        "domain": {"upper": [width, width, float(column)]},
        "particles": p,
        "contact": {"normal_stiffness": k["normal_stiffness"], "restitution": 0.43, "friction": 0.46,
                    "rolling_friction": 0.46},
        "time": {"dem_step": k["dem_step"], "end": 100.0},
        "gas": {"enabled": True, "cells": [cells, cells, int(round(column / 0.015))], "cfd_step": k["cfd_step"],
                "inlet_velocity": 2.0 * EXPERIMENT[shape]},
        "coupling": coupling,
        "output": {"progress": False, "timeseries_interval": 1e-3},
        "run": {"threads": threads}}


SAMPLE = 5e-4  # s between pressure-drop samples of a hold (the ramp's time series interval)


def _hold_entry(sim, folder, u, hold, weight, solid_volume, area):
    """One point of the curve: the hold's pressure drop (and the same corrected for the bed's
    acceleration over the averaged window, ``hold_statistics``) and, for the bed as it is at the end of
    the hold, the uniform bed of its core packing and equivalent height under the closure at this
    velocity (the CFD-DEM's own error, hold by hold). ``touched_roof``: the bed top came within a
    particle diameter of the roof during the averaged half of the hold (the roof then carries part of
    the bed, and the pressure drop is not the fluidized bed's)."""
    drop, spread, top, corrected, walls = hold_statistics(read_timeseries(folder), sim.time, hold, SAMPLE, area)
    roof = float(sim.case.domain.upper[2])
    size = 2.0 * float((sim.particles.radius + sim.particles.half_length).max())
    hold_packing = packed_state(sim)
    solid_height = solid_volume / area
    uniform = uniform_bed_pressure_gradient(sim.bridge.model, 1.0 - hold_packing["solids_fraction"], u,
                                            hold_packing["axes"]) * solid_height / hold_packing["solids_fraction"]
    return {"velocity": u, "pressure_drop": drop, "pressure_drop_std": spread,
            "over_weight": drop / weight,
            "over_weight_acceleration_corrected": None if corrected is None else corrected / weight,
            "walls_share_of_weight": None if walls is None else walls / (weight * area),
            "packed_solids_fraction": hold_packing["solids_fraction"],
            "closure_uniform_bed_over_weight": uniform / weight, "end_time": sim.time,
            "bed_top_max": top, "touched_roof": bool(top >= roof - size)}


class RampStopped(RuntimeError):
    """A ramp stopped by SIGINT/SIGTERM, its checkpoint written: ``--resume`` continues it."""


def _stopped(sim, tag):
    if sim.stopped_early:
        raise RampStopped(f"{tag}: stopped at t = {sim.time:.4f} s with its checkpoint written; the same command "
                          "with --resume continues the ramp")


def ramp(spec, threads=None):
    """One defluidization ramp (sequential by nature): ``spec`` a dict of this tool's options (shape,
    closures, particles, threads, width, settings, drag, hold, start, quick, out, resume). Returns the
    result object (see the module docstring). A module-level function, so that the sweep engine can run
    several ramps as tasks.

    The ramp runs in its own run folder (``OUT/ramp_<tag>``): a checkpoint every 0.05 s and at a stop,
    the holds done in ``ramp.json``. ``resume`` continues a killed or stopped ramp from its last
    checkpoint, inside a hold or the start, bit for bit; without it an existing folder is replaced."""
    o = dict(spec)
    wall0, cpu0 = time.perf_counter(), time.process_time()
    shape = o["shape"]
    umf_exp = EXPERIMENT[shape]
    tag = shape if shape == "sphere" else f"{shape}_{o['closures']}"
    if o["drag"] != "paper":
        tag += f"_{o['drag']}"
    rising = bool(o.get("rising"))
    if rising:
        tag += f"_rising_{o.get('preparation') or 'friction'}"
    table = reduced_bed_table(shape, o["closures"], o["particles"], o["threads"], o["width"], o["settings"],
                              o["drag"])
    if o.get("seed") is not None:  # another realization of the bed (replicas of a ramp)
        table["particles"]["insertion"]["seed"] = int(o["seed"])
    # checkpoints every 0.05 s and where run() ends (a stop); samples every SAMPLE s; no snapshots
    table["output"].update(timeseries_interval=SAMPLE, checkpoint_interval=0.05, vtk=False)
    ratios = list(RISING if rising else FALLING)
    if o["quick"]:
        ratios = [0.4, 0.7, 1.0, 1.3, 2.0] if rising else [2.0, 1.3, 1.0, 0.7, 0.4]
    start = 0.0 if rising else o["start"]  # a rising ramp starts from rest at its first velocity
    if rising:  # from the prepared bed, its friction the case's own
        prepared = settled_state(table, Path(o["out"]) / f"settle_{tag}", o.get("preparation") or "friction")
        table["particles"]["initial_state"] = str(prepared.resolve())
    # the fluidized holds (at and above 1.3 Umf,exp: the plateau) may be longer: a slugging bed's
    # pressure drop swings over ~0.5 s, so a 0.25 s hold averages a fraction of one swing
    plateau_hold = o.get("plateau_hold") or o["hold"]
    holds = [plateau_hold if ratio >= FLUIDIZED_FROM else o["hold"] for ratio in ratios]
    # the inlet rises linearly over the start (a full-speed start lifts the packed bed as one plug), then
    # steps down through the holds: the case's inlet schedule
    steps, ends = defluidization_steps(start, [ratio * umf_exp for ratio in ratios], holds)
    table["gas"].update(inlet_ramp=start, inlet_steps=[list(pair) for pair in steps])
    case = case_from_dict(table)
    folder = Path(o["out"]) / f"ramp_{tag}"
    progress_file = folder / "ramp.json"
    resume = bool(o.get("resume")) and (folder / "checkpoint.npz").exists() and progress_file.exists()
    sim = fvdem.Simulation(case, folder, resume=resume, overwrite=not resume, threads=o["threads"] or None,
                           progress=False)
    weight = weight_per_area(sim.model)
    box = case.domain
    area = float(np.prod(np.asarray(box.upper[:2]) - np.asarray(box.lower[:2])))
    solid_volume = float(spherocylinder_volume(sim.particles.radius, sim.particles.half_length).sum())
    record = json.loads(progress_file.read_text()) if resume else {"tag": tag}
    curve = record.get("curve", [])
    if not resume and rising:  # the prepared bed, before the gas moves it
        prepared = packed_state(sim)
        record["prepared"] = {k: float(prepared[k]) for k in ("solids_fraction", "bed_top")}
        record["prepared"]["umf_closure_uniform_bed"] = float(uniform_bed_umf(
            sim.bridge.model, 1.0 - prepared["solids_fraction"], prepared["axes"], case.particles.density))
    if resume:
        print(f"{tag}: resumed at t = {sim.time:.4f} s after {len(curve)} of {len(ratios)} holds", flush=True)
    else:  # from the first step on: a ramp stopped or killed inside its start resumes too
        progress_file.write_text(json.dumps({**record, "curve": curve}) + "\n")
    if sim.time < start - 0.5 * SAMPLE:  # the start (all of it, or its rest after a stop)
        sim.run(start - sim.time)
        _stopped(sim, tag)
        progress_file.write_text(json.dumps({**record, "curve": curve}) + "\n")
    for k in range(len(curve), len(ratios)):
        # a hold from its start, or its rest after a stop (a stop's checkpoint falls inside a hold; a
        # kill between a hold's end checkpoint and its record leaves nothing to run: the point is
        # completed from the time series and the restored bed); the case's schedule sets the inlet
        ratio, u = ratios[k], steps[k][1]
        if ends[k] - sim.time > 0.5 * SAMPLE:
            sim.run(ends[k] - sim.time)
            _stopped(sim, tag)
        curve.append(_hold_entry(sim, folder, u, holds[k], weight, solid_volume, area))
        tmp = progress_file.with_suffix(".tmp")
        tmp.write_text(json.dumps({**record, "curve": curve}) + "\n")
        tmp.replace(progress_file)
        c = curve[-1]
        print(f"{tag}: U = {u:.3f} m/s ({ratio:.2f} Umf_exp): pressure drop {c['pressure_drop']:.1f} Pa = "
              f"{c['over_weight']:.3f} W/A (+- {c['pressure_drop_std']:.1f}); core solids "
              f"{c['packed_solids_fraction']:.4f}, a uniform bed of it {c['closure_uniform_bed_over_weight']:.3f} W/A"
              + ("" if c.get("over_weight_acceleration_corrected") is None else
                 f"; {c['over_weight_acceleration_corrected']:.3f} W/A less the bed's acceleration")
              + ("" if c.get("walls_share_of_weight") is None else
                 f"; the walls carry {c['walls_share_of_weight']:+.3f} W")
              + ("; the bed touched the roof (left out of the plateau)" if c["touched_roof"] else ""),
              flush=True)
    velocity = [c["velocity"] for c in curve]
    drop = [c["pressure_drop"] for c in curve]
    roofed = [bool(c.get("touched_roof", False)) for c in curve]
    plateau, umf, (a, b) = fit_umf(velocity, drop, weight, umf_exp, roofed)
    # the fixed-bed branch against W/A itself rather than the measured plateau
    umf_at_weight = None if umf is None else quadratic_crossing(a, b, weight)
    # the same plateau with each hold's mean corrected for the bed's acceleration (hold_statistics)
    corrected = [c.get("over_weight_acceleration_corrected") for c in curve]
    plateau_corrected = umf_at_corrected = None
    if all(v is not None for v in corrected):
        plateau_corrected = plateau_of(velocity, np.asarray(corrected) * weight, umf_exp, roofed)
        umf_at_corrected = None if umf is None else quadratic_crossing(a, b, plateau_corrected)
    p = case.particles
    d_p = float(spherocylinder_shape(p.diameter, p.length or p.diameter)[0])
    phi = float(sphericities(p.diameter, p.length or p.diameter, 0.0)[0])
    packing = packed_state(sim)
    closure_umf = uniform_bed_umf(sim.bridge.model, 1.0 - packing["solids_fraction"], packing["axes"], p.density)
    png = Path(o["out"]) / f"umf_{tag}.png"
    _plot(png, velocity, drop, weight, plateau, umf, a, b, umf_exp, tag, "fluidization" if rising else "defluidization")
    # the defluidized bed, for tools/fixed_bed_layers.py --state (its structure without its motion)
    state = Path(o["out"]) / f"umf_{tag}_defluidized.npz"
    order = np.argsort(sim.particles.ids, kind="stable")
    np.savez(state, **{k: v[order] for k, v in sim.particles.as_dict().items()})
    return {
        "shape": shape, "closures": None if shape == "sphere" else o["closures"],
        "umf_simulated": umf, "umf_experiment": umf_exp,
        "relative_error": None if umf is None else (umf - umf_exp) / umf_exp,
        "plateau_over_weight": plateau / weight,
        "plateau_over_weight_acceleration_corrected": None if plateau_corrected is None else plateau_corrected / weight,
        "umf_at_corrected_plateau": umf_at_corrected,
        "umf_wen_yu": wen_yu_umf(d_p, p.density, case.gas.density, case.gas.viscosity, -case.domain.gravity[2]),
        "umf_at_weight": umf_at_weight,
        "drag": case.coupling.drag,
        "packed_solids_fraction": packing["solids_fraction"],
        "packed_bed_height": packing["bed_top"],
        "axis_sin2_from_vertical": packing["sin2"],
        "umf_closure_uniform_bed": closure_umf,
        "umf_ergun_at_packed_voidage": ergun_umf(d_p, p.density, 1.0 - packing["solids_fraction"], phi,
                                                 case.gas.density, case.gas.viscosity, -case.domain.gravity[2]),
        "bed": f"{p.count} particles in a {o['width']:g} x {o['width']:g} m column, 15 mm cells, packed height "
               f"{packing['bed_top']:.3f} m (the paper's bed: 32,500 in 0.15 x 0.15 m, about 0.2 m; Umf is a "
               "property of particles and gas)",
        "settings": o["settings"], "seed": table["particles"]["insertion"]["seed"],
        "direction": "rising" if rising else "falling",
        "preparation": (o.get("preparation") or "friction") if rising else None,
        "prepared_solids_fraction": record["prepared"]["solids_fraction"] if rising else None,
        "prepared_bed_height": record["prepared"]["bed_top"] if rising else None,
        "prepared_umf_closure_uniform_bed": record["prepared"].get("umf_closure_uniform_bed") if rising else None,
        "hold_seconds": o["hold"], "plateau_hold_seconds": plateau_hold,
        "column_height": float(case.domain.upper[2]), "inlet_ramp_seconds": start,
        "plateau_holds_touching_roof": sum(r for r, c in zip(roofed, curve)
                                           if c["velocity"] >= FLUIDIZED_FROM * umf_exp), "curve": curve, "plot": str(png), "defluidized_state": str(state),
        "wall_seconds": time.perf_counter() - wall0, "cpu_seconds": time.process_time() - cpu0,
    }


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--shape", nargs="+", choices=("sphere", "spherocylinder"), default=["sphere"],
                        help="one ramp per shape (and per --drag law)")
    parser.add_argument("--closures", choices=("sp", "mp"), default="mp", help="AR-4 closures (ignored for spheres)")
    parser.add_argument("--particles", type=int, default=2000)
    parser.add_argument("--hold", type=float, default=0.25, help="seconds at each velocity")
    parser.add_argument("--start", type=float, default=0.5, help="seconds fluidized before the ramp")
    parser.add_argument("--plateau-hold", type=float, help="seconds at each velocity at and above 1.3 Umf,exp "
                        "(the plateau; default: --hold): a slugging bed needs longer averages there")
    parser.add_argument("--quick", action="store_true", help="500 particles, short holds (a smoke test)")
    parser.add_argument("--threads", type=int, default=0)
    parser.add_argument("--width", type=float, default=0.06, help="column width [m] (a multiple of the 15 mm cells); "
                        "scale --particles with the cross-section to keep the bed height")
    parser.add_argument("--settings", choices=tuple(SETTINGS), default="paper",
                        help="contact stiffness, DEM and CFD steps: Mema et al.'s or fvdem's defaults")
    parser.add_argument("--drag", nargs="+", choices=("paper",) + tuple(n for n in law_names("drag") if n != "none"),
                        default=["paper"], help="drag closure(s): Mema et al.'s (Hoelzer-Sommerfeld + Di Felice, or "
                        "Sanjeevi-Padding for --closures mp) or any registered law (fvdem laws drag), lift and "
                        "torque kept; several give one ramp each")
    parser.add_argument("--workers", type=int, default=1, help="ramps side by side (several ramps only): Dask "
                        "LocalCluster workers, each ramp on --threads threads")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler to send the ramps to")
    parser.add_argument("--out", default=".")
    parser.add_argument("--resume", action="store_true",
                        help="continue killed or stopped ramps from their last checkpoint (OUT/ramp_<tag>)")
    parser.add_argument("--rising", action="store_true",
                        help="the fluidization branch: the bed settled first, the inlet stepped up from rest")
    parser.add_argument("--preparation", choices=tuple(PREPARATIONS),
                        help="with --rising: how the bed settles (friction: as the study's beds; frictionless: "
                             "denser, its friction given back for the ramp); default friction")
    parser.add_argument("--seed", type=int, help="the bed's insertion seed (default 7): replicas of a ramp")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--combine", nargs="+", metavar="OUTPUT",
                        help="draw saved outputs of this tool (their last lines) on one chart, run nothing")
    args = parser.parse_args(argv)
    if args.combine:
        Path(args.out).mkdir(parents=True, exist_ok=True)
        print(_combined_plot(Path(args.out) / "umf_compare.png", args.combine))
        return
    if args.preparation and not args.rising:
        parser.exit(2, f"--preparation {args.preparation}: only with --rising (a falling ramp starts fluidized: "
                       "its bed's preparation is gone before the first hold)\n")
    if args.quick:
        args.particles, args.hold, args.start = 500, 0.06, 0.15
    Path(args.out).mkdir(parents=True, exist_ok=True)  # before the ramp: its chart must not fail after it
    specs = [{"shape": shape, "closures": args.closures, "particles": args.particles, "threads": args.threads,
              "width": args.width, "settings": args.settings, "drag": drag, "hold": args.hold, "start": args.start,
              "quick": args.quick, "out": str(Path(args.out).resolve()), "resume": args.resume,
              "plateau_hold": args.plateau_hold, "rising": args.rising, "preparation": args.preparation,
              "seed": args.seed}
             for shape in args.shape for drag in args.drag]
    if len(specs) == 1:  # one ramp: in this process, its output as before
        try:
            result = ramp(specs[0])
        except RampStopped as exc:
            print(exc, file=sys.stderr)
            raise SystemExit(130) from None
        print(json.dumps(result) if args.json else json.dumps(result, indent=2))
        return
    # several ramps: tasks on fvdem's sweep engine (the Dask clients of fvdem study); each stays sequential
    from fvdem.study import map_tasks
    wall0 = time.perf_counter()
    names = [f"{s['shape']}-{s['drag']}" for s in specs]
    outcomes = map_tasks(ramp, specs, names, threads=args.threads, scheduler=args.scheduler, workers=args.workers,
                         log=lambda line: print(line, file=sys.stderr, flush=True))
    for name, outcome in zip(names, outcomes):
        if outcome["status"] == "failed":
            print(f"{name}: failed: {outcome['error']}", flush=True)
    result = {"ramps": [dict(o["value"], name=o["name"]) if o["value"] else {"name": o["name"], "error": o["error"]}
                        for o in outcomes], "wall_seconds": time.perf_counter() - wall0}
    if all(o["value"] for o in outcomes):
        result["plot"] = str(_combined_plot(Path(args.out) / "umf_compare.png", None,
                                            results=[o["value"] for o in outcomes]))
    print(json.dumps(result) if args.json else json.dumps(result, indent=2))
    if any(o["status"] == "failed" for o in outcomes):
        raise SystemExit(1)


def packed_state(sim):
    """The defluidized bed at the end of the ramp (``fvdem.analysis.bed.bed_packing``)."""
    box = sim.case.domain
    return bed_packing(sim.particles, box.lower, box.upper, box.periodic)


def _combined_plot(path, outputs, results=None):
    """Pressure drop / (W/A) against U / Umf,experiment of several ramps on one chart, each with its
    simulated Umf (dotted) and its closure's uniform-bed Umf at the ramp's packing (a triangle on 1).
    The ramps are saved outputs of this tool (their last lines) or ``results`` themselves."""
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7.5, 4.5 + 0.16 * len(results or outputs)))
    if results is None:
        results = [json.loads(Path(name).read_text().strip().splitlines()[-1]) for name in outputs]
    for r in results:
        exp = r["umf_experiment"]
        u = np.array([c["velocity"] for c in r["curve"]]) / exp
        shape = "AR-1" if r["shape"] == "sphere" else f"AR-4 {r['closures'].upper()}"
        width = r["bed"].split(" column")[0].split("in a ")[-1]
        found = r["umf_simulated"] is not None
        label = (f"{shape}, {r['drag']}, {r['bed'].split(' particles')[0]} in {width} ({r['settings']}): "
                 + (f"Umf {r['umf_simulated']:.2f} m/s ({r['relative_error']:+.0%})" if found else "no Umf found")
                 + (f", rising from a {r['preparation']} bed" if r.get("direction") == "rising" else "")
                 + (f"; W/A at {r['umf_at_weight']:.2f}" if r.get("direction") == "rising"
                    and r.get("umf_at_weight") is not None else ""))
        line, = ax.plot(u, [c["over_weight"] for c in r["curve"]], "o-", ms=3, label=label)
        if found:
            ax.axvline(r["umf_simulated"] / exp, color=line.get_color(), ls=":", lw=1)
        closure = (r.get("prepared_umf_closure_uniform_bed") if r.get("direction") == "rising"
                   else r["umf_closure_uniform_bed"])  # a rising ramp's: at the packing it starts from
        if closure is not None:
            ax.plot([closure / exp], [1.0], "v", color=line.get_color(), ms=8)
    ax.axvline(1.0, color="k", lw=1.2, label="Umf measured (1.58 m/s AR-1, 1.7 m/s AR-4)")
    ax.axvspan(0.9, 1.1, color="k", alpha=0.07, label="within 10 %")
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_xlabel("U / Umf,experiment")
    ax.set_ylabel("bed pressure drop / (W/A)")
    ax.set_title("ramps (falling unless said rising); triangles: the closure's Umf at the packing\n"
                 "(a falling ramp's end, a rising ramp's start)",
                 fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6.5, loc="upper center", bbox_to_anchor=(0.5, -0.14))  # below the axes: long labels
    return _save(fig, path)


def _plot(path, velocity, drop, weight, plateau, umf, a, b, umf_exp, tag, direction="defluidization"):
    from fvdem.analysis.plots import _pyplot, _save
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(velocity, np.asarray(drop) / weight, "o-", label=f"simulated ({direction})")
    u = np.linspace(0, max(velocity), 100)
    if umf is not None:
        ax.plot(u, np.minimum(a * u + b * u * u, plateau) / weight, "--", color="grey", label="fixed-bed fit / plateau")
        ax.axvline(umf, color="tab:red", ls=":", label=f"Umf simulated {umf:.2f} m/s")
    ax.axvline(umf_exp, color="k", ls="-.", lw=0.8, label=f"Umf experiment {umf_exp} m/s")
    ax.axhline(1.0, color="k", lw=0.5)
    ax.set_xlabel("superficial gas velocity U [m/s]")
    ax.set_ylabel("bed pressure drop / (W/A)")
    ax.set_title(f"{direction}, {tag}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    _save(fig, path)


if __name__ == "__main__":
    main()
