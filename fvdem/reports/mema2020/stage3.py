"""Stage 3's study file composed from the decisions (issue 66, docs/bed-dynamics.md, "Stage 3", composition fixed on
2026-12-07 before any of its runs), so that the re-run of the paper's study follows from the archived decisions
alone:

1. *Settings*, per shape (AR-1: the families on ``ar1.toml``; AR-4 MP's decisions for the three AR-4 families on
   ``ar4_mp.toml``, ``ar4_sp.toml``, ``ar4_mp_drag.toml``): stage 2's, with the contact settings' choice, each screening
   factor rule 3 changes (confirmed at the new contact settings where those change too: ``confirmation_study``), and
   the velocity reference of the Umf rule (``umf_reference``: the experiment's Umf within 5 %, else stage 2's own
   reference kept). Run settings go to the shape's families; its beds
   take a bed preparation, and settle at their own case's contact settings (the paper's), as the beds of the runs
   that decided the contact settings did (``tools/stage3_study.py`` gives both).
2. *Points*: every point of a shape whose settings change, from its base families (stage 2's families less the
   replica series ``<family>_t95`` and ``<family>_expansion``, which the plan's rounds bring back); a shape without a
   change keeps stage 2's families, beds and points as they were, so that ``fvdem study --adopt`` counts its runs as
   they are.
3. *Replicas*: two a point for a changed shape (one where stage 2 ran one: the roofed points of the paper's column,
   kept for the record); then the rounds of ``plan.toml``.
"""
from __future__ import annotations

import copy
import re
from pathlib import PurePosixPath

import tomli_w

from .families import series_base

CONTACT_KEYS = ("contact.normal_stiffness", "time.dem_step", "gas.cfd_step")  # the contact settings' choice
SHAPE_CASES = {"AR-1": {"ar1.toml", "bed_ar1.toml"},
               "AR-4 MP": {"ar4_mp.toml", "ar4_sp.toml", "ar4_mp_drag.toml", "bed_ar4.toml"}}
EXPERIMENT_UMF = {"AR-1": 1.58, "AR-4 MP": 1.7}  # [m/s] Mema et al., Table 6
UMF_WITHIN = 0.05  # the Umf rule: within this of the experiment, the study returns to the paper's velocity definition
REPLICAS = 2  # a changed shape's replicas a point (stage 2's)
NEW_BED = "_stage3"  # a changed shape's beds: stage 2's names with this (their runs are new runs, never adopted)
CONFIRM_REPLICAS = 3  # a factor's runs a level in its confirmation at new contact settings


def study_toml(table: dict) -> str:
    """A study table as TOML whose ``[[points]]``, ``[[exclude]]`` and ``[[durations]]`` (each list of tables) are
    written as arrays of tables, so that a round can append more of them (``round_toml``): tomli_w writes a short
    list of tables as an inline array, which TOML forbids to extend."""
    arrays = {k: v for k, v in table.items() if isinstance(v, list) and v and all(isinstance(e, dict) for e in v)}
    text = tomli_w.dumps({k: v for k, v in table.items() if k not in arrays}).rstrip("\n")
    for key, entries in arrays.items():
        for entry in entries:
            text += f"\n\n[[{key}]]\n" + tomli_w.dumps(entry).rstrip("\n")
    return text + "\n"


def shape_of_case(path: str) -> str | None:
    """The shape a family's or bed's case file is of (by its file name), or None."""
    name = PurePosixPath(path).name
    return next((shape for shape, cases in SHAPE_CASES.items() if name in cases), None)


def umf_reference(shape: str, measured: float) -> dict:
    """The Umf rule (docs/bed-dynamics.md, "Umf with the preferred bed"): fvdem's Umf with the preferred bed within
    5 % of the experiment's, the study returns to the paper's velocity definition (``gas.umf`` the experiment's);
    beyond, U/Umf stays referred to fvdem's own Umf (``umf`` None: stage 2's reference kept)."""
    experiment = EXPERIMENT_UMF[shape]
    off = measured / experiment - 1.0
    return {"measured": measured, "experiment": experiment, "relative": off,
            "umf": experiment if abs(off) <= UMF_WITHIN else None}


def _families(entry: dict) -> list:
    family = entry.get("family")
    return [] if family is None else [family] if isinstance(family, str) else list(family)


def _with_families(entry: dict, families: list) -> dict:
    return {**entry, "family": families[0] if len(families) == 1 else families}


