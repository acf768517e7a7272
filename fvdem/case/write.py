"""A case written back: nested tables of plain values (``case_as_dict``) and TOML (``to_toml``)."""
from __future__ import annotations

import re
from dataclasses import fields

from .schema import Case


_SCALAR_ARRAY = re.compile(r"\[\n((?: +[^\n\"'\[\]]*,\n)+) *\]")


def _dumps(table: dict) -> str:
    """TOML by tomli-w, with arrays of numbers and booleans on one line (``upper = [0.15, 0.15, 1.05]``; an array
    of such arrays one per line)."""
    import tomli_w
    return _SCALAR_ARRAY.sub(lambda m: "[" + ", ".join(item.strip().rstrip(",") for item in m.group(1).splitlines())
                             + "]", tomli_w.dumps(table))


def _toml_value(value) -> str:
    """One value as TOML (the reference tables' defaults)."""
    return _dumps({"v": list(value) if isinstance(value, tuple) else value})[4:].strip()


def case_as_dict(case) -> dict:
    """The case as nested tables of plain values (unset optional values left out), the form TOML takes."""
    table = {}
    for f in fields(case):
        kind = f.metadata.get("kind")
        value = getattr(case, f.name)
        if kind == "internal" or value is None:
            continue
        if kind == "section":
            table[f.name] = case_as_dict(value)
        elif kind == "schedule":
            table[f.name] = [list(pair) for pair in value]
        else:
            table[f.name] = list(value) if isinstance(value, tuple) else value
    return table


def to_toml(case: Case, header: str | None = None) -> str:
    """The fully resolved case as TOML (unset optional values are omitted), written by tomli-w so that
    any string (newlines, quotes, backslashes, Unicode) reads back as it was; ``header``: a comment line
    (e.g. what made the run) after the first."""
    lines = ["# fully resolved case written by fvdem (defaults included, SI units)"]
    if header:
        lines += [f"# {part}" for part in header.splitlines()]
    return "\n".join(lines) + "\n" + _dumps(case_as_dict(case))
