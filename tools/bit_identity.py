"""Bit-identity of the coupled step across code changes: five small coupled cases, each advanced a few
tenths of a second, every array of the model's state (particles, gas, bridge) hashed; two such records
compared array by array.

A refactoring that must move nothing bit for bit is checked by running this in a worktree of the base
commit and in the new tree, then comparing::

    git worktree add /tmp/base <base-commit>
    (cd /tmp/base && PYTHONPATH=$PWD python /path/to/tools/bit_identity.py --out /tmp/base.json)
    python tools/bit_identity.py --out /tmp/new.json
    python tools/bit_identity.py --compare /tmp/base.json /tmp/new.json      # exit 1 when anything differs

``--quick --json`` records one case over five coupling intervals as one JSON line (the suite's smoke run).

The tool only uses ``load_case``, ``Simulation`` and ``Model.state()``, which every commit since 0.2 has,
so the same file runs against an older tree (keep its path outside that tree on ``PYTHONPATH``'s side:
the base tree's ``fvdem`` must be the one imported). Arrays present in only one record (e.g. a state
added by a new feature that is off) are listed, not counted as differences.

The five cases cover the coupled step's branches: spheres with the semi-implicit drag; spheres with the
explicit drag, Stokes rotational drag and one-way coupling off the pressure-gradient force; AR-4 rods
with the multi-particle drag, lift and torque (``sanjeevi-padding``) and the smoothed voidage; AR-4 rods
with the single-particle closures (``hoelzer-sommerfeld`` + ``zastawny``); the periodic liquid
suspension (``cases/hindered_settling.toml``). A fixed bed (``particles.fixed``) is the sixth.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
SMALL = {"output.progress": False, "output.snapshot_interval": 100.0, "output.checkpoint_interval": 100.0,
         "output.timeseries_interval": 100.0, "run.threads": 1}
ROD = {"particles.shape": "spherocylinder", "particles.diameter": 0.003, "particles.length": 0.012,
       "particles.count": 1500, "particles.insertion.upper": [0.06, 0.06, 0.3]}
CASES = {
    "spheres_semi_implicit": ("coupled_small.toml", {}, 0.2),
    "spheres_explicit_stokes_oneway": ("coupled_small.toml", {"coupling.drag_treatment": "explicit",
                                                              "coupling.rotational_drag": "stokes",
                                                              "coupling.pressure_gradient_force": False,
                                                              "coupling.two_way": False}, 0.2),
    "rods_multi_particle": ("coupled_small.toml", {**ROD, "coupling.drag": "sanjeevi-padding",
                                                   "coupling.lift": "sanjeevi-padding",
                                                   "coupling.torque": "sanjeevi-padding"}, 0.2),
    "rods_single_particle": ("coupled_small.toml", {**ROD, "coupling.drag": "hoelzer-sommerfeld",
                                                    "coupling.lift": "zastawny", "coupling.torque": "zastawny"}, 0.2),
    "suspension": ("hindered_settling.toml", {}, None),
    "fixed_bed": ("coupled_small.toml", {"particles.fixed": True}, 0.2),
}


def digest(array) -> str:
    array = np.ascontiguousarray(np.asarray(array))
    return hashlib.sha256(str(array.dtype).encode() + str(array.shape).encode() + array.tobytes()).hexdigest()


def record(names, quick: bool = False) -> dict:
    from fvdem import Simulation
    from fvdem.case import load_case
    import fvdem
    print(f"fvdem from {Path(fvdem.__file__).parent}", file=sys.stderr)
    out = {}
    for name in names:
        file, overrides, duration = CASES[name]
        case = load_case(ROOT / "cases" / file, {**SMALL, **overrides})
        sim = Simulation(case, progress=False)
        if duration is None:  # the suspension: a tenth of its viscous time scale's worth of steps
            duration = 20 * sim.time_step
        if quick:  # a smoke test of the tool: a few coupling intervals
            duration = 5 * sim.time_step
        sim.run(duration)
        state = sim.model.state()
        out[name] = {"steps": int(sim.step_count), "time": float(sim.time),
                     "arrays": {key: digest(value) for key, value in sorted(state.items())
                                if isinstance(value, np.ndarray) or np.isscalar(value)}}
        print(f"{name}: {out[name]['steps']} steps, {len(out[name]['arrays'])} arrays", file=sys.stderr)
    return out


def compare(a: dict, b: dict) -> list[str]:
    lines, differ = [], 0
    for name in sorted(set(a) | set(b)):
        if name not in a or name not in b:
            lines.append(f"{name}: only in {'the second' if name in b else 'the first'} record")
            continue
        ra, rb = a[name], b[name]
        if ra["steps"] != rb["steps"]:
            lines.append(f"{name}: {ra['steps']} against {rb['steps']} steps")
            differ += 1
        keys = set(ra["arrays"]) | set(rb["arrays"])
        changed = sorted(k for k in keys if k in ra["arrays"] and k in rb["arrays"] and ra["arrays"][k] != rb["arrays"][k])
        only = sorted(keys - (set(ra["arrays"]) & set(rb["arrays"])))
        differ += len(changed)
        lines.append(f"{name}: {len(keys) - len(only) - len(changed)} arrays identical, {len(changed)} differ"
                     + (f" ({', '.join(changed)})" if changed else "")
                     + (f"; in one record only: {', '.join(only)}" if only else ""))
    lines.append("IDENTICAL" if differ == 0 else f"DIFFERENT: {differ} differences")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", help="write the record (JSON) here")
    parser.add_argument("--cases", nargs="+", choices=sorted(CASES), default=sorted(CASES))
    parser.add_argument("--compare", nargs=2, metavar=("BASE", "NEW"), help="compare two records; exit 1 if any differ")
    parser.add_argument("--quick", action="store_true", help="one case for five coupling intervals (a smoke test)")
    parser.add_argument("--json", action="store_true", help="print the record as one JSON line")
    args = parser.parse_args(argv)
    if args.compare:
        a, b = (json.loads(Path(p).read_text()) for p in args.compare)
        lines = compare(a, b)
        print("\n".join(lines))
        return 0 if lines[-1] == "IDENTICAL" else 1
    result = record(["spheres_semi_implicit"] if args.quick else args.cases, args.quick)
    text = json.dumps(result, indent=1, sort_keys=True)
    if args.out:
        Path(args.out).write_text(text + "\n")
    if args.json:
        print(json.dumps(result, sort_keys=True))
    elif not args.out:
        print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
