"""The second set of rules of seed 000's findings (issue 66; fvdem.reports.mema2020.readings), fixed before the
study's stage 3: each decides on rows of known numbers as its rule says, and the first set's verdicts on the
committed stage-2 archive stay what they were."""
import json

import numpy as np
import pytest

from fvdem.reports.mema2020 import readings
from fvdem.reports.mema2020.rules import check_findings
from fvdem.reports.mema2020.table import entropy_columns

from paths import ROOT


def _rows(family, v, window=None, t95=None, dense=None, ends=None, n=None):
    """Table rows of ``family`` at U/Umf ``v``: one per value of the lists given (window entropy, t95, dense-bed
    expansion, end time)."""
    n = n or len(next(x for x in (window, t95, dense) if x is not None))
    rows = []
    for k in range(n):
        rows.append({"name": f"{family}_{v}_r{k + 1}", "family": family, "gas.u_over_umf": v, "status": "finished",
                     "mixing_entropy_window": None if window is None else window[k],
                     "t95": None if t95 is None else t95[k],
                     "simulated_seconds": (ends or [20.0] * n)[k],
                     "dense_bed_expansion": None if dense is None else dense[k]})
    return rows


def test_the_entropy_columns_read_the_curve_at_fixed_times_and_hold_a_mixed_bed_at_its_end():
    time = np.arange(0.0, 6.01, 0.01)
    series = {"time": time, "mixing_entropy": np.minimum(time / 5.0, 0.96)}
    mixed = entropy_columns(series, ended_mixed=True)
    assert mixed["mixing_entropy_at_2"] == pytest.approx(0.4) and mixed["mixing_entropy_at_8"] == pytest.approx(0.96)
    # the window 1-8 s every 0.5 s: t/5 up to 4.8 s, then 0.96 (held past 6 s)
    expected = np.mean([min(t / 5.0, 0.96) for t in np.arange(1.0, 8.01, 0.5)])
    assert mixed["mixing_entropy_window"] == pytest.approx(expected)
    going = entropy_columns(series, ended_mixed=False)  # a run that has not reached 8 s: no window yet
    assert going["mixing_entropy_at_8"] is None and going["mixing_entropy_window"] is None
    assert going["mixing_entropy_at_4"] == pytest.approx(0.8)


def test_the_entropy_curve_rule_holds_where_the_replicas_tell_the_order_and_decides_against_the_reverse():
    higher = _rows("ar4_mp", 1.6, window=[0.60, 0.62, 0.61]) + _rows("ar4_mp", 1.7, window=[0.72, 0.70, 0.71])
    lower = _rows("ar1", 1.6, window=[0.45, 0.44, 0.46]) + _rows("ar1", 1.7, window=[0.55, 0.56, 0.57])
    claim = "AR-4 above AR-1"
    assert readings.entropy_higher(higher + lower, "ar4_mp", "ar1", (1.6, 1.7), claim, "")["verdict"] == "holds"
    swapped = [{**r, "family": "ar1" if r["family"] == "ar4_mp" else "ar4_mp"} for r in higher + lower]
    assert readings.entropy_higher(swapped, "ar4_mp", "ar1", (1.6, 1.7), claim, "")["verdict"] == "does not hold"
    noisy = _rows("ar4_mp", 1.6, window=[0.3, 0.8]) + _rows("ar1", 1.6, window=[0.5, 0.52])
    finding = readings.entropy_higher(noisy, "ar4_mp", "ar1", (1.6,), claim, "")
    assert finding["verdict"] == "open" and "within their spread" in finding["why"]
    assert "the paper: " in finding["rule"] and finding["readings"] == "second" and finding["fixed"] == "2026-12-07"


