"""A case table (TOML) -> a validated ``Case``: each value converted by its field's rule (units, types,
ranges, registered names), unknown keys with did-you-mean, overrides (``--set``), the ``[suspension]``
expansion, then the cross-checks; every problem collected into one ``CaseError``."""
from __future__ import annotations

import copy
import difflib
import math
import re
import tomllib
from dataclasses import fields, replace
from pathlib import Path
from typing import Any

from ..errors import CaseError
from .checks import _cross_checks
from .schema import UNITS, Case, _choices, _describe_rule
from .suspension import expand_suspension


# every number of a case lies within these magnitudes (or is 0): values such as 1e-320 or 1e308 overflow
# or divide by zero in the derived checks (collision time, step ratios, volumes) instead of being refused
MIN_MAGNITUDE, MAX_MAGNITUDE = 1e-30, 1e30


def _number(value, meta, path, problems):
    """A float in SI from a number or a 'value unit' string; None (and a problem) if invalid."""
    unit = meta.get("unit")
    if isinstance(value, bool):
        problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
        return None
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str) and unit is not None:
        text = value.strip().split(None, 1)
        try:
            magnitude = float(text[0])
        except (ValueError, IndexError):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        symbol = text[1].strip() if len(text) > 1 else ""
        if symbol not in UNITS[unit]:
            problems.append(f"{path} = {value!r}: unit {symbol!r} is not a {unit} unit; allowed: "
                            + ", ".join(UNITS[unit]))
            return None
        number = magnitude * UNITS[unit][symbol]
    else:
        problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
        return None
    if not math.isfinite(number):
        problems.append(f"{path} = {value!r}: must be finite")
        return None
    if number != 0.0 and not MIN_MAGNITUDE <= abs(number) <= MAX_MAGNITUDE:
        problems.append(f"{path} = {value!r}: magnitude outside {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g} (SI), beyond "
                        "any physical value of it and the range fvdem's arithmetic is checked for")
        return None
    return number


def _check_range(number, meta, path, raw, problems):
    for key, ok in (("gt", lambda a, b: a > b), ("ge", lambda a, b: a >= b), ("lt", lambda a, b: a < b),
                    ("le", lambda a, b: a <= b)):
        bound = meta.get(key)
        if bound is not None and not ok(number, bound):
            problems.append(f"{path} = {raw!r}: out of range; allowed: {_describe_rule(meta)}")
            return


def _convert(value, meta, path, problems):
    kind = meta["kind"]
    if value is None:
        return None
    if kind == "float":
        number = _number(value, meta, path, problems)
        if number is not None:
            _check_range(number, meta, path, value, problems)
        return number
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        _check_range(value, meta, path, value, problems)
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            problems.append(f"{path} = {value!r}: expected true or false")
            return None
        return value
    if kind == "str":
        if not isinstance(value, str):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        if _choices(meta) and value not in _choices(meta):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        return value
    if kind in ("vec3", "bool3", "int3"):
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        item_meta = dict(meta, kind={"vec3": "float", "bool3": "bool", "int3": "int"}[kind])
        items = [_convert(v, item_meta, f"{path}[{k}]", problems) for k, v in enumerate(value)]
        return None if any(v is None for v in items) else tuple(items)
    if kind == "schedule":
        return _schedule(value, meta, path, problems)
    raise AssertionError(kind)


def _schedule(value, meta, path, problems):
    """A list of ``[time, value]`` pairs: times [s] >= 0 and increasing, values by the field's rule (unit, range)."""
    if not isinstance(value, (list, tuple)) or not all(isinstance(v, (list, tuple)) and len(v) == 2 for v in value):
        problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
        return None
    time_meta = dict(kind="float", unit="time", ge=0.0)
    pairs = [(_convert(t, time_meta, f"{path}[{k}][0]", problems),
              _convert(v, dict(meta, kind="float"), f"{path}[{k}][1]", problems)) for k, (t, v) in enumerate(value)]
    if any(t is None or v is None for t, v in pairs):
        return None
    if any(b[0] <= a[0] for a, b in zip(pairs, pairs[1:])):
        problems.append(f"{path} = {value!r}: the times must increase")
        return None
    return tuple(pairs)


