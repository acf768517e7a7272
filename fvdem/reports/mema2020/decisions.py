"""The screenings' decisions (issue 66, docs/bed-dynamics.md, "The screening"): which of the model choices that the
paper does not fix change for the re-run of the paper's study (stage 3), read from a screening's record
(``screening.json`` of ``fvdem.study.screening``) by the rule committed on 2026-12-07 before the screenings' runs:

1. the primary response: AR-1 the mixing entropy at 3 s; AR-4 MP the mixing entropy at 6 s, with the rods'
   alignment inside the bed and the corner columns' share of the gas as its early signs;
2. a factor **matters** where the 95 % interval of its main effect on the primary response excludes zero; where the
   interval reaches both zero and 10 % of the response's mean, replicas are added before anything is decided on it;
3. a factor changes only where (a) it matters, (b) its change moves the bed toward the paper's behaviour (AR-1: more
   mixed at 3 s; AR-4 MP: more mixed at 6 s, rods less flat, less gas in the corners) and (c) the paper does not
   fix the setting (rolling friction, Table 5, and the closures: lift and torque); a factor the paper fixes that
   matters is reported as a cause, never adopted (as coded: one that matters toward the paper's behaviour; one
   that matters away from it is no cause of the gap and is kept);
4. a told two-factor chain that holds a factor to be changed is resolved (a fold-over of the design) before the
   change.

Rule 3 (b) for AR-4 MP, as coded (written 2026-12-07 before any AR-4 screening run had ended): the primary response
gives the direction (more mixed at 6 s); an early sign whose own main effect is told against the paper's way (rods
flatter, more gas in the corners) withholds the change, and an untold one does not.

The stage-3 confirmation of a factor at new contact settings (docs/bed-dynamics.md, "Stage 3", rule 1) is
``confirmation``: 3 runs at its high level against 3 at its low, rule 2 on the primary response (the 95 % interval
of the difference of the means, Welch's t, in the screening's direction; runs added where it reaches both zero and
10 % of the mean).

Effects are read on every replica the design plans: until every planned run holds the primary response (and, for
AR-4 MP, its early signs) the reading is provisional and changes nothing.
"""
from __future__ import annotations

import math

from ...study.screening import MATTERS
from .spread import sample_variance, satterthwaite

FIXED = "2026-12-07"  # the date the screening rule was committed, before the screenings' runs
CONFIDENCE = 0.95  # the intervals of rule 2 (the screening report's own ``confidence``)

# rule 1: per shape, the screening design's name, its primary response and the way toward the paper's behaviour
# (+1: the paper's bed is higher in it, -1: lower), and the early signs with their ways (rule 3 b)
SCREENINGS = {
    "AR-1": {"design": "ar1", "primary": "mixing_entropy@3.0", "toward": +1, "signs": {}},
    "AR-4 MP": {"design": "ar4_mp", "primary": "mixing_entropy@6.0", "toward": +1,
                "signs": {"rod_alignment_inside": +1, "corner_gas_share": -1}},  # mean |a_z| up: rods less flat
}
# rule 3 (c): the settings the paper fixes, with where (their effects are causes, never adopted)
PAPER_FIXES = {
    "rolling": "rolling friction 0.46 (Mema et al., Table 5)",
    "lift": "the multi-particle lift closure (Mema et al., Table 1: Sanjeevi and Padding, 2020)",
    "torque": "the multi-particle torque closure (Mema et al., Table 1: Sanjeevi and Padding, 2020)",
}


def shape_of(record: dict) -> str | None:
    """The shape whose screening ``record`` is (by its design's name), or None."""
    name = record["design"]["name"]
    return next((s for s, d in SCREENINGS.items() if d["design"] == name), None)


def _main_effects(result: dict) -> dict:
    """A response's main effects by factor name (its record's ``effects`` of one term)."""
    return {e["factors"][0]: e for e in result.get("effects", []) if len(e["term"]) == 1}