def test_little_change_is_one_equivalence_test_at_20_percent():
    tight = (_rows("ar1", 2.3, t95=[3.3, 3.4, 3.35]) + _rows("ar1", 2.6, t95=[3.2, 3.25, 3.3])
             + _rows("ar1", 2.9, t95=[3.1, 3.15, 3.2]))
    assert readings.little_change(tight, "ar1", "")["verdict"] == "holds"
    apart = (_rows("ar1", 2.3, t95=[5.0, 5.1, 5.05]) + _rows("ar1", 2.6, t95=[3.2, 3.25, 3.3])
             + _rows("ar1", 2.9, t95=[3.1, 3.15, 3.2]))
    assert readings.little_change(apart, "ar1", "")["verdict"] == "does not hold"
    unmixed = apart + _rows("ar1", 2.9, t95=[None])
    assert readings.little_change(unmixed, "ar1", "")["verdict"] == "open"


def test_the_larger_fall_counts_an_unmixed_run_at_its_end_as_a_bound():
    ar1 = _rows("ar1", 1.6, t95=[17.0, 16.5, 16.8]) + _rows("ar1", 2.0, t95=[5.0, 5.2, 4.9])
    ar4 = _rows("ar4_mp", 1.6, t95=[8.0, 8.3, 8.1]) + _rows("ar4_mp", 2.0, t95=[4.7, 4.8, 4.9])
    assert readings.larger_drop(ar1 + ar4, "")["verdict"] == "holds"  # 11.7 s against 3.3 s
    stalled = _rows("ar4_mp", 1.6, t95=[None, None, None]) + _rows("ar4_mp", 2.0, t95=[4.7, 4.8, 4.9])
    finding = readings.larger_drop(ar1 + stalled, "")  # AR-4's fall > 20 - 4.8 = 15.2 s, a bound above AR-1's
    assert finding["verdict"] == "does not hold" and finding["values"]["ar4_mp"]["lower bound"]
    unknown = _rows("ar4_mp", 1.6, t95=[None], ends=[None]) + _rows("ar4_mp", 2.0, t95=[4.7, 4.8, 4.9])
    assert readings.larger_drop(ar1 + unknown, "")["verdict"] == "open"  # unmixed at an unknown end: no bound
    short = _rows("ar4_mp", 1.6, t95=[None] * 3, ends=[8.0] * 3) + _rows("ar4_mp", 2.0, t95=[4.7, 4.8, 4.9])
    assert readings.larger_drop(ar1 + short, "")["verdict"] == "open"  # > 3.2 s only: a bound that decides nothing


def test_the_first_step_rule_compares_each_later_rise_with_the_first():
    def family(name, windows):
        return [r for v, w in windows.items() for r in _rows(name, v, window=w)]
    steep_first = {1.6: [0.40, 0.41, 0.42], 1.7: [0.70, 0.71, 0.72], 2.0: [0.80, 0.81, 0.82], 2.3: [0.85, 0.86, 0.87]}
    rows = family("ar1", steep_first) + family("ar4_mp", steep_first) + family("ar4_sp", steep_first)
    assert readings.largest_change_first(rows, ("ar1", "ar4_mp", "ar4_sp"), "")["verdict"] == "holds"
    later = {**steep_first, 2.0: [0.95, 0.96, 0.97], 1.7: [0.50, 0.51, 0.52]}
    rows = family("ar1", later) + family("ar4_mp", steep_first) + family("ar4_sp", steep_first)
    assert readings.largest_change_first(rows, ("ar1", "ar4_mp", "ar4_sp"), "")["verdict"] == "does not hold"