def compose_stage3(stage2: dict, changes: dict) -> dict:
    """Stage 3's study table from stage 2's (``stage2``: the parsed study file) and ``changes``: per shape that
    changes, ``{"set": run settings, "bed": bed settings}`` (the contact settings in both, a factor's run settings in
    ``set``, a bed preparation in ``bed``, ``gas.umf`` in ``set``). A shape absent from ``changes`` (or with both
    empty) keeps stage 2's tables as they were."""
    changed = {shape for shape, c in changes.items() if c.get("set") or c.get("bed")}
    unknown = set(changes) - set(SHAPE_CASES)
    if unknown:
        raise ValueError(f"changes for {sorted(unknown)}: the shapes are {', '.join(SHAPE_CASES)}")
    out = {k: copy.deepcopy(v) for k, v in stage2.items() if k not in ("families", "beds", "points", "exclude",
                                                                          "durations")}
    out["name"] = "mema2020_stage3"
    out["description"] = ("Mema et al. (2020), the 22 runs at the decided settings (issue 66): "
                          + (", ".join(f"{s} changed" for s in sorted(changed)) or "nothing changed"))
    out["replicas"] = REPLICAS
    kept = {}
    for name, family in stage2["families"].items():
        shape = shape_of_case(family["case"])
        if shape in changed:
            if series_base(name) is not None:
                continue  # a replica series: the plan's rounds bring it back
            family = {**family, "set": {**family.get("set", {}), **changes[shape].get("set", {})},
                      "bed": family["bed"] + NEW_BED}
            family.pop("replicas", None)
        kept[name] = copy.deepcopy(family)
    used = {f.get("bed") for f in kept.values()}
    beds = {}
    for name, bed in stage2.get("beds", {}).items():
        shape = shape_of_case(bed["case"])
        if shape in changed:  # a bed of its own name: no run of stage 2 can pass for one of stage 3 (--adopt)
            name, bed = name + NEW_BED, {**bed, "set": {**bed.get("set", {}), **changes[shape].get("bed", {})}}
            if name not in used:
                continue
        beds[name] = copy.deepcopy(bed)
    out["beds"], out["families"] = beds, kept
    for key in ("points", "exclude", "durations"):
        entries = []
        for entry in stage2.get(key, []):
            named = _families(entry)
            if not named:
                entries.append(copy.deepcopy(entry))
                continue
            for group in ([f for f in named if f in kept and shape_of_case(kept[f]["case"]) in changed],
                          [f for f in named if f in kept and shape_of_case(kept[f]["case"]) not in changed]):
                if not group:
                    continue
                entry_ = _with_families(copy.deepcopy(entry), group)
                if key == "points" and shape_of_case(kept[group[0]]["case"]) in changed:
                    if "replicas" in entry_:
                        entry_["replicas"] = min(entry_["replicas"], REPLICAS)
                    if set(entry_) <= {"family", "gas.u_over_umf", "replicas"} and entry_.get("replicas") == REPLICAS:
                        continue  # the study's two a point: the entry says nothing more
                entries.append(entry_)
        if entries:
            out[key] = entries
    return out


def confirmation_study(screening: dict, factors: list, contact: dict, bed_contact: dict) -> dict:
    """The study that confirms screening factors at new contact settings before stage 3 changes them
    (docs/bed-dynamics.md, "Stage 3", rule 1): from the screening's study table (``screening``), the design's base
    run with every factor at its study setting (``<design>_base``, the low level of all) and per factor in
    ``factors`` its high level alone (``<design>_<factor>``), at the screening's point, ``CONFIRM_REPLICAS`` runs
    each from their own beds; the runs at the ``contact`` settings, the beds settled at ``bed_contact`` (as stage
    3's: ``tools/stage3_study.py``)."""
    design = screening["design"]
    for factor in factors:
        if factor not in design["factors"]:
            raise ValueError(f"factor {factor!r}: not one of {design['name']}'s ({', '.join(design['factors'])})")
    out = {"name": f"confirm_{design['name']}",
           "description": f"{design['name']}: {', '.join(factors)} confirmed at new contact settings "
                          f"({', '.join(f'{k} = {v:g}' for k, v in contact.items())})",
           "duration": design.get("duration", screening["duration"]), "report": screening.get("report", "table"),
           "replicas": CONFIRM_REPLICAS, "settings": dict(screening.get("settings", {}))}
    out["beds"] = {name: {**bed, "set": {**bed.get("set", {}), **bed_contact}}
                   for name, bed in copy.deepcopy(screening.get("beds", {})).items()}
    levels = {"base": {}, **{factor: design["factors"][factor]["high"] for factor in factors}}
    out["families"] = {}
    for label, level in levels.items():
        overrides = dict(level)
        bed = overrides.pop("bed", design.get("bed"))
        family = {"case": design["case"], "set": {**design.get("set", {}), **contact, **overrides}}
        if bed is not None:
            family["bed"] = bed
        out["families"][f"{design['name']}_{label}"] = family
    used = {f.get("bed") for f in out["families"].values()}
    out["beds"] = {name: bed for name, bed in out["beds"].items() if name in used}
    return out


