"""What every part of a study file's check shares: a problem line, did-you-mean, a TOML file read with
its errors named, a sub-table."""
from __future__ import annotations

import tomllib
from pathlib import Path

from ..errors import CaseError


def problem(problems, key, value, allowed):
    problems.append(f"{key} = {value!r}: {allowed}")


def did_you_mean(key, allowed) -> str:
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


def table_of(table, key, problems):
    value = table.get(key, {})
    if not isinstance(value, dict):
        problem(problems, key, value, "a table")
        return {}
    return value


REPLICAS_SPAN, PRIORITY_SPAN = (1, 1000), (-1000, 1000)  # the integers ``replicas`` and ``priority`` take


def seconds_of(value, path: str, problems) -> bool:
    """Whether ``value`` is a number of simulated seconds (0 < value < 1e6); else a problem at ``path``."""
    if isinstance(value, (int, float)) and not isinstance(value, bool) and 0 < value < 1e6:
        return True
    problem(problems, path, value, "a number of simulated seconds > 0")
    return False


def replicas_of(table: dict, path: str, default: int, problems) -> int:
    """``table``'s ``replicas`` (``default`` when absent): an integer 1-1000, else a problem and 1."""
    return integer_in(table, "replicas", path, default, REPLICAS_SPAN, 1, problems)


def priority_of(table: dict, path: str, problems) -> int:
    """``table``'s ``priority`` (0 when absent): an integer -1000-1000, else a problem and 0."""
    return integer_in(table, "priority", path, 0, PRIORITY_SPAN, 0, problems,
                    " (the queue's tier: higher first, 0 by default)")


def integer_in(table: dict, key: str, path: str, default: int, span: tuple, fallback: int, problems,
             why: str = "") -> int:
    """``table[key]`` (``default`` when absent): an integer within ``span`` (a bool is not one), else a problem at
    ``path`` ("an integer <low>-<high>" and ``why``) and ``fallback``."""
    value = table.get(key, default)
    low, high = span
    if not isinstance(value, int) or isinstance(value, bool) or not low <= value <= high:
        problem(problems, path, value, f"an integer {low}-{high}{why}")
        return fallback
    return value
