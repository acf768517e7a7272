"""tools/bit_identity.py: the record of a coupled case's state and the comparison of two records."""
import json
import subprocess
import sys

import numpy as np

from paths import ROOT, TOOLS

sys.path.append(str(TOOLS))  # noqa: E402 (a tool imported as a module; appended, never shadowing)
import bit_identity  # noqa: E402


def test_the_digest_sees_values_dtype_and_shape():
    a = np.arange(6, dtype=np.float64)
    assert bit_identity.digest(a) == bit_identity.digest(a.copy())
    assert bit_identity.digest(a) != bit_identity.digest(a.astype(np.float32))
    assert bit_identity.digest(a) != bit_identity.digest(a.reshape(2, 3))
    b = a.copy()
    b[3] = np.nextafter(b[3], 10.0)  # one ulp
    assert bit_identity.digest(a) != bit_identity.digest(b)


def test_a_changed_array_is_named_and_an_added_one_listed_apart():
    base = {"case": {"steps": 3, "arrays": {"x": "1", "v": "2"}}}
    same = {"case": {"steps": 3, "arrays": {"x": "1", "v": "2", "bridge.stream": "9"}}}
    lines = bit_identity.compare(base, same)
    assert lines[-1] == "IDENTICAL" and "bridge.stream" in lines[0]
    moved = {"case": {"steps": 3, "arrays": {"x": "1", "v": "3"}}}
    lines = bit_identity.compare(base, moved)
    assert lines[-1].startswith("DIFFERENT: 1") and "(v)" in lines[0]


def test_one_case_recorded_twice_is_identical(tmp_path):
    """The record is deterministic: the same tree twice gives the same hashes (one thread)."""
    files = []
    for k in range(2):
        out = tmp_path / f"r{k}.json"
        subprocess.run([sys.executable, str(ROOT / "tools" / "bit_identity.py"), "--cases", "suspension",
                        "--out", str(out)], check=True, capture_output=True)
        files.append(out)
    record = json.loads(files[0].read_text())
    assert record["suspension"]["steps"] == 20 and len(record["suspension"]["arrays"]) > 20
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "bit_identity.py"), "--compare", *map(str, files)],
                            capture_output=True, text=True)
    assert result.returncode == 0 and result.stdout.strip().endswith("IDENTICAL")


def test_a_run_stopped_half_way_and_resumed_lands_on_the_whole_run(tmp_path):
    """Every array of the state, the gas solver's counters included, is the whole run's after a stop at half
    way and a resume (the counters once restarted when no factorization was restored)."""
    tool = [sys.executable, str(ROOT / "tools" / "bit_identity.py"), "--cases", "suspension"]
    subprocess.run([*tool, "--out", str(tmp_path / "whole.json")], check=True, capture_output=True)
    subprocess.run([*tool, "--stop-half", str(tmp_path / "half")], check=True, capture_output=True)
    subprocess.run([*tool, "--resume", str(tmp_path / "half"), "--out", str(tmp_path / "resumed.json")], check=True,
                   capture_output=True)
    result = subprocess.run([*tool[:2], "--compare", str(tmp_path / "whole.json"), str(tmp_path / "resumed.json")],
                            capture_output=True, text=True)
    assert result.returncode == 0, result.stdout