def _key_path(path: str, key) -> str:
    """``path.key``, or ``path['key']`` for a key that is not a plain name (empty, spaces, digits first)."""
    if isinstance(key, str) and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_-]*", key):
        return f"{path}.{key}" if path else key
    return f"{path}[{key!r}]"


def _build(cls, table, path, problems):
    if not isinstance(table, dict):
        problems.append(f"{path or 'case'} = {table!r}: expected a table")
        return cls()
    known = {f.name: f for f in fields(cls) if f.metadata.get("kind") != "internal"}
    for key in table:
        if key not in known:
            where = _key_path(path, key)
            close = difflib.get_close_matches(key, known, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            problems.append(f"{where}: unknown key{hint}; allowed keys here: {', '.join(known)}")
    values = {}
    for name, f in known.items():
        where = f"{path}.{name}" if path else name
        meta = f.metadata
        if meta["kind"] == "section":
            sub_cls = f.default_factory
            values[name] = _build(sub_cls, table.get(name, {}), where, problems)
            continue
        if name not in table:
            continue
        converted = _convert(table[name], meta, where, problems)
        if converted is not None:
            values[name] = converted
    return cls(**values)


def _set_path(table: dict, dotted: str, value: Any) -> None:
    keys = dotted.split(".")
    node = table
    for key in keys[:-1]:
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            raise CaseError([f"--set {dotted!r}: '{key}' is not a table"])
    node[keys[-1]] = value


def parse_override(text: str):
    """``'a.b=value'`` -> ``('a.b', value)`` with value parsed as TOML (bare words as strings)."""
    if "=" not in text:
        raise CaseError([f"--set {text!r}: expected KEY=VALUE, e.g. time.end=0.5"])
    key, raw = text.split("=", 1)
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key.strip(), value


def case_from_dict(table: dict, source: str | None = None, overrides: dict | None = None) -> Case:
    """Validate a case table (as read from TOML). ``overrides`` maps dotted keys to values
    (``{"time.end": 0.5}``) and is applied, to a copy, before validation. Raises ``CaseError``."""
    if overrides:
        table = copy.deepcopy(table)
        for key, value in overrides.items():
            _set_path(table, key, value)
    problems: list[str] = []
    case = _build(Case, table, "", problems)
    if not problems and case.gas.u_over_umf is not None:
        g = case.gas
        if g.umf is None:
            problems.append(f"gas.u_over_umf = {g.u_over_umf:g}: needs gas.umf (the minimum fluidization velocity, m/s)")
        elif "inlet_velocity" in table.get("gas", {}) and abs(g.inlet_velocity - g.u_over_umf * g.umf) > 1e-12:
            problems.append(f"gas.inlet_velocity = {g.inlet_velocity:g} and gas.u_over_umf = {g.u_over_umf:g}: "
                            "give one of them")
        else:
            case = replace(case, gas=replace(g, inlet_velocity=g.u_over_umf * g.umf))
    if not problems and case.suspension.enabled:
        table = expand_suspension(case, table, problems)
        if not problems:
            case = _build(Case, table, "", problems)
    if not problems:
        _cross_checks(case, problems)
    if problems:
        raise CaseError(problems)
    return replace(case, source=source)


def load_case(path, overrides: dict | None = None) -> Case:
    """Read and validate a TOML case file. ``overrides`` maps dotted keys to values
    (``{"time.end": 0.5}``) and is applied before validation. Raises ``CaseError``."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            table = tomllib.load(fh)
    except FileNotFoundError:
        raise CaseError([f"{path}: no such case file"]) from None
    except IsADirectoryError:
        raise CaseError([f"{path}: is a directory, not a case file"]) from None
    except PermissionError:
        raise CaseError([f"{path}: not readable (permission denied)"]) from None
    except UnicodeDecodeError as exc:
        raise CaseError([f"{path}: not a text file (not UTF-8 at byte {exc.start}); a case file is TOML text"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{path}: not valid TOML: {exc}"]) from None
    except OSError as exc:
        raise CaseError([f"{path}: cannot be read ({exc.strerror or exc})"]) from None
    if not table:
        raise CaseError([f"{path}: empty case file (no tables or keys); see `fvdem schema` or cases/ for examples"])
    return case_from_dict(table, source=str(path), overrides=overrides)