def _told_way(effect: dict | None) -> int:
    """+1 or -1 where the effect's interval excludes zero (its sign), 0 where it does not or has none."""
    if effect is None or effect.get("low") is None or not effect.get("decided"):
        return 0
    return 1 if effect["estimate"] > 0 else -1


def _complete(record: dict, response: str) -> str | None:
    """None where every planned run of the design (its points times its replicas) holds ``response``; else what
    waits (effects are read on every replica: one replica of a saturated design has no error term of its own)."""
    result = record["results"].get(response, {})
    if "effects" not in result:
        return f"{response}: {result.get('waiting', 'not in the record')}"
    planned = result["points"] * record["design"]["replicas"]
    return None if result["runs"] >= planned else f"{result['runs']} of {planned} runs hold {response}"


def screening_decision(record: dict) -> dict:
    """Rules 1-4 on a screening's record: per factor its main effect on the primary response with the interval,
    ``matters`` (True, False, or None: within its interval of mattering, replicas to add first, or no interval),
    ``toward_paper`` (rule 3 b), ``paper_fixes`` (rule 3 c: where, or None) and ``decision``: "change" (the study's
    setting moves to the factor's high level for stage 3), "keep" (it does not matter, or it matters away from the
    paper's behaviour), "cause" (it matters toward the paper's behaviour but the paper fixes it: reported, never
    adopted), "add replicas" (rule 2, with ``replicas_to_tell`` a point), "fold-over first" (rule 4: a told
    two-factor chain holds it) or "waits for the early signs" (AR-4 MP: a sign not yet read). ``chains``: the told
    two-factor chains on the primary response (rule 4 reports them). ``changes``: the factors to change with their
    high level's settings, only once ``decided``: every planned run holds the primary response and the signs, and no
    factor waits. Before that the entries are a provisional reading (``waiting`` says what is missing); a primary
    response without effects yet gives none."""
    shape = shape_of(record)
    if shape is None:
        raise ValueError(f"design {record['design']['name']!r}: not one of the screenings "
                         f"({', '.join(d['design'] for d in SCREENINGS.values())})")
    rule = SCREENINGS[shape]
    primary = rule["primary"]
    result = record["results"].get(primary, {})
    out = {"shape": shape, "primary": primary, "fixed": FIXED, "rule": _rule_words(shape), "factors": {},
           "chains": [], "changes": {}, "decided": False}
    if "effects" not in result:
        out["waiting"] = _complete(record, primary)
        return out
    if result["confidence"] != CONFIDENCE:
        raise ValueError(f"design.confidence = {result['confidence']}: the rule reads {_percent(CONFIDENCE)} "
                         "intervals")
    waiting = [w for w in (_complete(record, name) for name in (primary, *rule["signs"])) if w]
    mean = result["mean"]
    effects = _main_effects(result)
    signs = {name: _main_effects(record["results"].get(name, {})) for name in rule["signs"]}
    chains = [e for e in result["effects"] if len(e["term"]) == 2 and _told_way(e)]
    out["chains"] = [{"chain": _chain(c), "factors": sorted(_chain_letters(c)), "estimate": c["estimate"],
                      "interval": [c["low"], c["high"]]} for c in chains]
    letters = record["design"]["letters"]
    changes = {}
    for factor, level in record["design"]["factors"].items():
        e = effects[factor]
        way = _told_way(e)
        entry = {"estimate": e["estimate"], "interval": [e["low"], e["high"]],
                 "relative": e["estimate"] / mean if mean else None, "paper_fixes": PAPER_FIXES.get(factor)}
        if e.get("low") is None:
            entry.update(matters=None, decision="add replicas", why="no interval (no error term yet)")
        elif way:
            entry["matters"] = True
        elif e.get("undecided"):
            entry.update(matters=None, decision="add replicas", replicas_to_tell=e.get("replicas_to_tell"),
                         why=f"the interval reaches both zero and {_percent(MATTERS)} of the mean")
        else:
            entry.update(matters=False, decision="keep")
        if entry["matters"]:
            against = [name for name, toward in rule["signs"].items() if _told_way(signs[name].get(factor)) == -toward]
            unread = [name for name in rule["signs"] if factor not in signs[name]]
            entry["toward_paper"] = way == rule["toward"] and not against
            if against:
                entry["signs_against"] = against
            held = [_chain(c) for c in chains if letters[factor] in _chain_letters(c)]
            if not entry["toward_paper"]:
                entry["decision"] = "keep"
            elif entry["paper_fixes"]:
                entry["decision"] = "cause"
            elif unread:
                entry.update(decision="waits for the early signs", why=f"no effects yet on {', '.join(unread)}")
            elif held:  # rule 4: the design folded over on this factor (``foldover = [factor]``) tells its chains
                entry.update(decision="fold-over first", chains=held, foldover=[factor])
            else:
                entry["decision"] = "change"
                changes[factor] = level["high"]
        out["factors"][factor] = entry
    if waiting:
        out["waiting"] = "; ".join(waiting)
    out["decided"] = not waiting and all(f["decision"] in ("change", "keep", "cause") for f in out["factors"].values())
    if out["decided"]:
        out["changes"] = changes
    return out


