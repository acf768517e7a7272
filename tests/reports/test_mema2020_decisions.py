"""The screenings' decisions (docs/bed-dynamics.md, "The screening", rules 1-4; fvdem.reports.mema2020.decisions),
on screenings of known effects run through the generic screening report: a factor the paper does not fix that
raises the entropy changes, one the paper fixes is a cause, one that lowers it or does nothing is kept, one within
its interval of mattering waits for replicas, a told chain holding it waits for a fold-over, and for AR-4 MP an early
sign told against the paper withholds the change. The stage-3 confirmation (3 runs a side) against Welch's test of
scipy."""
import itertools
import json

import numpy as np
import pytest
from scipy.stats import ttest_ind

from fvdem.reports.mema2020.decisions import PAPER_FIXES, confirmation, screening_decision
from fvdem.study.design import two_level
from fvdem.study.screening import screening

AR1 = {"rolling": ("A", {"contact.rolling_friction": 0.0}), "wall": ("B", {"contact.wall_friction": 0.1}),
       "packing": ("C", {"bed": "ar1_dense"}), "start": ("D", {"gas.inlet_ramp": 0.0}),
       "voidage": ("E", {"coupling.voidage": "trilinear"}), "gaswall": ("F", {"gas.walls": "free-slip"})}
AR4 = {**AR1, "lift": ("G", {"coupling.lift": "none"}), "torque": ("H", {"coupling.torque": "none"})}


def _screen(tmp_path, name, factors, generators, responses, effects, noise, seed=0, replicas=2, drop=0,
            planned=None, unread=None):
    """Run the generic screening report on a synthetic design: each response ``base + sum(effect / 2 * coded)``
    plus N(0, noise) (``effects``: response -> (base, {term: effect})), entropy columns as time series; ``drop``:
    leave out the first point's runs; ``planned``: the design's replicas where fewer ran; ``unread``: a response
    the first point's runs do not hold yet."""
    letters = {f: letter for f, (letter, _) in factors.items()}
    built = two_level(len(factors), generators)
    design = {"name": name, "label": built.label(), "letters": letters, "generators": generators,
              "defining_relation": built.defining_relation(), "resolution": built.resolution,
              "aliases": {x: built.aliases(x) for x in built.letters}, "replicas": planned or replicas,
              "centre_points": 0,
              "responses": responses, "censored": [], "confidence": 0.95,
              "factors": {f: {"letter": letter, "low": {}, "high": high} for f, (letter, high) in factors.items()}}
    rng = np.random.default_rng(seed)
    rows, series = [], {}
    for r, i in itertools.product(range(replicas), range(built.runs)):
        coded = built.matrix[i]
        run = f"{name}_{i + 1:02d}_r{r + 1}"
        row = {"name": run, "family": name, "status": "finished", "simulated_seconds": 8.0,
               **{f"design.{f}": int(c) for f, c in zip(factors, coded)}}
        curves = {}
        for response, (base, terms) in effects.items():
            value = base + rng.normal(0.0, noise)
            for term, effect in terms.items():
                value += effect / 2 * np.prod([coded[built.letters.index(x)] for x in term])
            if response == unread and i == 0:
                continue
            if "@" in response:
                column, at = response.split("@")
                curves.setdefault(column, {})[float(at)] = value
            else:
                row[response] = value
        series[run] = {"time": [0.0, 8.0]} if curves else None
        for column, points in curves.items():  # a straight line through the value at its time
            (at, value), = points.items()
            series[run][column] = [value - 0.01 * at, value + 0.01 * (8.0 - at)]
        rows.append(row)
    if drop:
        rows = [r for r in rows if not r["name"].startswith(f"{name}_01_")]
    screening(tmp_path, design, rows, series)
    return json.loads((tmp_path / "screening.json").read_text())


def _ar1(tmp_path, terms, noise=0.005, **kw):
    return _screen(tmp_path, "ar1", AR1, ["E = ABC", "F = BCD"], ["mixing_entropy@3.0"],
                   {"mixing_entropy@3.0": (0.6, terms)}, noise, **kw)


