"""The seams between components (docs/ARCHITECTURE.md): the DEM is a backend behind ``DEMBackend``, which
declares everything the rest of fvdem uses of it, and the gas is read through ``GasPhase``, never its solver."""
import ast

import numpy as np
import pytest

from fvdem.dem.backends import BACKENDS, MEMBERS, DEMBackend, build_backend, missing_members, register_backend
from fvdem.dem.particles import ParticleArrays
from fvdem.dem.system import Box, ContactModel
from fvdem.timing import Timings

from paths import ROOT

PACKAGE = ROOT / "fvdem"


class _Complete:
    """A stand-in with every member of the interface (values, not behaviour)."""

    particles = None
    dt = 1e-5
    gravity = np.zeros(3)
    box = None
    timings = Timings()
    step_count = 0
    rebuild_count = 0
    time = 0.0

    def step(self, steps=1):
        pass

    def coupled_step(self, steps, inputs):
        pass

    def diagnostics(self):
        return {}

    def check_health(self):
        pass

    def state(self):
        return {}

    def restore(self, data):
        pass


def _lacking(member):
    attributes = {k: v for k, v in vars(_Complete).items() if not k.startswith("__")}
    attributes.pop(member)
    return type(f"Lacking_{member}", (), attributes)()


def test_the_members_are_what_isinstance_checks():
    assert isinstance(_Complete(), DEMBackend) and missing_members(_Complete()) == []
    assert {"gravity", "dt", "timings", "box", "time", "coupled_step", "state", "restore"} <= set(MEMBERS)


@pytest.mark.parametrize("member", MEMBERS)
def test_a_backend_lacking_a_member_fails_isinstance_and_is_refused(member):
    system = _lacking(member)
    assert not isinstance(system, DEMBackend)
    assert missing_members(system) == [member]
    register_backend("lacking", lambda *args: system, "a backend without one member (a test)")
    try:
        particles = ParticleArrays.create(np.array([[0.01, 0.01, 0.01]]), 0.002, 0.0, 1000.0)
        with pytest.raises(TypeError, match=rf"lacks {member} of the interface"):
            build_backend("lacking", particles, Box((0, 0, 0), (0.1, 0.1, 0.1), (False,) * 3), ContactModel(),
                          1e-5, (0, 0, -9.81), None)
    finally:
        BACKENDS.pop("lacking")


def _attributes_of(tree, owner_names):
    """Attributes read off an expression ending in one of ``owner_names`` (``dem.x``, ``self.dem.x``,
    ``model.dem.x``): the ``x``s."""
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute):
            value = node.value
            name = value.attr if isinstance(value, ast.Attribute) else value.id if isinstance(value, ast.Name) else None
            if name in owner_names:
                found.add(node.attr)
    return found


def test_the_protocol_declares_everything_used_of_a_dem_outside_it():
    """Every attribute the model, bridge, scenes, monitors, writers and analyses read off a DEM is a member of
    ``DEMBackend`` (a GPU backend providing the protocol provides all fvdem needs)."""
    used = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        if path.parent.name == "dem":
            continue
        for attribute in _attributes_of(ast.parse(path.read_text()), {"dem"}):
            used.setdefault(attribute, []).append(str(path.relative_to(ROOT)))
    assert used, "no use of a DEM found: the scan is broken"
    undeclared = {k: v for k, v in used.items() if k not in MEMBERS}
    assert not undeclared, f"used of a DEM but not in DEMBackend: {undeclared}"


def test_nobody_outside_the_gas_touches_its_solver():
    """The scenes, monitors, writers, model and tools read the gas through ``GasPhase`` (velocity, pressure,
    voidage, max_speed, periodic, timings, the inlet's schedule), never ``gas.solver``."""
    offenders = []
    for path in sorted([*PACKAGE.rglob("*.py"), *(ROOT / "tools").glob("*.py")]):
        if path.parent.name == "gas" and path.parent.parent == PACKAGE:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Attribute) and node.attr == "solver":
                offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not offenders, offenders


def test_the_tools_take_the_gas_properties_from_a_case():
    """No tool writes the gas's density or viscosity down again: they come from a case (or the solver's)."""
    for path in sorted((ROOT / "tools").glob("*.py")):
        text = path.read_text()
        assert "1.568e-5" not in text and "RHO, MU =" not in text, path.name
