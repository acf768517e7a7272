"""``fvdem compile``: its scenes compile every kernel the shipped cases run, so that a run, a study's worker or a
job started after it compiles nothing (numba's cache hits, counted by each dispatcher)."""
import json
import subprocess
import sys

from paths import ROOT


# in one fresh interpreter, fvdem compile's scenes, then each shipped case shrunk to 150 particles inserted at
# the bottom (the paper's cases start from settled beds that other cases write), three of its steps: the kernel
# signatures each case needed beyond those the scenes compiled or loaded (cached or not: numba keeps one
# compiled function per signature, so a signature new to the process is one the scenes do not cover)
SHIPPED = r"""
import json, sys, tomllib
from pathlib import Path
from fvdem.case.parse import case_from_dict
from fvdem.simulation import Simulation
from fvdem.warmup import SCENES, kernel_signatures as signatures, run_scene

for table, steps in SCENES.values():
    run_scene(table, steps)
covered = signatures()
out = {}
for path in sorted(Path(sys.argv[1]).glob("*.toml")):
    table = tomllib.loads(path.read_text())
    particles = table.get("particles")
    if particles and particles.get("count", 0) > 0:
        particles.pop("initial_state", None)
        upper = table["domain"]["upper"]
        particles["count"] = 150
        particles["insertion"] = dict(particles.get("insertion", {}), lower=[0.0, 0.0, 0.0],
                                      upper=[upper[0], upper[1], 0.1])
    sim = Simulation(case_from_dict(table, source=str(path)), progress=False, threads=1)
    sim.run(3 * sim.time_step)
    out[path.name] = sorted(signatures() - covered)
print(json.dumps(out))
"""


def test_the_scenes_cover_every_kernel_signature_of_the_shipped_cases():
    shipped = subprocess.run([sys.executable, "-c", SHIPPED, str(ROOT / "cases")], capture_output=True, text=True,
                             cwd=ROOT, timeout=1800)
    assert shipped.returncode == 0, shipped.stderr[-3000:]
    new = json.loads(shipped.stdout.strip().splitlines()[-1])
    assert len(new) == len(list((ROOT / "cases").glob("*.toml"))) >= 10
    assert all(kernels == [] for kernels in new.values()), {k: v for k, v in new.items() if v}


def test_fvdem_compile_reports_each_scene_and_a_second_call_compiles_nothing():
    result = subprocess.run([sys.executable, "-m", "fvdem", "compile", "--json"], capture_output=True, text=True,
                            cwd=ROOT, timeout=1800)
    assert result.returncode == 0, result.stderr[-3000:]
    report = json.loads(result.stdout.strip().splitlines()[-1])
    from fvdem.warmup import SCENES
    assert set(report["scenes"]) == set(SCENES)
    for name, scene in report["scenes"].items():
        assert scene["seconds"] > 0 and isinstance(scene["compiled"], list), name
    # and a second call finds every kernel cached
    again = subprocess.run([sys.executable, "-m", "fvdem", "compile", "--json"], capture_output=True, text=True,
                           cwd=ROOT, timeout=1800)
    assert again.returncode == 0, again.stderr[-3000:]
    assert all(s["compiled"] == [] for s in json.loads(again.stdout.strip().splitlines()[-1])["scenes"].values())


def test_a_wrong_job_count_is_refused_before_anything_runs():
    result = subprocess.run([sys.executable, "-m", "fvdem", "compile", "--jobs", "0"], capture_output=True,
                            text=True, cwd=ROOT, timeout=120)
    assert result.returncode == 2 and "--jobs" in result.stderr and "at least 1" in result.stderr
    assert "Traceback" not in result.stderr and result.stdout == ""