def test_a_free_setting_that_mixes_the_bed_faster_changes_and_a_fixed_one_is_a_cause(tmp_path):
    d = screening_decision(_ar1(tmp_path, {"D": 0.12, "A": 0.15, "E": -0.10}))
    f = d["factors"]
    assert f["start"]["decision"] == "change" and f["start"]["matters"] and f["start"]["toward_paper"]
    assert f["start"]["interval"][0] > 0 and f["start"]["estimate"] == pytest.approx(0.12, abs=0.01)
    assert f["rolling"]["decision"] == "cause" and f["rolling"]["paper_fixes"] == PAPER_FIXES["rolling"]
    assert f["voidage"]["decision"] == "keep" and f["voidage"]["matters"] and not f["voidage"]["toward_paper"]
    for factor in ("wall", "packing", "gaswall"):  # nothing: told small (the interval inside +- 10 % of 0.6)
        assert f[factor]["matters"] is False and f[factor]["decision"] == "keep"
    assert d["changes"] == {"start": {"gas.inlet_ramp": 0.0}} and d["decided"]


def test_an_effect_within_its_interval_of_mattering_waits_for_replicas(tmp_path):
    d = screening_decision(_ar1(tmp_path, {"D": 0.05}, noise=0.06, seed=3))
    waiting = [f for f, e in d["factors"].items() if e["decision"] == "add replicas"]
    assert waiting and not d["decided"] and d["changes"] == {}
    for f in waiting:
        e = d["factors"][f]
        assert e["matters"] is None and e["interval"][0] < 0 < e["interval"][1] and e["replicas_to_tell"] >= 2
        assert max(abs(x) for x in e["interval"]) > 0.1 * 0.6


def test_a_told_chain_that_holds_the_factor_to_change_asks_a_fold_over(tmp_path):
    """2^(6-2), E = ABC, F = BCD: AD is aliased with EF; a told AD + EF chain holds D (start) and A."""
    d = screening_decision(_ar1(tmp_path, {"D": 0.12, "AD": 0.08}))
    start = d["factors"]["start"]
    assert start["decision"] == "fold-over first" and start["chains"] == ["AD + EF"]
    assert d["changes"] == {} and not d["decided"]


def test_a_screening_still_waiting_for_design_points_decides_nothing(tmp_path):
    d = screening_decision(_ar1(tmp_path, {"D": 0.12}, replicas=1, drop=1))
    assert "waiting" in d and d["factors"] == {} and not d["decided"]


def _ar4(tmp_path, alignment_terms, corner_terms=None, entropy_terms=None, unread=None):
    responses = ["mixing_entropy@6.0", "rod_alignment_inside", "corner_gas_share"]
    effects = {"mixing_entropy@6.0": (0.5, entropy_terms or {"C": 0.15, "E": 0.15}),
               "rod_alignment_inside": (0.4, alignment_terms), "corner_gas_share": (0.3, corner_terms or {})}
    return _screen(tmp_path, "ar4_mp", AR4, ["E = BCD", "F = ACD", "G = ABC", "H = ABD"], responses, effects,
                   0.005, unread=unread)


def test_ar4_an_early_sign_told_against_the_paper_withholds_the_change(tmp_path):
    """Packing (C) and voidage (E) both mix the AR-4 bed faster at 6 s; voidage also lays the rods flatter."""
    d = screening_decision(_ar4(tmp_path, {"E": -0.08}))
    assert d["shape"] == "AR-4 MP" and d["primary"] == "mixing_entropy@6.0"
    assert d["factors"]["packing"]["decision"] == "change"
    assert d["factors"]["voidage"]["decision"] == "keep"
    assert d["factors"]["voidage"]["signs_against"] == ["rod_alignment_inside"]
    assert d["changes"] == {"packing": {"bed": "ar1_dense"}}


def test_ar4_more_gas_in_the_corners_withholds_the_change_too(tmp_path):
    d = screening_decision(_ar4(tmp_path, {}, corner_terms={"C": 0.06}))
    assert d["factors"]["packing"]["decision"] == "keep"
    assert d["factors"]["packing"]["signs_against"] == ["corner_gas_share"]
    assert d["factors"]["voidage"]["decision"] == "change" and d["changes"] == {"voidage": AR4["voidage"][1]}
    # less gas in the corners is the paper's way: no veto
    d = screening_decision(_ar4(tmp_path, {}, corner_terms={"C": -0.06}))
    assert d["factors"]["packing"]["decision"] == "change"


