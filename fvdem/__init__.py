"""fvdem: CFD-DEM for fluidized beds of spheres and spherocylinders (FiPy gas, numba DEM).

Library use::

    import fvdem
    case = fvdem.load_case("cases/bed_ar1.toml", {"particles.count": 2000})
    sim = fvdem.Simulation(case)
    sim.run(0.05)
    print(sim.diagnostics())
"""
__version__ = "0.1.0"

from .case import Case, CaseError, load_case  # noqa: E402
from .dem.system import SimulationError  # noqa: E402
from .simulation import OutputError, Simulation  # noqa: E402


def run(case_path, out_dir=None, overrides=None, **kwargs) -> dict:
    """Load a case file and run it to its end time; returns the summary dictionary."""
    return Simulation(load_case(case_path, overrides), out_dir, **kwargs).run()


__all__ = ["Case", "CaseError", "OutputError", "Simulation", "SimulationError", "load_case", "run", "__version__"]
