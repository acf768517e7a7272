"""The loops over the particles that run the registered hydrodynamic laws (the bridge's fast path), written
from the registry.

A law is registered once (``closures.register``, a set of laws sharing their work ``closures.register_set``).
From the registry this module writes the source of a module holding, for each kind (drag, lift, torque, set),
a dispatch function with one branch per registered law, by its index in the registry, and a parallel loop
over the particles that calls it. A law compiled with ``inline="always"`` (as those of ``laws.py`` are) is
inlined into the loop, also one registered at run time, e.g. by a test (a call through a function argument
cost the laws 1.6-2.5 times as much).

numba caches a compiled function under its module's source file and keys on that file only, so a loop that
inlines a law would not see an edit to the law's file. The generated module's name therefore carries a
**fingerprint** of the registry: a hash of the generated source, of each law's code and of the source files
its module reads (its own and those it imports from its package, e.g. ``laws.py`` and ``coefficients.py``).
A law added, removed, reordered or edited gives another module and so another cache entry; nothing needs
clearing by hand. The modules are written to ``directory()`` (``NUMBA_CACHE_DIR/fvdem_law_loops`` when set,
else the user's cache directory, else the temporary one; numba caches them beside, in ``__pycache__``); one
not used for ``STALE_DAYS`` days is removed, with its caches, when another is written.
"""
from __future__ import annotations

import ast
import hashlib
import importlib.util
import os
import sys
import tempfile
import time
from pathlib import Path

PREFIX = "fvdem_law_loops_"  # the generated modules' names: PREFIX + fingerprint (fvdem compile finds them)
STALE_DAYS = 30
KINDS = ("drag", "lift", "torque", "set")
_LAW_ARGUMENTS = "sx, sy, sz, eps, ax, ay, az, shape"
_AT_PARTICLE = "slip[i, 0], slip[i, 1], slip[i, 2], voidage[i], axis[i, 0], axis[i, 1], axis[i, 2], shape"
_LOOPS = {  # per kind: the loop's arguments after the index, what one particle's values are assigned to, its doc
    "drag": ("out", "out[i]", "The drag law of index ``k`` at every particle: drag coefficients c [kg/s] (N,)."),
    "lift": ("out", "out[i, 0], out[i, 1], out[i, 2]", "The lift law of index ``k`` at every particle: forces [N] "
             "(N, 3)."),
    "torque": ("out", "out[i, 0], out[i, 1], out[i, 2]", "The torque law of index ``k`` at every particle: torques "
               "[N m] (N, 3)."),
    "set": ("c_out, lift_out, torque_out",
            "(c_out[i], lift_out[i, 0], lift_out[i, 1], lift_out[i, 2], torque_out[i, 0], torque_out[i, 1],\n"
            "         torque_out[i, 2])", "The set of laws of index ``k`` at every particle in one pass: drag "
            "coefficients (N,),\n    lift (N, 3) and torque (N, 3)."),
}


def _label(function) -> str:
    python = getattr(function, "py_func", function)
    return f"{python.__module__}.{python.__qualname__}"


def source(registry: dict) -> str:
    """The loops' module, but for its header: ``registry`` maps each kind of ``KINDS`` to its ``(name,
    function)`` pairs in registry order (a function: a law of ``laws.py``'s form, or a set's)."""
    index = {kind: {name: k for k, (name, _) in enumerate(registry[kind])} for kind in KINDS}
    lines = ["import numba", "from numba import njit", "", f"INDEX = {index!r}", "",
             "# the laws, bound by fvdem.coupling.law_loops before anything here is compiled"]
    for kind in KINDS:
        lines += [f"{kind}_{k} = None  # {name!r}: {_label(function)}"
                  for k, (name, function) in enumerate(registry[kind])]
    for kind in KINDS:
        entries = registry[kind]
        if not entries:
            continue
        outputs, assigned, doc = _LOOPS[kind]
        lines += ["", "", "@njit(cache=True, inline=\"always\")", f"def _{kind}(k, {_LAW_ARGUMENTS}):"]
        for k in range(len(entries) - 1):
            lines += [f"    if k == {k}:", f"        return {kind}_{k}({_LAW_ARGUMENTS})"]
        lines += [f"    return {kind}_{len(entries) - 1}({_LAW_ARGUMENTS})", "", "",
                  "@njit(cache=True, parallel=True)",
                  f"def {kind}_loop(k, slip, voidage, axis, shape, {outputs}):",
                  f'    """{doc}"""',
                  "    for i in numba.prange(slip.shape[0]):",
                  f"        {assigned} = _{kind}(k, {_AT_PARTICLE})"]
    return "\n".join(lines) + "\n"


def _module_files(module_name: str, seen: dict) -> None:
    """Into ``seen`` (path -> sha256): the source file of module ``module_name`` and, recursively, of the
    modules of its own top-level package it imports (those loaded)."""
    module = sys.modules.get(module_name)
    path = getattr(module, "__file__", None)
    if not path or not path.endswith(".py") or path in seen or not os.path.exists(path):
        return
    text = Path(path).read_bytes()
    seen[path] = hashlib.sha256(text).hexdigest()
    top = module_name.split(".")[0]
    package = module_name if path.endswith("__init__.py") else module_name.rpartition(".")[0]
    for node in ast.walk(ast.parse(text)):
        names = []
        if isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")
                parent = ".".join(parts[:len(parts) - node.level + 1])
                base = f"{parent}.{base}" if base else parent
            names = [f"{base}.{alias.name}" if f"{base}.{alias.name}" in sys.modules else base
                     for alias in node.names]
        for name in names:
            if name.split(".")[0] == top and name in sys.modules:
                _module_files(name, seen)


