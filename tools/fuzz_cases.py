"""Fuzz the case-file validation: every file in cases/, mutated at random, must give a valid case or a
``CaseError`` that names the key at fault; any other exception is a crash (issue 19).

    python tools/fuzz_cases.py --count 100000 --json      # about 10 minutes on one core

Mutations (one to three per case): a value replaced by another type (number, string, boolean, list,
table), an extreme (1e308, -1e308, 1e-320, 0, -0.0, NaN, +-inf, 10**30, 2**63, -1), a unit string with
a wrong or extreme magnitude, a key removed or misspelt, an unknown nested key, a section replaced by
a scalar. The last line printed is one JSON object: counts, and the first crashes with their case,
mutations and exception.
"""
from __future__ import annotations

import argparse
import copy
import json
import math
import random
import re
import sys
import time
import tomllib
import traceback
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

from fvdem.case import CaseError, case_from_dict  # noqa: E402

EXTREMES = [1e308, -1e308, 1e-320, -1e-320, 0, 0.0, -0.0, math.nan, math.inf, -math.inf, 10 ** 30, 2 ** 63,
            -(2 ** 63), -1, 1, 2.5, 1e-9, 1e9]
STRINGS = ["", "x", "5.3 mm", "5.3 kg", "nan m", "1e400 m", "-1 m", "1e-320 s", "inf s", "3 m/s", "true",
           "random", "sphere", "spherocylinder", "piso", "none", "hoelzer-sommerfeld", " ", "ü"]
# a problem names its key first: "particles.insertion.upper[2] = ...", "gas.cell: unknown key ...",
# "--set a.b: ..."; every message of a CaseError must
KEY_PATTERN = re.compile(r"^(--set .+|(?:[A-Za-z_][\w-]*|\[.*?\])(?:\.[\w-]+|\[.*?\])*(?: = |: | \(|$))")


def case_tables(folder: Path = ROOT / "cases"):
    """``[(path, table)]`` of every case file."""
    return [(path, tomllib.loads(path.read_text())) for path in sorted(folder.glob("*.toml"))]


def _leaves(table, prefix=()):
    for key, value in table.items():
        path = prefix + (key,)
        yield path, value
        if isinstance(value, dict):
            yield from _leaves(value, path)


def random_value(rng: random.Random, depth: int = 0):
    choice = rng.randrange(8 if depth < 2 else 6)
    if choice == 0:
        return rng.choice(EXTREMES)
    if choice == 1:
        return rng.choice(STRINGS)
    if choice == 2:
        return rng.choice([True, False])
    if choice == 3:
        return rng.uniform(-10, 10) * 10 ** rng.randint(-12, 12)
    if choice == 4:
        return rng.randint(-5, 10 ** rng.randint(1, 25))
    if choice == 5:
        return rng.choice(STRINGS[2:11])
    if choice == 6:
        return [random_value(rng, depth + 1) for _ in range(rng.choice([0, 1, 2, 3, 3, 3, 4]))]
    return {rng.choice(["x", "enabled", "seed", "lower"]): random_value(rng, depth + 1)}


def mutate(table: dict, rng: random.Random) -> tuple[dict, list[str]]:
    """A mutated deep copy of ``table`` and a description of each mutation."""
    table = copy.deepcopy(table)
    done = []
    for _ in range(rng.choice([1, 1, 2, 3])):
        leaves = list(_leaves(table))
        if not leaves:
            break
        path, value = rng.choice(leaves)
        parent = table
        for key in path[:-1]:
            parent = parent[key]
        key = path[-1]
        kind = rng.randrange(10)
        if kind < 5:
            new = random_value(rng)
            parent[key] = new
            done.append(f"{'.'.join(path)} = {new!r}")
        elif kind == 5:
            del parent[key]
            done.append(f"removed {'.'.join(path)}")
        elif kind == 6:
            misspelt = key[:-1] if len(key) > 1 and rng.random() < 0.5 else key + rng.choice("sx_")
            parent[misspelt] = parent.pop(key)
            done.append(f"{'.'.join(path)} renamed {misspelt}")
        elif kind == 7:
            target = parent[key] if isinstance(parent[key], dict) else parent
            target[rng.choice(["extra", "Seed", "nested"])] = random_value(rng)
            done.append(f"unknown key under {'.'.join(path)}")
        elif kind == 8 and isinstance(value, (list, tuple)) and value:
            value = list(value)
            value[rng.randrange(len(value))] = random_value(rng)
            parent[key] = value
            done.append(f"{'.'.join(path)} item = {value!r}")
        else:
            new = rng.choice(EXTREMES)
            parent[key] = new
            done.append(f"{'.'.join(path)} = {new!r}")
    return table, done


