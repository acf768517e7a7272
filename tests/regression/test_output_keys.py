"""Every case in cases/ writes the timeseries columns and summary keys recorded before the scenes
restructuring (issue 15): ``tests/output_keys.py`` recorded them with the code of b38a3bd; the `timings` table (issue 16)
and `provenance.cpu` (2026-12-06) were added on purpose since."""
import json

import pytest

from output_keys import CASES, RECORD, outputs


@pytest.mark.parametrize("name", CASES)
def test_case_writes_the_recorded_outputs(name, tmp_path):
    record = json.loads(RECORD.read_text())
    assert name in record, f"cases/{name}.toml is new: record its outputs with python tests/output_keys.py"
    got = outputs(name, tmp_path / name)
    assert got["timeseries"] == record[name]["timeseries"]  # in order: a CSV may be read by position
    assert sorted(got["summary"]) == sorted(record[name]["summary"])  # a JSON object has no order


def test_every_recorded_case_still_exists():
    assert sorted(json.loads(RECORD.read_text())) == CASES
