"""JSON Schemas (draft 7) of case files and study files, for editors that check TOML against a
schema (Taplo / Even Better TOML in VS Code, JetBrains' TOML plugin): completion, hover text, and a
wrong key or value underlined as it is typed.

The case schema is generated from the same dataclass fields (``fvdem.case``: kind, unit, range,
choices, registry, doc) that ``load_case`` checks and ``fvdem schema`` documents, so the three cannot
drift. A schema cannot express the cross-checks (e.g. the DEM step against the collision time, the CFD
step a multiple of the DEM step); ``fvdem check`` still runs them. ``fvdem schema --json-schema case``
prints it; ``docs/schema/`` holds the committed copies (``tests/unit/test_json_schema.py`` keeps them current).
"""
from __future__ import annotations

import json
import re
from dataclasses import fields

from .case import UNITS, Case, _choices, case_as_dict

SCHEMA_VERSION = "http://json-schema.org/draft-07/schema#"  # what Taplo (Even Better TOML) reads


def _bounded(kind: str, meta: dict) -> dict:
    """``{"type": kind}`` with the field's bounds (gt, ge, lt, le) as JSON Schema keywords."""
    out = {"type": kind}
    for key, word in (("gt", "exclusiveMinimum"), ("ge", "minimum"), ("lt", "exclusiveMaximum"), ("le", "maximum")):
        if meta.get(key) is not None:
            out[word] = meta[key]
    return out


def _number(meta: dict) -> dict:
    """A number with the field's bounds; with a unit also a ``"5.3 mm"`` string in one of its units."""
    number = _bounded("number", meta)
    if not meta.get("unit"):
        return number
    units = "|".join(re.escape(u) for u in UNITS[meta["unit"]])
    text = {"type": "string", "pattern": rf"^\s*[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?\s+({units})\s*$",
            "description": f"a number and a unit: {', '.join(UNITS[meta['unit']])}"}
    return {"anyOf": [number, text]}


def _value(meta: dict, live: bool) -> dict:
    kind = meta["kind"]
    if kind == "float":
        return _number(meta)
    if kind == "int":
        return _bounded("integer", meta)
    if kind == "bool":
        return {"type": "boolean"}
    if kind == "str":
        choices = _choices(meta) if (live or not meta.get("registry")) else None
        return {"type": "string", **({"enum": list(choices)} if choices else {})}
    if kind == "schedule":  # [time, value] pairs
        pair = [_number(dict(kind="float", unit="time", ge=0.0)), _number(dict(meta, kind="float"))]
        return {"type": "array", "items": {"type": "array", "items": pair, "minItems": 2, "maxItems": 2}}
    item = _value(dict(meta, kind={"vec3": "float", "bool3": "bool", "int3": "int"}[kind]), live)
    return {"type": "array", "items": item, "minItems": 3, "maxItems": 3}


def _section(cls, defaults, live: bool) -> dict:
    properties = {}
    for f in fields(cls):
        meta = f.metadata
        if meta.get("kind") == "internal":
            continue
        if meta.get("kind") == "section":
            properties[f.name] = {**_section(f.default_factory, defaults.get(f.name, {}), live),
                                  **({"description": meta["doc"]} if meta.get("doc") else {})}
            continue
        value = _value(meta, live)
        if meta.get("optional"):
            value["description"] = "optional; " + (meta.get("doc") or "")
        elif meta.get("doc"):
            value["description"] = meta["doc"]
        if f.name in defaults:
            value["default"] = defaults[f.name]
        properties[f.name] = value
    return {"type": "object", "properties": properties, "additionalProperties": False}


def case_schema(live: bool = True) -> dict:
    """The JSON Schema of a case file. ``live``: registry-backed keys (drag, lift, torque, voidage) list
    today's registered names as an enum."""
    schema = _section(Case, case_as_dict(Case()), live)
    return {"$schema": SCHEMA_VERSION, "title": "fvdem case file",
            "description": "A case of fvdem (CFD-DEM for fluidized beds): docs/case-reference.md", **schema}


def case_keys(cls=Case, prefix: str = "") -> list[str]:
    """Every dotted case key (``gas.u_over_umf``), the keys a study's settings and ``set`` tables take."""
    keys = []
    for f in fields(cls):
        if f.metadata.get("kind") == "internal":
            continue
        if f.metadata.get("kind") == "section":
            keys += case_keys(f.default_factory, f"{prefix}{f.name}.")
        else:
            keys.append(prefix + f.name)
    return keys


