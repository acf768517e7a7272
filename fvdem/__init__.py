"""fvdem: CFD-DEM for fluidized beds of spheres and spherocylinders (FiPy gas, numba DEM).

Library use::

    import fvdem
    case = fvdem.load_case("cases/bed_ar1.toml", {"particles.count": 2000})
    sim = fvdem.Simulation(case)
    sim.run(0.05)
    print(sim.diagnostics())
"""
from .version import __version__  # noqa: F401

import os as _os  # noqa: E402

import numba as _numba  # noqa: E402

# numba picks TBB over OpenMP when libtbb is installed (it comes with, e.g., Debian's LIGGGHTS and
# OpenFOAM packages). With TBB a parallel kernel launch costs ~13 us instead of ~5 and small systems
# stepped many times ran up to 250 x slower (a one-sphere test: 250 s against 1 s, measured
# 2026-12-01): prefer OpenMP, unless the user chose a layer
if not {"NUMBA_THREADING_LAYER", "NUMBA_THREADING_LAYER_PRIORITY"} & set(_os.environ):
    _numba.config.THREADING_LAYER_PRIORITY = ["omp", "tbb", "workqueue"]

from .case import Case, load_case  # noqa: E402
from .errors import CaseError, OutputError, SimulationError  # noqa: E402
from .simulation import Simulation  # noqa: E402


def run(case_path, out_dir=None, overrides=None, **kwargs) -> dict:
    """Load a case file and run it to its end time; returns the summary dictionary."""
    return Simulation(load_case(case_path, overrides), out_dir, **kwargs).run()


__all__ = ["Case", "CaseError", "OutputError", "Simulation", "SimulationError", "load_case", "run", "__version__"]
