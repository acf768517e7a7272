"""What every part of a study file's check shares: a problem line, did-you-mean, a TOML file read with
its errors named, a sub-table."""
from __future__ import annotations

import tomllib
from pathlib import Path

from ..errors import CaseError


def _problem(problems, key, value, allowed):
    problems.append(f"{key} = {value!r}: {allowed}")


def _did_you_mean(key, allowed) -> str:
    import difflib
    close = difflib.get_close_matches(str(key), sorted(allowed), n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


def read_toml(path, what: str = "") -> dict:
    """A TOML file's table; ``CaseError`` naming the file (after ``what``, e.g. "--cluster ") when it
    cannot be read or parsed."""
    try:
        return tomllib.loads(Path(path).read_text())
    except (OSError, UnicodeDecodeError) as exc:
        raise CaseError([f"{what}{path}: cannot be read ({exc})"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{what}{path}: not valid TOML ({exc})"]) from None


def _table(table, key, problems):
    value = table.get(key, {})
    if not isinstance(value, dict):
        _problem(problems, key, value, "a table")
        return {}
    return value