def test_the_first_step_rules_error_counts_the_17_umf_mean_twice_where_it_ends_the_later_rise():
    """With the later rise 1.7 -> 2.0, first - rise = 2 w(1.7) - w(1.6) - w(2.0): the 1.7 Umf mean's variance enters
    four times (``_rise_error``'s weights). Here the rises (0.30 against 0.15) are told apart with it once (t errors
    0.076) and not with it four times (0.153): the finding stays open and plans replicas, at 1.7 Umf the most."""
    assert readings._rise_error([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0]], [1.0, 2.0])[0] == pytest.approx((17 / 3) ** 0.5)
    windows = {1.6: [0.29, 0.30, 0.31, 0.29, 0.30, 0.31], 1.7: [0.50, 0.55, 0.60, 0.60, 0.65, 0.70],
               2.0: [0.74, 0.75, 0.76, 0.74, 0.75, 0.76]}
    rows = [r for v, w in windows.items() for r in _rows("ar1", v, window=w)]
    once, df = readings._rise_error([windows[1.6], windows[2.0], windows[1.7]])
    twice, df2 = readings._rise_error([windows[1.6], windows[2.0], windows[1.7]], [-1.0, -1.0, 2.0])
    first, rise = 0.30, 0.15
    assert first - rise > readings.critical(df) * once and first - rise < readings.critical(df2) * twice
    finding = readings.largest_change_first(rows, ("ar1",), "")
    assert finding["verdict"] == "open"
    (plan,) = finding["plans"]
    counts = {run["u_over_umf"]: (run["replicas"], run["now"]) for run in plan["runs"]}
    assert counts[1.7][0] > counts[1.7][1] == 6 and counts[1.7][0] >= max(n for n, _ in counts.values())


def test_an_open_second_reading_plans_the_replicas_that_would_tell_it_and_the_plan_file_lists_them():
    """The entropy-curve reading at 1.7 Umf: AR-4 MP 0.667 against AR-1 0.56 on two runs each (the stage-2 numbers'
    size) is within the spread; its plan asks more of both, as ``plan_points`` tables; the equivalence reading of
    "little change" plans replicas at its two velocities."""
    from fvdem.reports.mema2020.plan import plan_points
    rows = (_rows("ar4_mp", 1.7, window=[0.62, 0.71]) + _rows("ar1", 1.7, window=[0.50, 0.62])
            + _rows("ar4_mp", 1.6, window=[0.55, 0.56, 0.54]) + _rows("ar1", 1.6, window=[0.44, 0.45]))
    finding = readings.entropy_higher(rows, "ar4_mp", "ar1", (1.6, 1.7), "claim", "paper")
    assert finding["verdict"] == "open" and "would tell" in finding["why"]
    (plan,) = finding["plans"]
    assert [(r["family"], r["u_over_umf"], r["now"]) for r in plan["runs"]] == [("ar4_mp", 1.7, 2), ("ar1", 1.7, 2)]
    assert sum(r["replicas"] - r["now"] for r in plan["runs"]) > 0
    text = plan_points(rows, [finding], "s")
    assert text.splitlines().count("[[points]]") == sum(r["replicas"] > r["now"] for r in plan["runs"])
    assert '"gas.u_over_umf" = 1.7' in text and "in the study already" not in text
    t95 = (_rows("ar1", 2.3, t95=[3.5, 3.8, 4.1]) + _rows("ar1", 2.9, t95=[3.0, 3.1, 3.2, 3.1, 3.05, 3.15]))
    little = readings.little_change(t95, "ar1", "paper")
    assert little["verdict"] == "open" and {r["u_over_umf"] for r in little["plans"][0]["runs"]} == {2.3, 2.9}


def test_the_first_rules_verdicts_on_the_committed_archive_are_unchanged_and_the_second_follow_them():
    archive = ROOT / "docs" / "data" / "mema2020"
    rows = [r for r in json.loads((archive / "table.json").read_text()) if r["status"] != "not planned"]
    committed = json.loads((archive / "findings.json").read_text())
    first = [f for f in committed if f.get("readings") != "second"]
    findings = check_findings(rows)
    assert findings[:len(first)] == first  # the first set, word for word
    second = findings[len(first):]
    assert len(second) == 8 and all(f["readings"] == "second" and "the paper: " in f["rule"] for f in second)


