"""DEM backends (issue 34): ``run.dem_backend`` selects a registered implementation behind the interface
of ``fvdem.dem.backends``; today's numba DEM is ``cpu``."""
import numpy as np
import pytest

import fvdem
from fvdem.dem.backends import BACKENDS, DEMBackend, backend_names, register_backend
from fvdem.dem.system import DEMSystem
from fvdem.model import Model

CASE = {"particles.count": 60, "domain.upper": [0.04, 0.04, 0.08], "particles.insertion.upper": [0.04, 0.04, 0.04],
        "time.end": 0.01, "gas.enabled": False}


def test_cpu_is_the_default_backend_and_meets_the_interface():
    case = fvdem.load_case("cases/demo.toml", CASE)
    assert case.run.dem_backend == "cpu" and "cpu" in backend_names()
    model = Model(case)
    assert isinstance(model.dem, DEMSystem) and isinstance(model.dem, DEMBackend)


def test_a_registered_backend_is_selected_by_the_case_key_and_an_unknown_one_refused():
    made = []

    class Recording(DEMSystem):
        """The CPU DEM, recording that it was built through the registry."""

    def factory(particles, box, contact, dt, gravity, skin):
        made.append(dt)
        return Recording(particles, box, contact, dt, gravity, skin)

    register_backend("recording", factory, "the CPU DEM, recording its construction (a test)")
    try:
        case = fvdem.load_case("cases/demo.toml", dict(CASE, **{"run.dem_backend": "recording"}))
        model = Model(case)
        assert isinstance(model.dem, Recording) and made == [case.time.dem_step]
        reference = Model(fvdem.load_case("cases/demo.toml", CASE))
        model.advance(20)
        reference.advance(20)
        np.testing.assert_array_equal(model.dem.particles.position, reference.dem.particles.position)
    finally:
        BACKENDS.pop("recording")
    with pytest.raises(fvdem.CaseError) as err:
        fvdem.load_case("cases/demo.toml", dict(CASE, **{"run.dem_backend": "cuda"}))
    assert "run.dem_backend" in str(err.value) and "cpu" in str(err.value)