def study_schema() -> dict:
    """The JSON Schema of a study file (``fvdem.study``): its tables, the case keys its settings take."""
    from .study import CLUSTER_KINDS, REPORTS, report_for
    from .study.sweep import PRIORITY_SPAN, REPLICAS_SPAN
    report_for(None)  # every registered report
    settings = {"type": "object", "propertyNames": {"enum": case_keys()},
                "description": "case keys (dotted, e.g. \"gas.inlet_ramp\") and their values"}
    seconds = {"type": "number", "exclusiveMinimum": 0, "maximum": 1e6}
    replicas = {"type": "integer", "minimum": REPLICAS_SPAN[0], "maximum": REPLICAS_SPAN[1],
                "description": "repeats; replica k >= 2 starts from its own bed (insertion seed + k - 1)"}
    priority = {"type": "integer", "minimum": PRIORITY_SPAN[0], "maximum": PRIORITY_SPAN[1], "default": 0,
                "description": "the queue's tier of these runs while not started, higher first (a later tranche "
                               "at -1)"}
    bed = {"type": "object", "required": ["case"], "additionalProperties": False,
           "properties": {"case": {"type": "string", "description": "a case file, relative to the study file"},
                          "set": settings}}
    family = {"type": "object", "required": ["case"], "additionalProperties": False,
              "properties": {**bed["properties"],
                             "bed": {"type": "string", "description": "the bed (a [beds] name) its runs start from"},
                             "duration": {**seconds, "description": "this family's own simulated seconds"},
                             "replicas": replicas, "priority": priority}}
    level = {"type": "object", "properties": {"bed": {"type": "string", "description": "start from this bed"}},
             "propertyNames": {"enum": ["bed", *case_keys()]},
             "description": "case keys and values of this level ({} for the base run's); bed: another of the "
                            "study's beds"}
    factor = {"type": "object", "required": ["low", "high"], "additionalProperties": False,
              "properties": {"low": {"$ref": "#/$defs/level"}, "high": {"$ref": "#/$defs/level"},
                             "centre": {"$ref": "#/$defs/level"}, "doc": {"type": "string"}}}
    design = {"type": "object", "required": ["case", "factors", "responses"], "additionalProperties": False,
              "description": "a two-level factorial over named factors (docs/screening.md)",
              "properties": {**family["properties"],
                             "name": {"type": "string", "pattern": "^[A-Za-z][A-Za-z0-9_]*$", "default": "design",
                                      "description": "the family and name prefix of the design's runs"},
                             "factors": {"type": "object", "minProperties": 2, "additionalProperties": factor,
                                         "description": "factors lettered A, B, ... in the file's order"},
                             "generators": {"type": "array", "items": {"type": "string"},
                                            "description": "'E = ABC' (letters) or 'e = a*b*c' (names)"},
                             "fraction": {"type": "integer", "minimum": 1,
                                          "description": "p of a 2^(k-p) fraction with the standard generators"},
                             "centre_points": {"type": "integer", "minimum": 0, "maximum": 100, "default": 0},
                             "foldover": {"anyOf": [{"const": "all"}, {"type": "array", "minItems": 1,
                                                                       "items": {"type": "string"}}],
                                          "description": "a second half of runs with these factors' signs "
                                                         "reversed ('all': every factor): it de-aliases chains"},
                             "responses": {"type": "array", "minItems": 1, "items": {"type": "string"},
                                           "description": "table columns, or series columns at a time "
                                                          "('mixing_entropy@3.0')"},
                             "censored": {"type": "array", "items": {"type": "string"},
                                          "description": "responses a run may end without (its end stands for them)"},
                             "confidence": {"type": "number", "minimum": 0.5, "exclusiveMaximum": 1,
                                            "default": 0.95}}}
    return {"$schema": SCHEMA_VERSION, "title": "fvdem study file",
            "description": "A sweep of fvdem runs (fvdem study): docs/studies.md",
            "type": "object", "required": ["duration"], "anyOf": [{"required": ["families"]}, {"required": ["design"]}],
            "additionalProperties": False, "$defs": {"level": level},
            "properties": {
                "name": {"type": "string"}, "description": {"type": "string"},
                "duration": {**seconds, "description": "simulated seconds of every run (time.end)"},
                "replicas": replicas, "settings": settings,
                "report": {"enum": sorted(REPORTS), "default": "table",
                           "description": "the study's table, figures and findings (fvdem laws report)"},
                "beds": {"type": "object", "additionalProperties": bed,
                         "description": "settled beds, each prepared once before the runs that start from it"},
                "families": {"type": "object", "minProperties": 1, "additionalProperties": family,
                             "description": "families of runs: a base case and its own settings"},
                "design": design,
                "axes": {"type": "object", "propertyNames": {"enum": case_keys()},
                         "additionalProperties": {"type": "array", "minItems": 1},
                         "description": "case keys and the values to sweep (every combination)"},
                "exclude": {"type": "array", "items": {"type": "object", "minProperties": 1},
                            "description": "runs to leave out: the family and axis values (each a value or a list) "
                                           "they match"},
                "durations": {"type": "array",
                              "items": {"type": "object", "required": ["duration"],
                                        "properties": {"duration": seconds}},
                              "description": "runs with their own simulated seconds: duration and the family "
                                             "and axis values (each a value or a list) they match; the last "
                                             "matching table decides"},
                "points": {"type": "array",
                           "items": {"type": "object",
                                     "anyOf": [{"required": ["duration"]}, {"required": ["replicas"]},
                                               {"required": ["priority"]}],
                                     "properties": {"duration": seconds, "replicas": replicas,
                                                    "priority": priority}},
                           "description": "runs with their own simulated seconds, replicas (e.g. one more where "
                                          "two lie within their spread) and/or priority: the family and axis "
                                          "values (each a value or a list) they match; after [[durations]], the "
                                          "last matching table decides each key"},
                "cluster": {"type": "object", "properties": {"kind": {"enum": list(CLUSTER_KINDS)},
                                                              "workers": {"type": "integer", "minimum": 1}},
                            "description": "where the runs go: local, or dask-jobqueue's slurm, pbs, sge, lsf "
                                           "with that class's options (memory required)"}}}


def dumps(schema: dict) -> str:
    return json.dumps(schema, indent=1, ensure_ascii=False) + "\n"
