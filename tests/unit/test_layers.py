"""The layering (docs/ARCHITECTURE.md, issue 34): the gas and the DEM are the bottom layers and import
nothing above them (the coupling, the scenes, the model, the study, the command line); what more than one
layer needs lives in leaf modules (fvdem.errors, fvdem.correlations, fvdem.timing)."""
import ast
import re
from pathlib import Path

import pytest

from paths import ROOT

PACKAGE = ROOT / "fvdem"
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


# the layers, bottom up (docs/ARCHITECTURE.md): a module imports from its own package, the leaves and the
# layers below its own, never from beside or above it
LAYERS = [
    {"errors", "correlations", "timing", "provenance", "signals", "version"},  # leaves
    {"dem", "gas"},
    {"coupling"},
    {"case"},
    {"analysis", "io"},
    {"model", "scenes", "monitors"},
    {"simulation"},
    {"study", "warmup"},
    {"reports"},  # published studies' reports (fvdem.reports.mema2020), registered with the study engine by name
    {"json_schema"},
    {"cli"},
    {"__main__", "__init__"},
]
RANK = {name: rank for rank, names in enumerate(LAYERS) for name in names}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _targets(path: Path, node) -> set:
    """The fvdem modules an import statement names (``fvdem.x.y`` form; ``from p import m`` names
    ``p.m`` when ``m`` is a module of package ``p``, else ``p``)."""
    package = _module_name(path) if path.name == "__init__.py" else _module_name(path).rsplit(".", 1)[0]
    if isinstance(node, ast.Import):
        return {a.name for a in node.names if a.name.startswith("fvdem")}
    if node.level == 0:
        if not (node.module or "").startswith("fvdem"):
            return set()
        base = node.module
    else:
        parts = package.split(".")
        base = ".".join(parts[:len(parts) - node.level + 1] + ([node.module] if node.module else []))
    found = set()
    for alias in node.names:
        candidate = f"{base}.{alias.name}"
        as_path = PACKAGE.parent / candidate.replace(".", "/")
        found.add(candidate if as_path.with_suffix(".py").exists() or (as_path / "__init__.py").exists() else base)
    return found


def _graph(module_level_only: bool) -> dict:
    graph = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        tree = ast.parse(path.read_text())
        nodes = tree.body if module_level_only else list(ast.walk(tree))
        if module_level_only:  # also imports under if / try at module level (not in functions, not for typing)
            nodes = [n for top in tree.body for n in ast.walk(top)
                     if not isinstance(top, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef))
                     and not (isinstance(top, ast.If) and "TYPE_CHECKING" in ast.unparse(top.test))]
        graph[_module_name(path)] = set().union(*(_targets(path, n) for n in nodes
                                                  if isinstance(n, (ast.Import, ast.ImportFrom)))) - {_module_name(path)}
    return graph


@pytest.mark.parametrize("module_level_only", [True, False], ids=["module level", "inside functions too"])
def test_no_import_cycle_among_fvdem_modules(module_level_only):
    """Imports form no cycle: module-level ones (a cycle would make the import order matter and a name
    half-defined), nor counting those inside functions (a cycle there is a tangle of modules that need each
    other: what both need belongs in a leaf, e.g. fvdem.study.records, registry and specs)."""
    graph = _graph(module_level_only=module_level_only)
    state, stack, cycles = {}, [], []

    def visit(module):
        state[module] = "open"
        stack.append(module)
        for target in sorted(graph.get(module, ())):
            if target not in graph:
                continue
            if state.get(target) == "open":
                cycles.append(stack[stack.index(target):] + [target])
            elif target not in state:
                visit(target)
        stack.pop()
        state[module] = "done"

    for module in sorted(graph):
        if module not in state:
            visit(module)
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c) for c in cycles)


def test_no_import_beside_or_above_a_modules_layer():
    """Every import, module-level or inside a function, goes to the module's own package, a leaf or a
    lower layer: dem and gas below coupling, coupling below case, case below analysis and io, those
    below model and scenes, scenes below simulation, simulation below study, study below the command
    line."""
    wrong = []
    for module, targets in _graph(module_level_only=False).items():
        parts = module.split(".")
        own = parts[1] if len(parts) > 1 else "__init__"
        assert own in RANK, f"{module}: fvdem.{own} has no layer in LAYERS (add it)"
        for target in targets:
            other = target.split(".")[1] if "." in target else "__init__"
            if other == own or RANK[other] == 0:
                continue
            if RANK[other] >= RANK[own]:
                wrong.append(f"{module} imports {target} (layer {RANK[other]}, its own {RANK[own]})")
    assert not wrong, "\n".join(sorted(wrong))