def test_the_contact_settings_rule_tells_differ_agree_or_open():
    def shape(defaults, paper, t_def, t_pap, w_def, w_pap):
        return (_rows(defaults, 2.0, t95=t_def, window=w_def) + _rows(paper, 2.0, t95=t_pap, window=w_pap))
    same = [5.0, 5.1, 4.9, 5.05, 4.95, 5.0, 5.1, 4.9]
    rows = (shape("ar1_t95", "ar1_paper", same, [5.0, 5.02, 4.98], [0.76] * 4 + [0.75] * 4, [0.76, 0.755, 0.757])
            + shape("ar4_mp_t95", "ar4_mp_paper", same, [3.0, 3.1, 2.9], [0.76] * 4 + [0.75] * 4, [0.85, 0.86, 0.84]))
    result = readings.contact_settings(rows)
    assert result["shapes"]["AR-1"]["verdict"] == "agree" and result["shapes"]["AR-4 MP"]["verdict"] == "differ"
    assert result["shapes"]["AR-4 MP"]["t95"]["order"] == "lower" and result["shapes"]["AR-1"]["t95"]["runs"] == [3, 8]
    unmixed = rows + _rows("ar1_paper", 2.0, t95=[None], window=[0.7], ends=[8.0])
    assert readings.contact_settings(unmixed)["shapes"]["AR-1"]["verdict"] == "open"
    # fewer than the three runs at the paper's settings: open, the reading so far said
    one = shape("ar4_mp_t95", "ar4_mp_paper", same, [3.0], [0.76] * 4 + [0.75] * 4, [0.85])
    entry = readings.contact_settings(one)["shapes"]["AR-4 MP"]
    assert readings.PAPER_RUNS == 3 and entry["verdict"] == "open" and entry["reading"] == "differ"
    assert "1 of the at least 3 runs" in entry["why"]
    assert readings.contact_candidates(one)["shapes"]["AR-4 MP"]["choice"] is None


