"""Every tool in tools/ runs from a fresh clone (issue 33): it prepares what it needs (the settled beds,
tools/_beds.py) or refuses in one line before it measures, and has a quick mode that this suite, or
`make smoke`, runs. FVDEM_BEDS_DIR points the tools at an empty folder: no runs/ left by earlier work."""
import json
import os
import re
import shutil
import subprocess
import sys

import pytest

from paths import ROOT

TOOLS = sorted(p.stem for p in (ROOT / "tools").glob("*.py") if not p.stem.startswith("_"))
SMOKE = set(re.findall(r"tools/(\w+)\.py --quick", (ROOT / "Makefile").read_text()))
# a tool whose purpose needs a program fvdem does not install: it refuses in one line without it
NEEDS = {"compare_liggghts": "liggghts"}
# the tools whose quick mode settles the quick beds, all in one folder (the first settles them)
ORDER = ["bench_coupled"] + [t for t in TOOLS if t != "bench_coupled" and t not in SMOKE]


def test_every_tool_has_a_quick_mode_that_the_suite_or_make_smoke_runs():
    for tool in TOOLS:
        assert '"--quick"' in (ROOT / "tools" / f"{tool}.py").read_text(), f"tools/{tool}.py has no --quick"
    assert SMOKE and SMOKE <= set(TOOLS) and set(TOOLS) == set(ORDER) | SMOKE


@pytest.fixture(scope="module")
def fresh(tmp_path_factory):
    """A working folder away from the repository and an empty beds folder (a fresh clone's)."""
    return tmp_path_factory.mktemp("work"), tmp_path_factory.mktemp("beds")


@pytest.mark.slow
@pytest.mark.parametrize("tool", ORDER)
def test_a_tool_runs_from_a_fresh_clone_in_its_quick_mode(tool, fresh):
    work, beds = fresh
    # one numba thread: a tool is checked here, not timed, and more threads than free cores stall OpenMP
    env = dict(os.environ, FVDEM_BEDS_DIR=str(beds), NUMBA_NUM_THREADS="1")
    result = subprocess.run([sys.executable, str(ROOT / "tools" / f"{tool}.py"), "--quick", "--json"],
                            capture_output=True, text=True, timeout=600, cwd=work, env=env)
    assert "Traceback" not in result.stderr, result.stderr[-3000:]
    if tool in NEEDS and shutil.which(NEEDS[tool]) is None:
        assert result.returncode == 2 and NEEDS[tool] in result.stderr.lower()
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr  # one line, before any work
        return
    assert result.returncode == 0, result.stderr[-3000:]
    assert isinstance(json.loads(result.stdout.strip().splitlines()[-1]), dict)


@pytest.mark.slow
def test_the_fluidized_benchmark_breaks_the_coupled_step_into_its_phases(fresh):
    """``bench_fluidized.py --coupled``: per shape the coupled step per simulated second and its timed phases
    per CFD step (after the quick beds of the test above), the DEM's and the bridge's all there and positive."""
    work, beds = fresh
    env = dict(os.environ, FVDEM_BEDS_DIR=str(beds), NUMBA_NUM_THREADS="1")
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "bench_fluidized.py"), "--quick", "--coupled",
                             "--json"], capture_output=True, text=True, timeout=600, cwd=work, env=env)
    assert result.returncode == 0, result.stderr[-3000:]
    out = json.loads(result.stdout.strip().splitlines()[-1])
    for shape in ("ar1", "ar4"):
        phases = out["shapes"][shape]["coupled_ms_per_cfd_step"]
        for phase in ("neighbour_list", "contact_forces", "integration", "voidage_mapping", "closures", "deposition"):
            assert phases[phase] > 0.0, (shape, phase, phases)
        assert out["shapes"][shape]["coupled_wall_seconds_per_simulated_second"] > 0.0