def test_the_bridge_steps_the_dem_through_its_coupled_step_and_never_sees_its_order():
    """The DEM re-sorts its particles by cell when it rebuilds its list; that stays inside it: the bridge
    calls ``coupled_step`` (the drag impulse comes back in the order the particles had when it was called)
    and reads neither the impulse array nor the particle ids to put rows back in order."""
    tree = ast.parse((PACKAGE / "coupling" / "bridge.py").read_text())
    attributes = {node.attr for node in ast.walk(tree) if isinstance(node, ast.Attribute)}
    assert "coupled_step" in attributes and "drag_impulse" not in attributes
    dem_steps = [node for node in ast.walk(tree) if isinstance(node, ast.Attribute) and node.attr == "step"
                 and "dem" in ast.unparse(node.value)]
    assert not dem_steps, [ast.unparse(n) for n in dem_steps]
    calls_on_ids = [node for node in ast.walk(tree) if isinstance(node, ast.Attribute) and node.attr == "ids"]
    assert len(calls_on_ids) <= 1  # the particle id named in the explicit-drag stability error only


def test_the_bridge_owns_the_coupling_inputs_and_writes_nothing_of_the_dem():
    """The coupling inputs are the bridge's own buffers (``CouplingInputs``) handed to ``coupled_step``: no
    assignment in the bridge has the DEM or its particle arrays (``dem.``, ``p.``, ``particles.``) on its
    left side, whole or in part, and it sets no flag of the DEM."""
    tree = ast.parse((PACKAGE / "coupling" / "bridge.py").read_text())
    targets = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.Assign, ast.AugAssign, ast.AnnAssign)):
            targets += node.targets if isinstance(node, ast.Assign) else [node.target]
    written = [ast.unparse(t) for t in targets if isinstance(t, (ast.Attribute, ast.Subscript))]
    into_dem = [w for w in written if w.split("[")[0].split(".")[0] in ("p", "dem", "particles")
                or ".dem." in w or "particles." in w]
    assert not into_dem, into_dem
    assert any("inputs.drag_coefficient" in w for w in written)  # the check sees the bridge's own writes


# what a published study's report or a scene knows, which the study engine must not: the mixing and its time,
# the paper (seed 000, Mema et al. 2020) and its families, the stop condition's own key
STUDY_WORDS = re.compile(r"mixing|mixed|t95|mema|stop_after_mixed|past_mixing|seed 000"
                         r"|(?<![/_])\bar[14](?:_\w+)?\b(?!\.toml)", re.IGNORECASE)


def test_the_study_engine_names_no_paper_nor_what_its_runs_measure():
    """``fvdem/study`` is generic: no line of it (comments and docstrings included) names the mixing, t95, the
    paper or its families. What ends a run early comes from the scenes' stop conditions (``fvdem.scenes.stops``),
    what a study reports from a report registered by name (``fvdem.reports``)."""
    found = [f"fvdem/study/{path.name}:{n}: {line.strip()}" for path in sorted((PACKAGE / "study").glob("*.py"))
             for n, line in enumerate(path.read_text().splitlines(), 1) if STUDY_WORDS.search(line)]
    assert not found, "\n".join(found)


def test_no_underscored_name_crosses_modules_of_the_study_engine_or_its_reports():
    """What a module of ``fvdem/study`` or ``fvdem/reports`` takes from another fvdem module has a public name
    (a shared reader lives in a leaf such as ``fvdem.study.records`` under a public name; an underscored name is
    its module's own)."""
    crossing = []
    for path in sorted([*(PACKAGE / "study").glob("*.py"), *(PACKAGE / "reports").rglob("*.py")]):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.level or (node.module or "").startswith("fvdem")):
                crossing += [f"{path.relative_to(PACKAGE.parent)}: {node.module or '.'} {a.name}" for a in node.names
                             if a.name.startswith("_") and not a.name.startswith("__")]
    assert not crossing, "\n".join(crossing)
