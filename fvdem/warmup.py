"""Compile fvdem's numba kernels into numba's on-disk cache ahead of the first run (``fvdem compile``).

fvdem's kernels are cached numba functions (``cache=True``): the first run after an install or an upgrade
compiles them, about 4 minutes of one core for a coupled case on a 2-core AMD EPYC (Zen 1, 2026-12-06), most
of it two kernels (the contact forces, about 110 s, a third less since its row is inlined once, and the
particle-to-grid map, about 60 s). Every process
that needs a kernel before the cache holds it compiles it too: the Dask workers of a first study, the jobs of a
first SLURM array, all at once. ``compile_kernels`` runs small scenes
of every kind the shipped cases run (spheres and AR-4 rods fluidized with the paper's closures, drag only, the
settling beds, the gas through a fixed bed, the periodic liquid suspension) for a few steps each, in two
processes (``CHAINS``), so that each kernel is compiled once and every later process loads it. Where every
kernel is cached it takes about 10 s (the imports).

numba's cache is keyed by the source file and the CPU: run it on the kind of machine the runs use (a compute
node, not a login node of another CPU) and again after editing a kernel's file.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor

_SPHERES = {"shape": "sphere", "count": 150, "diameter": "5.3 mm", "density": 1442.0, "colour": "by_height",
            "insertion": {"upper": [0.06, 0.06, 0.1], "seed": 1}}
_RODS = {"shape": "spherocylinder", "count": 150, "diameter": "3 mm", "length": "12 mm", "density": 1442.0,
         "colour": "by_height", "insertion": {"upper": [0.06, 0.06, 0.1], "orientation": "random", "seed": 1}}
_CONTACT = {"normal_stiffness": 2.0e4, "restitution": 0.43, "friction": 0.46, "rolling_friction": 0.46}
_GAS = {"enabled": True, "cells": [4, 4, 20], "umf": 1.7, "u_over_umf": 2.0, "cfd_step": 1.0e-4}


def _coupled(particles: dict, coupling: dict) -> dict:
    return {"domain": {"upper": [0.06, 0.06, 0.3]}, "particles": particles, "contact": _CONTACT,
            "time": {"dem_step": 1.0e-5, "end": 1.0}, "gas": _GAS, "coupling": coupling}


def _settling(particles: dict) -> dict:
    return {"domain": {"upper": [0.06, 0.06, 0.3]}, "particles": particles, "contact": _CONTACT,
            "time": {"dem_step": 1.0e-5, "end": 1.0, "stop_when_settled": True, "min_time": 0.4}}


# name: (the case table, its steps: CFD steps where the gas runs, else DEM steps). Together they run what
# cases/ar4_mp.toml, ar4_mp_drag.toml, ar1.toml, demo.toml, bed_ar4.toml, bed_ar1.toml, fixed_bed_gas.toml and
# hindered_settling.toml run (tests/unit/test_warmup.py: those cases need no kernel signature beyond the scenes')
SCENES = {
    "rods_settling": (_settling(_RODS), 5),
    "gas": ({"domain": {"upper": [0.06, 0.06, 0.3]}, "particles": {"count": 0},
             "gas": {"enabled": True, "cells": [4, 4, 20], "inlet_velocity": 1.0, "walls": "free-slip",
                     "cfd_step": 1.0e-3, "scheme": "simple",
                     "porous_zone": {"enabled": True, "lower": [0.0, 0.0, 0.0], "upper": [0.06, 0.06, 0.1],
                                     "voidage": 0.45, "particle_diameter": "5.3 mm"}},
             "time": {"end": 0.05}}, 3),
    "rods_fixed": (_coupled(dict(_RODS, fixed=True), {"drag": "sanjeevi-padding", "lift": "sanjeevi-padding",
                                                      "torque": "sanjeevi-padding", "voidage": "divided"}), 3),
    "rods": (_coupled(_RODS, {"drag": "sanjeevi-padding", "lift": "sanjeevi-padding",
                              "torque": "sanjeevi-padding", "voidage": "divided"}), 3),
    "spheres": (_coupled(_SPHERES, {"drag": "hoelzer-sommerfeld", "voidage": "divided"}), 3),
    "rods_drag": (_coupled(_RODS, {"drag": "sanjeevi-padding", "voidage": "divided"}), 3),
    "suspension": ({"suspension": {"enabled": True, "particle": "cylinder", "aspect_ratio": 2.0,
                                   "density_ratio": 2.0, "galileo_equivalent": 1296, "solids_fraction": 0.2,
                                   "box": [9, 9, 18], "cells": [3, 3, 6], "diameter": "1 mm", "duration": 20}},
                   3),
    "spheres_settling": (_settling(_SPHERES), 5),
}

# The scenes in chains, each chain one process running its scenes in order, the chains side by side. Every
# coupled scene needs the DEM's kernels and the coupling's, so the costly ones compile one after the other in one
# chain (the rods settling: the contact forces take most; the rods fluidized: the particle-to-grid map and the
# closures), and the later scenes of that chain find nearly all of theirs compiled (the drag laws are branches
# of one loop); the gas solver's kernels compile beside them. Measured on a 2-core AMD EPYC (Zen 1) beside two
# busy processes (the campaign's runs), 2026-12-06, cold caches, all 44 kernels: one process per scene, two at a
# time, 509 s (the contact forces and the grid map compiled twice, by the rods and the spheres side by side); in
# waves of scenes whose kernels do not overlap, 381 s; these two chains side by side 333 s, one after the other
# (``jobs = 1``) 444 s. With every kernel cached a process per scene cost 35 s in imports, the two chains 9 s.
CHAINS = (("rods_settling", "rods", "spheres", "rods_drag", "rods_fixed", "suspension", "spheres_settling"),
          ("gas",))


def fvdem_dispatchers() -> list:
    """The numba dispatchers of the fvdem modules imported in this process."""
    from numba.core.dispatcher import Dispatcher
    found = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("fvdem") and module is not None:
            for value in list(vars(module).values()):
                if isinstance(value, Dispatcher):
                    found[id(value)] = value
    return list(found.values())


def _label(dispatcher, signature) -> str:
    return f"{dispatcher.py_func.__module__}.{dispatcher.py_func.__qualname__}{signature}"


def kernel_signatures() -> set[str]:
    """Every fvdem kernel signature this process holds compiled (from numba's cache or compiled here)."""
    return {_label(d, sig) for d in fvdem_dispatchers() for sig in d.signatures}


def compiled_here() -> list[str]:
    """The fvdem kernels (and signatures) this process compiled rather than loaded from numba's cache."""
    return sorted(_label(d, sig) for d in fvdem_dispatchers() for sig, n in d.stats.cache_misses.items() if n)


def run_scene(table: dict, steps: int) -> dict:
    """Build ``table``'s case and advance it ``steps`` steps in this process, no output folder: what it compiled."""
    from .case.parse import case_from_dict
    from .simulation import Simulation
    before, start = set(compiled_here()), time.perf_counter()
    sim = Simulation(case_from_dict(table, source="fvdem compile"), progress=False, threads=1)
    sim.run(steps * sim.time_step)
    return {"seconds": time.perf_counter() - start, "compiled": [k for k in compiled_here() if k not in before]}


def _chain_process(names, env: dict, report) -> dict:
    """Run the scenes ``names`` in one fresh interpreter, in order: ``{name: {"seconds", "compiled"}}``."""
    with tempfile.TemporaryFile("w+") as errors:  # a file, not a pipe: warnings never block the scenes
        process = subprocess.Popen([sys.executable, "-m", "fvdem.warmup", *names], stdout=subprocess.PIPE,
                                   stderr=errors, text=True, env=env)
        results = {}
        for line in process.stdout:  # one JSON line per scene, as each ends
            name, result = json.loads(line)
            results[name] = result
            if report is not None:
                report(name, result)
        process.wait()
        errors.seek(0)
        stderr = errors.read()
    if process.returncode != 0:
        tail = "\n".join(stderr.strip().splitlines()[-5:])
        failed = next((n for n in names if n not in results), names[-1])
        raise RuntimeError(f"the scene {failed!r} failed (exit {process.returncode}):\n{tail}")
    return results


def compile_kernels(scenes=None, jobs: int = 2, report=None) -> dict:
    """Run ``scenes`` (names of ``SCENES``, default all) by ``CHAINS``: each chain's scenes in order in one fresh
    interpreter, ``jobs`` chains at a time (more than ``len(CHAINS)`` gain nothing): ``{"scenes": {name:
    {"seconds", "compiled" (the kernels it compiled; none where the cache or an earlier scene of its chain held
    them)}}, "wall_seconds"}``. ``report(name, result)`` is called as each scene ends."""
    names = list(SCENES) if scenes is None else list(scenes)
    unknown = [n for n in names if n not in SCENES]
    if unknown:
        raise ValueError(f"unknown scene(s) {', '.join(map(repr, unknown))}; the scenes: {', '.join(SCENES)}")
    env = dict(os.environ, NUMBA_NUM_THREADS="1")  # compiling is one core's work; a scene's steps are few
    chains = [[n for n in chain if n in names] for chain in CHAINS]
    start = time.perf_counter()
    results = {}
    with ThreadPoolExecutor(max(1, jobs)) as pool:
        for future in [pool.submit(_chain_process, chain, env, report) for chain in chains if chain]:
            results.update(future.result())
    return {"scenes": {n: results[n] for n in names}, "wall_seconds": time.perf_counter() - start}


if __name__ == "__main__":  # scenes in this process, in order (``compile_kernels`` starts one per chain)
    for scene in sys.argv[1:]:
        print(json.dumps([scene, run_scene(*SCENES[scene])]), flush=True)