def _percent(x: float) -> str:
    return f"{100 * x:g} %"


def _chain_letters(effect: dict) -> set:
    """The factor letters of a two-factor effect's chain (its term and its two-letter aliases)."""
    return {x for word in [effect["term"], *effect["aliases"]] if len(word) == 2 for x in word}


def _chain(effect: dict) -> str:
    return " + ".join([effect["term"], *[a for a in effect["aliases"] if len(a) == 2]])


def _rule_words(shape: str) -> str:
    rule = SCREENINGS[shape]
    signs = "".join(f"; {name} told {'down' if way > 0 else 'up'} withholds it" for name, way in rule["signs"].items())
    return (f"{rule['primary']}: a main effect matters where its {_percent(CONFIDENCE)} interval excludes zero "
            f"(replicas first where it reaches both zero and {_percent(MATTERS)} of the mean); it changes "
            f"where it matters toward the paper ({'up' if rule['toward'] > 0 else 'down'}{signs}), the paper does "
            "not fix it, and no told two-factor chain holds it")


def confirmation(low: list, high: list, screened: dict) -> dict:
    """Stage 3's confirmation of a factor at new contact settings: the primary response of 3 runs at the factor's
    ``low`` level and 3 at its ``high`` (more are read as they are), rule 2 of the screening on the difference of
    the means (high less low, its 95 % interval by Welch's t). It **confirms** where the interval excludes zero on
    the side of the screening's effect (``screened``: the factor's entry of ``screening_decision``); it asks
    "add runs" where the interval reaches both zero and 10 % of the runs' mean (rule 2: runs before a decision);
    else it "does not confirm" (told the other way, or told small: the factor stays at its study setting). "open"
    with fewer than two runs a side."""
    from scipy.stats import t as student
    out = {"runs": [len(low), len(high)], "screened": screened["estimate"]}
    if len(low) < 2 or len(high) < 2:
        out["verdict"] = "open"
        return out
    sides = (low, high)
    mean = [sum(x) / len(x) for x in sides]
    terms = [sample_variance(x) / len(x) for x in sides]
    df = satterthwaite(terms, [len(x) - 1 for x in sides]) or math.inf
    half = float(student.ppf(0.5 + CONFIDENCE / 2, df)) * math.sqrt(sum(terms)) if math.isfinite(df) else 0.0
    difference = mean[1] - mean[0]
    bounds = [difference - half, difference + half]
    size = MATTERS * abs(sum(low) + sum(high)) / (len(low) + len(high))
    out.update(estimate=difference, interval=bounds, df=df)
    if bounds[0] > 0 or bounds[1] < 0:
        out["verdict"] = "confirms" if (difference > 0) == (screened["estimate"] > 0) else "does not confirm"
    elif bounds[1] >= size or bounds[0] <= -size:
        out["verdict"] = "add runs"
    else:
        out["verdict"] = "does not confirm"
    return out