ROUND_HOURS = 20.0  # rule 3: a round adds every plan table whose added replicas cost at most this many core-hours
ROUND_MARK = "# stage 3, round "  # the comment line that opens each round appended to the study file


def round_tables(tables: dict, hours: float = ROUND_HOURS) -> tuple[list, list]:
    """A round of rule 3 (docs/bed-dynamics.md, "Stage 3"): of the plan's tables (``plan.plan_tables``), each whose
    added replicas cost at most ``hours`` core-hours at its point's runs so far, cheapest first; and apart, each
    other with why it stays (more than ``hours``: its finding stays open, said with the plan's numbers; or its
    cost unknown: no run of its point has ended). Each as ``{"family", "u_over_umf", "from", "replicas", "more",
    "core_hours", "why"}``."""
    chosen, left = [], []
    for (family, v), table in tables.items():
        more = table["replicas"] - table["from"]
        cost = table["cost"]
        entry = {"family": family, "u_over_umf": v, "from": table["from"], "replicas": table["replicas"],
                 "more": more, "core_hours": None if cost is None else more * cost / 3600.0,
                 "why": list(table["why"])}
        if entry["core_hours"] is None:
            left.append({**entry, "left": "no run of its point has ended: its cost is unknown"})
        elif entry["core_hours"] > hours:
            left.append({**entry, "left": f"{entry['core_hours']:.3g} core-hours, more than a round's {hours:g}"})
        else:
            chosen.append(entry)
    chosen.sort(key=lambda e: (e["core_hours"], e["family"], e["u_over_umf"]))
    left.sort(key=lambda e: (e["family"], e["u_over_umf"]))
    return chosen, left


def addable_series(stage2: dict, stage3: dict) -> list:
    """The replica series of stage 2 that rounds may add to stage 3's file: those of a changed shape (its base family's
    bed renamed ``NEW_BED``), which ``compose_stage3`` leaves to the rounds, whether a round has brought them back or
    not (a later round may ask one at another velocity)."""
    families = stage3.get("families", {})
    return sorted(name for name in stage2.get("families", {})
                  if series_base(name) in families
                  and families[series_base(name)].get("bed") != stage2["families"][series_base(name)].get("bed"))


def _delta(old: dict, new: dict) -> dict:
    """The settings ``new`` sets otherwise than ``old``."""
    return {k: v for k, v in new.items() if old.get(k, object()) != v}


def series_tables(stage2: dict, stage3: dict, name: str, velocities: list) -> dict:
    """What stage 3's file needs to run stage 2's replica series ``name`` at ``velocities`` alone: its family with
    the changes stage 3 made to its base family's settings (``set``) and beds (renamed ``NEW_BED`` with the changes
    made to the base's bed), that bed where the file lacks it, the ``[[durations]]`` of its base family in stage 3's
    file and then its own of stage 2 (the last that matches decides: an expansion series' 5 s), and the velocities
    of the file's axis it does not run at (``{"families": {...}, "beds": {...}, "durations": [...], "exclude": [...]}``,
    ``exclude`` a list of U/Umf). Its replicas come from the round's ``[[points]]``."""
    base = series_base(name)
    old_base, new_base = stage2["families"][base], stage3["families"][base]
    family = copy.deepcopy(stage2["families"][name])
    family["set"] = {**family.get("set", {}), **_delta(old_base.get("set", {}), new_base.get("set", {}))}
    family.pop("replicas", None)
    beds = {}
    old_bed, new_bed = old_base.get("bed"), new_base.get("bed")
    if family.get("bed") is not None and new_bed != old_bed:  # the shape's beds renamed: the series' too
        change = _delta(stage2["beds"][old_bed].get("set", {}), stage3["beds"][new_bed].get("set", {}))
        renamed = family["bed"] + NEW_BED
        if renamed not in stage3.get("beds", {}):
            bed = copy.deepcopy(stage2["beds"][family["bed"]])
            beds[renamed] = {**bed, "set": {**bed.get("set", {}), **change}}
        family["bed"] = renamed
    durations = ([_with_families(copy.deepcopy(d), [name]) for d in stage3.get("durations", [])
                  if base in _families(d)]
                 + [_with_families(copy.deepcopy(d), [name]) for d in stage2.get("durations", [])
                    if name in _families(d)])
    axis = list(stage3.get("axes", {}).get("gas.u_over_umf", []))
    return {"families": {name: family}, "beds": beds, "durations": durations,
            "exclude": [v for v in axis if v not in velocities]}


