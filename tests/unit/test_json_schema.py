"""The JSON Schemas of case and study files (fvdem.json_schema): valid schemas, current copies in
docs/schema/, every shipped file accepted, and what load_case refuses for a key, type, unit, range or
choice refused by the schema too (one source of truth)."""
import json
import subprocess
import sys
import tomllib

import pytest

from fvdem.case import CaseError, case_from_dict
from fvdem.json_schema import case_schema, dumps, study_schema
from fvdem.study.sweep import BED_KEYS, FAMILY_KEYS, POINT_KEYS, STUDY_KEYS, study_from_table

from paths import ROOT

jsonschema = pytest.importorskip("jsonschema")
CASES = sorted((ROOT / "cases").glob("*.toml"))
STUDIES = sorted((ROOT / "studies").glob("*.toml"))


def errors(schema, table):
    return list(jsonschema.Draft7Validator(schema).iter_errors(table))


def test_the_schemas_are_valid_and_the_committed_copies_current():
    for kind, schema in (("case", case_schema()), ("study", study_schema())):
        jsonschema.Draft7Validator.check_schema(schema)
        committed = (ROOT / "docs" / "schema" / f"{kind}.schema.json").read_text()
        assert committed == dumps(schema), (f"docs/schema/{kind}.schema.json is stale: "
                                            f"fvdem schema --json-schema {kind} > docs/schema/{kind}.schema.json")
    result = subprocess.run([sys.executable, "-m", "fvdem", "schema", "--json-schema", "study"], capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0 and json.loads(result.stdout) == study_schema()


@pytest.mark.parametrize("path", CASES + STUDIES, ids=[p.name for p in CASES + STUDIES])
def test_every_shipped_case_and_study_file_is_accepted(path):
    schema = case_schema() if path.parent.name == "cases" else study_schema()
    assert errors(schema, tomllib.loads(path.read_text())) == []


@pytest.mark.parametrize("section, key, value", [
    ("particles", "diamter", 0.005),           # misspelt key
    ("particles", "diameter", "5.3 kg"),       # a unit of the wrong kind
    ("particles", "diameter", -1.0),           # out of range
    ("particles", "count", 1.5),               # a float for an integer
    ("particles", "shape", "cube"),            # not a choice
    ("coupling", "drag", "no-such-law"),       # not a registered name
    ("domain", "upper", [0.1, 0.1]),           # two of three
    ("output", "vtk", "yes"),                  # a string for a boolean
    ("gas", "cells", [10, 10, 70.5]),          # a float in an integer triple
])
def test_what_load_case_refuses_the_schema_refuses(section, key, value):
    table = tomllib.loads((ROOT / "cases" / "demo.toml").read_text())
    table.setdefault(section, {})[key] = value
    with pytest.raises(CaseError):
        case_from_dict(table, str(ROOT / "cases" / "demo.toml"))
    assert errors(case_schema(), table), f"{section}.{key} = {value!r} passed the schema"


def test_a_value_with_a_unit_and_a_study_with_a_wrong_key_or_case_key():
    table = tomllib.loads((ROOT / "cases" / "demo.toml").read_text())
    table["particles"]["diameter"] = "5.3 mm"
    assert errors(case_schema(), table) == []
    study = tomllib.loads((ROOT / "studies" / "smoke.toml").read_text())
    assert errors(study_schema(), {**study, "replica": 2})
    assert errors(study_schema(), {**study, "settings": {"gas.u_over_um": 2.0}})
    assert errors(study_schema(), {**study, "families": {"ar1": {"case": "x.toml", "bed": "small", "replicas": 0}}})


def test_the_study_schema_names_the_keys_the_study_loader_takes():
    """Each table of a study file: the schema's keys are the loader's (a key added to one only is a defect:
    the schema refused every study file with ``priority`` once, 2026-12-05)."""
    schema = study_schema()["properties"]
    assert set(schema) == STUDY_KEYS
    assert set(schema["beds"]["additionalProperties"]["properties"]) == BED_KEYS
    assert set(schema["families"]["additionalProperties"]["properties"]) == FAMILY_KEYS
    assert set(schema["points"]["items"]["properties"]) == set(POINT_KEYS)


@pytest.mark.parametrize("priority, accepted", [(-1, True), (1000, True), (2000, False), (1.5, False),
                                                ("low", False), (True, False)])
def test_a_priority_the_study_loader_takes_or_refuses_the_schema_does_too(priority, accepted, tmp_path):
    """``priority`` of a family and of a [[points]] table: the schema and ``study_from_table`` agree."""
    study = tomllib.loads((ROOT / "studies" / "smoke.toml").read_text())
    family = next(iter(study["families"]))
    for table in ({**study, "families": {**study["families"], family: {**study["families"][family],
                                                                        "priority": priority}}},
                  {**study, "points": [{"family": family, "priority": priority}]}):
        assert (errors(study_schema(), table) == []) is accepted
        if accepted:
            study_from_table(table, ROOT / "studies" / "smoke.toml", tmp_path / "out")
        else:
            with pytest.raises(CaseError, match="priority"):
                study_from_table(table, ROOT / "studies" / "smoke.toml", tmp_path / "out")