def test_the_contact_candidates_rule_chooses_the_cheapest_that_reproduces_the_papers_change():
    """studies/contact_candidates.toml's rule on known numbers: the defaults (t95 5) differ from the paper's settings
    (7); a candidate told apart from the paper's differs; one between both, told from neither, is open; one like the
    paper's agrees, and of two agreeing the cheaper (CPU s per simulated s) is the choice, if cheaper than the
    paper's own."""
    def costed(family, t95, window, cpu, ends=None):
        return [{**r, "cpu_seconds": None if cpu is None else cpu * r["simulated_seconds"]}
                for r in _rows(family, 2.0, t95=t95, window=window, ends=ends or [8.0] * len(t95))]
    defaults = costed("ar1_t95", [5.0, 5.1, 4.9, 5.05, 4.95, 5.0, 5.1, 4.9],
                      [0.80, 0.81, 0.79, 0.80, 0.805, 0.795, 0.80, 0.80], 190.0)
    paper = costed("ar1_paper", [7.0, 7.1, 6.9], [0.70, 0.71, 0.69], 720.0)
    like = costed("ar1_candidate_k3200", [6.95, 7.05, 7.0], [0.70, 0.705, 0.695], 340.0)
    cheaper_like = costed("ar1_candidate_cfd", [7.0, 6.9, 7.1], [0.71, 0.70, 0.70], 300.0)
    unlike = costed("ar1_candidate_soft", [5.0, 5.05, 4.95], [0.80, 0.805, 0.795], 200.0)
    between = costed("ar1_candidate_mid", [5.0, 7.0, 9.0], [0.6, 0.75, 0.9], 250.0)
    result = readings.contact_candidates(defaults + paper + like + unlike + between)["shapes"]["AR-1"]
    assert result["contact_settings"] == "differ"
    verdicts = {f: c["verdict"] for f, c in result["candidates"].items()}
    assert verdicts == {"ar1_candidate_k3200": "agrees", "ar1_candidate_soft": "differs",
                        "ar1_candidate_mid": "open"}
    # the open candidate may still agree and is the cheaper (250 against 340): nothing chosen yet
    assert result["choice"] is None and result["why"].startswith("ar1_candidate_mid: open")
    dearer = costed("ar1_candidate_mid", [5.0, 7.0, 9.0], [0.6, 0.75, 0.9], 400.0)  # open, but dearer
    result = readings.contact_candidates(defaults + paper + like + unlike + dearer)["shapes"]["AR-1"]
    assert result["choice"] == "ar1_candidate_k3200" and result["candidates"]["ar1_candidate_k3200"]["cost"] == 340.0
    # a candidate not yet run (its runs not started) holds the choice too: its cost is unknown
    queued = [{**r, "status": "pending", "t95": None, "mixing_entropy_window": None, "cpu_seconds": None,
               "simulated_seconds": 0.0} for r in costed("ar1_candidate_cfd", [7.0] * 3, [0.7] * 3, 300.0)]
    result = readings.contact_candidates(defaults + paper + like + queued)["shapes"]["AR-1"]
    assert result["choice"] is None and "ar1_candidate_cfd" in result["why"]
    both = readings.contact_candidates(defaults + paper + like + cheaper_like)["shapes"]["AR-1"]
    assert both["choice"] == "ar1_candidate_cfd"  # the cheaper of two agreeing
    assert readings.contact_candidates(defaults + paper + unlike)["shapes"]["AR-1"]["choice"] == "ar1_paper"
    assert readings.contact_candidates(defaults + paper + between)["shapes"]["AR-1"]["choice"] is None
    # agreeing at no saving: the paper's own; an agreeing candidate of unknown cost decides nothing yet
    dear = costed("ar1_candidate_k3200", [6.95, 7.05, 7.0], [0.70, 0.705, 0.695], 900.0)
    assert readings.contact_candidates(defaults + paper + dear)["shapes"]["AR-1"]["choice"] == "ar1_paper"
    unknown = costed("ar1_candidate_k3200", [6.95, 7.05, 7.0], [0.70, 0.705, 0.695], None)
    assert readings.contact_candidates(defaults + paper + unknown)["shapes"]["AR-1"]["choice"] is None
    # the change reproduced on one measure suffices (t95 like the paper's, the window told from neither)
    one = costed("ar1_candidate_one", [6.9, 7.0, 7.1], [0.65, 0.75, 0.85], 300.0)
    assert readings.contact_candidates(defaults + paper + one)["shapes"]["AR-1"]["candidates"][
        "ar1_candidate_one"]["verdict"] == "agrees"
    # told from the defaults the other way than the paper's settings: not the paper's change
    wrong = costed("ar1_candidate_fast", [6.0, 7.5, 9.0], [0.86, 0.87, 0.85], 300.0)
    entry = readings.contact_candidates(defaults + paper + wrong)["shapes"]["AR-1"]["candidates"]["ar1_candidate_fast"]
    assert entry["mixing_entropy_window"]["against_defaults"] == "higher" and entry["verdict"] != "agrees"
    # the defaults agreeing with the paper's settings, they stand whatever a candidate does; undecided, none yet
    alike = costed("ar1_paper", [5.0, 5.02, 4.98], [0.80, 0.801, 0.799], 720.0)
    assert readings.contact_candidates(defaults + alike + like)["shapes"]["AR-1"]["choice"] == "defaults"
    stalled = costed("ar1_paper", [7.0, None], [0.70, 0.60], 720.0)  # a paper's run unmixed at 8 s: open
    assert readings.contact_candidates(defaults + stalled + like)["shapes"]["AR-1"]["contact_settings"] == "open"
    assert readings.contact_candidates(defaults + stalled + like)["shapes"]["AR-1"]["choice"] is None
    # a run unmixed at its end (10 s) is a lower bound: above the paper's it differs, else it leaves t95 unknown
    late = costed("ar1_candidate_k3200", [9.8, 9.9, None], [0.60, 0.61, 0.59], 340.0, ends=[10.0] * 3)
    entry = readings.contact_candidates(defaults + paper + late)["shapes"]["AR-1"]["candidates"]["ar1_candidate_k3200"]
    assert entry["verdict"] == "differs" and entry["t95"]["candidate"] == pytest.approx(9.9)
    near = costed("ar1_candidate_k3200", [6.95, 7.05, None], [0.70, 0.705, 0.695], 340.0, ends=[10.0] * 3)
    entry = readings.contact_candidates(defaults + paper + near)["shapes"]["AR-1"]["candidates"]["ar1_candidate_k3200"]
    assert entry["verdict"] == "open" and "lower bound" in entry["why"]
    # a run on its way counts nowhere (no t95 yet is not unmixed)
    going = [{**r, "status": "running", "t95": None} for r in costed("ar1_candidate_k3200", [7.0], [0.7], 340.0)]
    assert readings.contact_candidates(defaults + paper + like + going)["shapes"]["AR-1"]["choice"] == \
        "ar1_candidate_k3200"
    paper_going = [{**r, "status": "running", "t95": None} for r in costed("ar1_paper", [7.0], [0.7], 720.0)]
    assert readings.contact_settings(defaults + paper + paper_going)["shapes"]["AR-1"]["verdict"] == "differ"


