"""Every input is refused cleanly (issue 19): mutated case files and ``--set`` overrides give a valid
case or a ``CaseError`` whose every message starts with the key at fault, never another exception;
the command line answers unreadable input with exit code 2 and one line. ``tools/fuzz_cases.py``
runs the same mutations by the hundred thousand (docs/validation.md)."""
import math
import random
import subprocess
import sys

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from paths import ROOT, TOOLS

sys.path.insert(0, str(TOOLS))
import fuzz_cases  # noqa: E402

from fvdem.case import CaseError, load_case, parse_override  # noqa: E402

CASES = fuzz_cases.case_tables()
SETTINGS = settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])

scalars = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True), st.integers(min_value=-(10 ** 40), max_value=10 ** 40),
    st.sampled_from([1e308, -1e308, 1e-320, 5e-324, -0.0, math.nan, math.inf, 2 ** 63, 10 ** 30]),
    st.booleans(), st.text(max_size=12), st.sampled_from(fuzz_cases.STRINGS))
values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                         st.dictionaries(st.text(max_size=6), inner, max_size=3)),
                      max_leaves=6)


def _assert_clean(table, source):
    outcome, detail = fuzz_cases.check_one(table, source)
    assert outcome in ("valid", "refused"), detail


def test_every_case_file_is_valid():
    for path, table in CASES:
        assert fuzz_cases.check_one(table, str(path))[0] == "valid", path


@SETTINGS
@given(index=st.integers(0, len(CASES) - 1), seed=st.integers(0, 2 ** 32 - 1))
def test_random_mutations_of_the_case_files_are_refused_cleanly(index, seed):
    path, table = CASES[index]
    mutated, _ = fuzz_cases.mutate(table, random.Random(seed))
    _assert_clean(mutated, str(path))


@SETTINGS
@given(index=st.integers(0, len(CASES) - 1), pick=st.integers(0, 10 ** 6), value=values)
def test_any_value_at_any_key_is_refused_cleanly(index, pick, value):
    path, table = CASES[index]
    leaves = list(fuzz_cases._leaves(table))
    key_path, _ = leaves[pick % len(leaves)]
    mutated = fuzz_cases.copy.deepcopy(table)
    node = mutated
    for key in key_path[:-1]:
        node = node[key]
    node[key_path[-1]] = value
    _assert_clean(mutated, str(path))


@SETTINGS
@given(index=st.integers(0, len(CASES) - 1),
       key=st.one_of(st.sampled_from(["time.end", "gas.cfd_step", "particles.diameter", "particles.count",
                                      "contact.restitution", "gas.cells", "particles.insertion.seed",
                                      "domain.upper", "gas", "time.end.x", "nope.key", "suspension.box"]),
                     st.text(min_size=1, max_size=15)),
       raw=st.one_of(st.text(max_size=15), st.sampled_from(["1e308", "1e-320", "nan", "inf", "-inf", "[1, 2]",
                                                             "{a = 1}", "true", "'5 mm'", "99999999999999999999"])))
def test_set_overrides_are_refused_cleanly(index, key, raw):
    path, _ = CASES[index]
    try:
        overrides = dict([parse_override(f"{key}={raw}")])
        load_case(path, overrides)
    except CaseError as exc:
        assert exc.problems and all(fuzz_cases.KEY_PATTERN.match(p) for p in exc.problems), exc.problems


def _check(path):
    result = subprocess.run([sys.executable, "-m", "fvdem", "check", str(path)], capture_output=True, text=True,
                            cwd=ROOT)
    return result.returncode, result.stderr.strip().splitlines()


@pytest.mark.parametrize("kind", ["binary", "empty", "directory", "missing", "not-toml"])
def test_command_line_refuses_unreadable_input_with_one_line(tmp_path, kind):
    path = tmp_path / "case.toml"
    if kind == "binary":
        path.write_bytes(b"\xff\xfe\x00\x01binary")
    elif kind == "empty":
        path.write_text("")
    elif kind == "directory":
        path.mkdir()
    elif kind == "not-toml":
        path.write_text("[domain\nupper = ")
    code, lines = _check(path)
    assert code == 2
    assert len(lines) == 1 and lines[0].startswith("fvdem: error:") and "Traceback" not in lines[0]


def test_check_refuses_what_run_refuses(tmp_path):
    """A case whose settled bed does not exist is refused by ``fvdem check`` as by ``fvdem run``."""
    case = tmp_path / "case.toml"
    case.write_text('[particles]\ncount = 10\ninitial_state = "missing.npz"\n')
    code, lines = _check(case)
    assert code == 2 and "particles.initial_state" in lines[0]


def test_python_dash_m_fvdem_is_the_command():
    result = subprocess.run([sys.executable, "-m", "fvdem", "check", "cases/demo.toml"], capture_output=True,
                            text=True, cwd=ROOT)
    assert result.returncode == 0 and "OK" in result.stdout