def _stable(value, depth: int = 0) -> str:
    """``value`` as text that is the same in every process (no addresses): code by its bytecode, constants
    and names; functions by name and code; numbers, strings, arrays and tuples of them by value."""
    if depth > 8:
        return "..."
    if hasattr(value, "co_code"):
        return (value.co_code.hex() + _stable(value.co_consts, depth + 1) + repr(value.co_names))
    python = getattr(value, "py_func", value)
    if callable(python) and hasattr(python, "__code__"):
        cells = tuple(cell.cell_contents for cell in python.__closure__ or ())
        return f"{_label(python)}({_stable(python.__code__, depth + 1)}; {_stable(cells, depth + 1)})"
    if isinstance(value, (tuple, list)):
        return "(" + ", ".join(_stable(v, depth + 1) for v in value) + ")"
    if hasattr(value, "tobytes") and hasattr(value, "dtype"):
        return f"{value.dtype}{getattr(value, 'shape', ())}:{hashlib.sha256(value.tobytes()).hexdigest()}"
    if value is None or isinstance(value, (bool, int, float, complex, str, bytes)):
        return repr(value)
    return type(value).__qualname__


def _code_digest(function) -> str:
    """A law's own code: bytecode, constants, names and closure values (what its file's hash misses when
    the same file defines it twice, e.g. a test's local law)."""
    return hashlib.sha256(_stable(function).encode()).hexdigest()


def fingerprint(registry: dict, text: str | None = None) -> str:
    """The registry's fingerprint: a hash of the generated ``source`` (names, order), of each law's code and
    of the source files the laws' modules read. 16 hex digits."""
    digest = hashlib.sha256((text if text is not None else source(registry)).encode())
    files: dict = {}
    for kind in KINDS:
        for name, function in registry[kind]:
            digest.update(f"{kind}/{name}/{_label(function)}/{_code_digest(function)}".encode())
            _module_files(getattr(function, "py_func", function).__module__, files)
    for path in sorted(files):
        digest.update(f"{os.path.basename(path)}:{files[path]}".encode())
    return digest.hexdigest()[:16]


def directory() -> Path:
    """Where the generated modules are written: the first writable of ``NUMBA_CACHE_DIR/fvdem_law_loops``
    (when set), the user's cache directory (``$XDG_CACHE_HOME`` or ``~/.cache``, ``fvdem/law_loops``), the
    temporary directory."""
    import numba
    candidates = [Path(numba.config.CACHE_DIR) / "fvdem_law_loops"] if numba.config.CACHE_DIR else []
    cache_home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    candidates += [Path(cache_home) / "fvdem" / "law_loops",
                   Path(tempfile.gettempdir()) / f"fvdem-law-loops-{os.getuid() if hasattr(os, 'getuid') else 0}"]
    for candidate in candidates:
        try:
            candidate.mkdir(parents=True, exist_ok=True)
            tempfile.TemporaryFile(dir=candidate).close()
            return candidate
        except OSError:
            continue
    raise OSError(f"no writable directory for the generated law loops among {', '.join(map(str, candidates))}")


def _write(path: Path, text: str) -> None:
    """``text`` to ``path`` at once (another process may import it meanwhile)."""
    handle, temporary = tempfile.mkstemp(dir=path.parent, suffix=".tmp")
    with os.fdopen(handle, "w") as out:
        out.write(text)
    os.chmod(temporary, 0o644)  # readable like any source file (mkstemp's is the owner's only)
    os.replace(temporary, path)


def _remove_stale(folder: Path, keep: str) -> None:
    """Remove the generated modules unused for ``STALE_DAYS`` days (their use touches them), with numba's and
    Python's caches of them."""
    import numba
    limit = time.time() - STALE_DAYS * 86400
    for path in folder.glob(f"{PREFIX}*.py"):
        try:
            if path.stem == keep or path.stat().st_mtime > limit:
                continue
            path.unlink()
        except OSError:
            continue
        caches = [folder / "__pycache__"]
        if numba.config.CACHE_DIR:  # numba's caches of the module, in a folder per source folder
            caches += list(Path(numba.config.CACHE_DIR).glob("*"))
        for cache in caches:
            for stale in cache.glob(f"{path.stem}.*"):
                stale.unlink(missing_ok=True)


def build(registry: dict):
    """The loops' module for ``registry`` (kind -> ``(name, function)`` pairs, see ``source``): imported from
    ``directory()``, written there first if no process has written it yet, its laws bound. The module has
    ``INDEX`` (kind -> name -> index), ``FINGERPRINT`` and, per kind with laws, ``<kind>_loop(k, slip,
    voidage, axis, shape, out...)``."""
    body = source(registry)
    key = fingerprint(registry, body)
    name = PREFIX + key
    module = sys.modules.get(name)
    if module is None:
        folder = directory()
        path = folder / f"{name}.py"
        header = ('"""The registered hydrodynamic laws\' loops over the particles, written by\n'
                  f'fvdem.coupling.law_loops from the registry (fingerprint {key}); do not edit: another registry\n'
                  f'or law is another module."""\n\nFINGERPRINT = {key!r}\n')
        try:
            os.utime(path)  # in use: not stale
        except FileNotFoundError:
            _write(path, header + body)
            _remove_stale(folder, name)
        except OSError:  # another user's, in a shared cache: used as it is
            pass
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        try:
            spec.loader.exec_module(module)
        except BaseException:
            del sys.modules[name]
            raise
    for kind in KINDS:
        for k, (_, function) in enumerate(registry[kind]):
            setattr(module, f"{kind}_{k}", function)
    return module