def test_the_contact_decision_tool_refuses_a_folder_that_is_no_archive(tmp_path):
    import subprocess
    import sys
    result = subprocess.run([sys.executable, str(ROOT / "tools" / "contact_decision.py"), "--archives", str(tmp_path)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "not a study archive" in result.stderr and "Traceback" not in result.stderr


def test_the_contact_decision_tool_draws_each_settings_entropy_curves(tmp_path):
    """``--plot``: the committed archives' AR-1 runs at 2.0 Umf, the defaults' replicas and the paper's settings, as
    mean entropy curves with their SD bands in one PNG; a path that is no .png in an existing folder is refused."""
    import subprocess
    import sys
    tool = [sys.executable, str(ROOT / "tools" / "contact_decision.py"), "--quick", "--json", "--archives",
            str(ROOT / "docs" / "data" / "mema2020"), str(ROOT / "docs" / "data" / "contact_paper")]
    png = tmp_path / "contact.png"
    result = subprocess.run(tool + ["--plot", str(png)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    bad = subprocess.run(tool + ["--plot", str(tmp_path / "missing" / "x.png")], capture_output=True, text=True,
                         timeout=300)
    assert bad.returncode == 2 and "--plot" in bad.stderr and "Traceback" not in bad.stderr


def test_the_contact_decision_tool_reads_a_familys_velocity_from_its_archived_case(tmp_path):
    """studies/contact_paper.toml runs its families at their case's own U/Umf, which a study's table (its swept
    keys only) does not list: the tool takes it from each archived run's case.toml, so the rule finds the runs
    (an archive whose runs it did not find decided nothing, "no runs")."""
    import importlib.util

    from fvdem.case import case_from_dict, to_toml
    spec = importlib.util.spec_from_file_location("contact_decision", ROOT / "tools" / "contact_decision.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    run = tmp_path / "runs" / "ar1_paper_r1"
    run.mkdir(parents=True)
    (run / "case.toml").write_text(to_toml(case_from_dict({"name": "ar1", "gas": {"enabled": True, "umf": 1.914,
                                                                                   "u_over_umf": 2.0}})))
    ended = {"name": "ar1_paper_r1", "family": "ar1_paper", "status": "ended", "t95": 6.5}
    assert tool.with_velocity(tmp_path, ended)["gas.u_over_umf"] == 2.0
    pending = {"name": "ar1_paper_r2", "family": "ar1_paper", "status": "pending", "t95": None}
    assert "gas.u_over_umf" not in tool.with_velocity(tmp_path, pending)
    swept = {**ended, "gas.u_over_umf": 1.6}
    assert tool.with_velocity(tmp_path, swept)["gas.u_over_umf"] == 1.6