def test_ar4_lift_and_torque_are_the_papers_closures_and_a_cause_where_they_matter(tmp_path):
    d = screening_decision(_ar4(tmp_path, {}, entropy_terms={"E": 0.15, "G": 0.12, "H": -0.12}))
    assert {"lift", "torque", "rolling"} <= set(PAPER_FIXES)
    assert d["factors"]["lift"]["decision"] == "cause"  # no lift mixes the bed faster: a cause, not adopted
    assert d["factors"]["torque"]["decision"] == "keep"  # no torque mixes slower: no cause of the gap
    assert d["factors"]["voidage"]["decision"] == "change" and set(d["changes"]) == {"voidage"}


def test_ar4_an_early_sign_not_read_yet_holds_every_change(tmp_path):
    d = screening_decision(_ar4(tmp_path, {}, unread="corner_gas_share"))
    assert d["factors"]["voidage"]["decision"] == "waits for the early signs"
    assert "corner_gas_share" in d["waiting"] and not d["decided"] and d["changes"] == {}


def test_a_reading_before_every_replica_has_run_is_provisional(tmp_path):
    """Every design point once (16 of 32 runs): the effects are read, nothing is decided or changed."""
    d = screening_decision(_ar1(tmp_path, {"D": 0.12}, replicas=1, planned=2))
    assert d["factors"]["start"]["decision"] == "change"  # the provisional reading
    assert d["waiting"] == "16 of 32 runs hold mixing_entropy@3.0" and not d["decided"] and d["changes"] == {}


def test_an_effect_without_an_interval_waits_and_a_cause_needs_no_fold_over(tmp_path):
    record = _ar1(tmp_path, {"A": 0.15, "AD": 0.08})
    d = screening_decision(record)
    assert d["factors"]["rolling"]["decision"] == "cause"  # never adopted: the chain AD + EF holds nothing
    assert [c["chain"] for c in d["chains"]] == ["AD + EF"] and d["decided"]
    wall = next(e for e in record["results"]["mixing_entropy@3.0"]["effects"] if e["term"] == "B")
    wall["low"] = wall["high"] = None
    d = screening_decision(record)
    assert d["factors"]["wall"]["decision"] == "add replicas" and not d["decided"]


def test_a_design_that_is_not_a_screening_of_the_paper_is_refused(tmp_path):
    record = _ar1(tmp_path, {})
    record["design"]["name"] = "mine"
    with pytest.raises(ValueError, match="'mine': not one of the screenings"):
        screening_decision(record)
    record["design"]["name"] = "ar1"
    record["results"]["mixing_entropy@3.0"]["confidence"] = 0.9
    with pytest.raises(ValueError, match="the rule reads 95 % intervals"):
        screening_decision(record)


@pytest.mark.parametrize("low, high, screened, verdict", [
    ([0.60, 0.62, 0.58], [0.75, 0.78, 0.73], 0.12, "confirms"),  # clearly up, as screened
    ([0.60, 0.62, 0.58], [0.75, 0.78, 0.73], -0.12, "does not confirm"),  # up, screened down
    ([0.60, 0.62, 0.58], [0.50, 0.47, 0.52], -0.12, "confirms"),  # down, as screened
    ([0.60, 0.62, 0.58], [0.50, 0.47, 0.52], 0.12, "does not confirm"),
    ([0.60, 0.66, 0.55], [0.64, 0.70, 0.61], 0.12, "add runs"),  # the interval reaches 0 and 10 % of the mean
    ([0.600, 0.602, 0.598, 0.600], [0.605, 0.601, 0.603], 0.12, "does not confirm"),  # told smaller than 10 %
])
def test_the_confirmation_at_new_contact_settings_is_welchs_test(low, high, screened, verdict):
    c = confirmation(low, high, {"estimate": screened})
    welch = ttest_ind(high, low, equal_var=False)
    assert c["verdict"] == verdict
    assert c["estimate"] == pytest.approx(np.mean(high) - np.mean(low))
    assert (c["interval"][0] > 0 or c["interval"][1] < 0) == (welch.pvalue < 0.05)
    if verdict == "add runs":
        assert max(abs(x) for x in c["interval"]) >= 0.1 * np.mean(low + high)
    assert confirmation(low[:1], high, {"estimate": screened})["verdict"] == "open"
