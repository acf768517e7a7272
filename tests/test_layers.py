"""The layering (docs/ARCHITECTURE.md, issue 34): the gas and the DEM are the bottom layers and import
nothing above them (the coupling, the scenes, the model, the study, the command line); what more than one
layer needs lives in leaf modules (fvdem.errors, fvdem.correlations, fvdem.timing)."""
import ast
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[1] / "fvdem"
ABOVE = {"coupling", "scenes", "model", "simulation", "study", "cli", "analysis", "io", "case", "monitors"}
LEAVES = {"errors", "correlations", "timing"}


def _fvdem_imports(path: Path, package: str) -> set:
    """The fvdem modules a file imports (first component below fvdem), module-level or inside functions."""
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level == 0 and (node.module or "").startswith("fvdem."):
                found.add(node.module.split(".")[1])
            elif node.level >= 2:  # from ..x import y, from .. import x
                target = (node.module or "").split(".")[0]
                found |= {target} if target else {a.name for a in node.names}
            elif node.level == 1 and package == "":  # a top-level module's sibling
                found.add((node.module or "").split(".")[0])
        elif isinstance(node, ast.Import):
            found |= {a.name.split(".")[1] for a in node.names if a.name.startswith("fvdem.")}
    return found


@pytest.mark.parametrize("layer", ["gas", "dem"])
def test_the_gas_and_the_dem_import_nothing_above_them(layer):
    for path in sorted((PACKAGE / layer).glob("*.py")):
        upward = _fvdem_imports(path, layer) & ABOVE
        assert not upward, f"fvdem/{layer}/{path.name} imports {sorted(upward)}"


def test_the_leaf_modules_import_no_other_fvdem_module():
    for leaf in sorted(LEAVES):
        assert not _fvdem_imports(PACKAGE / f"{leaf}.py", ""), leaf


def test_the_bridge_talks_to_the_gas_through_its_interface_only():
    """The coupling bridge uses GasPhase's bridge interface (set_voidage, set_exchange, step, flux_velocity,
    pressure_gradient, exchange_lost, return_momentum, mesh, mean_pressure_gradient), never the solver or
    the phase's exchange arrays."""
    tree = ast.parse((PACKAGE / "coupling" / "bridge.py").read_text())
    private = {"solver", "exchange_beta", "exchange_source", "returned_momentum"}
    used = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
    assert not used & private, sorted(used & private)