_EXCLUDE_HEAD = "[[exclude]]  # {name}: the velocities no round has asked it at (a later round narrows this list)"


def _exclude_block(name: str, velocities: list) -> str:
    """A series' own ``[[exclude]]`` as a round writes it (``narrow_exclude`` finds it again)."""
    return (_EXCLUDE_HEAD.format(name=name) + f'\nfamily = "{name}"\n"gas.u_over_umf" = '
            + "[" + ", ".join(repr(float(v)) for v in velocities) + "]")


def narrow_exclude(text: str, name: str, velocities: list) -> str | None:
    """``text`` (stage 3's file) with the velocities ``velocities`` taken out of the ``[[exclude]]`` an earlier round
    wrote for the series ``name`` (the block left as a comment once its list is empty); None where the file holds no
    such block (an exclusion written otherwise is not the rounds' to change)."""
    pattern = re.compile(re.escape(_EXCLUDE_HEAD.format(name=name)) + r'\nfamily = "' + re.escape(name)
                         + r'"\n"gas\.u_over_umf" = \[([^\]\n]*)\]')
    found = pattern.search(text)
    if found is None:
        return None
    kept = [float(v) for v in found.group(1).split(",") if v.strip() and float(v) not in velocities]
    block = (_exclude_block(name, kept) if kept
             else f"# {name}: runs at every velocity of the axis (its [[exclude]] emptied by the rounds)")
    return text[:found.start()] + block + text[found.end():]


def round_toml(chosen: list, stage2: dict, stage3: dict, number: int, said: list) -> str:
    """Round ``number``'s text to append to stage 3's file: a head (``ROUND_MARK``, then ``said``'s lines), the
    tables a replica series new to the file needs (``series_tables``, at the velocities the round asks of it; a bed
    two series share written once), and each chosen table (``round_tables``) as a ``[[points]]`` table with the
    findings that ask it and its cost. A series the file holds already, asked at a velocity an earlier round
    excluded, needs that exclusion narrowed too (``narrow_exclude``)."""
    lines = ["", f"{ROUND_MARK}{number}"] + [f"# {line}" for line in said]
    new = {}
    for entry in chosen:
        if entry["family"] not in stage3.get("families", {}):
            new.setdefault(entry["family"], []).append(entry["u_over_umf"])
    beds = dict(stage3.get("beds", {}))
    for name, velocities in sorted(new.items()):
        tables = series_tables(stage2, {**stage3, "beds": beds}, name, velocities)
        beds.update(tables["beds"])
        lines.append(f"# {name}: stage 2's replica series of {series_base(name)}, at this round's points alone")
        lines.append(tomli_w.dumps({k: tables[k] for k in ("families", "beds") if tables[k]}).rstrip("\n"))
        if tables["durations"]:
            lines.append(study_toml({"durations": tables["durations"]}).rstrip("\n"))
        if tables["exclude"]:
            lines += ["", _exclude_block(name, tables["exclude"])]
    for entry in chosen:
        lines += [""] + [f"# {why}" for why in entry["why"]]
        lines += [f"# {entry['more']} more, about {entry['core_hours']:.3g} core-hours", "[[points]]",
                  f'family = "{entry["family"]}"', f'"gas.u_over_umf" = {float(entry["u_over_umf"])!r}',
                  f"replicas = {entry['replicas']}  # {entry['from']} in the study so far"]
    return "\n".join(lines) + "\n"