def _classify(load, pattern):
    """``("valid" | "refused" | "crash" | "unnamed", detail)`` of ``load()``: "unnamed" is a CaseError with
    a message that ``pattern`` (a key path first) does not match."""
    try:
        load()
    except CaseError as exc:
        if not exc.problems or not all(pattern.match(p) for p in exc.problems):
            return "unnamed", exc.problems
        return "refused", None
    except Exception as exc:  # noqa: BLE001 - anything else is the finding
        return "crash", f"{type(exc).__name__}: {exc} @ {traceback.extract_tb(exc.__traceback__)[-1].name}"
    return "valid", None


def check_one(table: dict, source: str):
    """A mutated case file: ``case_from_dict``."""
    return _classify(lambda: case_from_dict(table, source=source), KEY_PATTERN)


def check_study(table: dict, source: str):
    """A mutated study file: ``fvdem.study.study_from_table`` (every case of the study checked)."""
    from fvdem.study import study_from_table
    return _classify(lambda: study_from_table(table, source, "/nonexistent/fuzz-study-out"), STUDY_KEY_PATTERN)


# a study's problem names a study key first, or the run or bed whose case has the problem ("ar1_u_over_umf2:
# particles.count = -5: ..."), or the study file itself
STUDY_KEY_PATTERN = re.compile(r"^(?:[\w.+-]+: |/|cluster|" + KEY_PATTERN.pattern[1:] + ")")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=10000, help="mutated case files to try")
    parser.add_argument("--seed", type=int, default=0, help="random seed of the mutations")
    parser.add_argument("--quick", action="store_true", help="200 mutations (seconds)")
    parser.add_argument("--studies", action="store_true", help="mutate the study files of studies/ instead")
    parser.add_argument("--json", action="store_true", help="the result as one JSON line")
    args = parser.parse_args(argv)
    if args.quick:
        args.count = 200
    rng = random.Random(args.seed)
    cases = case_tables(ROOT / "studies") if args.studies else case_tables()
    check = check_study if args.studies else check_one
    counts = {"valid": 0, "refused": 0, "crash": 0, "unnamed": 0}
    findings = []
    start = time.perf_counter()
    step = max(1, args.count // 20)
    for i in range(args.count):
        path, table = cases[rng.randrange(len(cases))]
        mutated, done = mutate(table, rng)
        outcome, detail = check(mutated, str(path))
        counts[outcome] += 1
        if outcome in ("crash", "unnamed") and len(findings) < 20:
            findings.append({"case": path.name, "mutations": done, "outcome": outcome, "detail": detail})
        if (i + 1) % step == 0:
            print(f"{i + 1}/{args.count} cases: {counts}", file=sys.stderr, flush=True)
    result = {"count": args.count, "seed": args.seed, "kind": "studies" if args.studies else "cases",
              "cases": [p.name for p, _ in cases], **counts,
              "seconds": round(time.perf_counter() - start, 1), "findings": findings}
    print(json.dumps(result) if args.json else json.dumps(result, indent=2))
    return 0 if counts["crash"] == 0 and counts["unnamed"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
