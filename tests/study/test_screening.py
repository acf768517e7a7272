"""Designed experiments (issue 66): two-level factorials and their aliases against the textbook tables, the
effects and intervals against responses of known effects, and a designed study run end to end whose effects
are known exactly (free fall: the speed at time t is g t whatever the density or the step)."""
import json
import subprocess
import sys

import numpy as np
import pytest

from fvdem.case import CaseError
from fvdem.study import load_study
from fvdem.study.design import STANDARD_GENERATORS, DesignError, analyse, fold_over, model_terms, two_level
from fvdem.study.screening import response_value


# resolution of each standard fraction as Montgomery (2013, Table 8.14) lists it
RESOLUTION = {(3, 1): 3, (4, 1): 4, (5, 1): 5, (5, 2): 3, (6, 1): 6, (6, 2): 4, (6, 3): 3, (7, 1): 7, (7, 2): 4,
              (7, 3): 4, (7, 4): 3, (8, 2): 5, (8, 3): 4, (8, 4): 4, (9, 3): 4, (9, 4): 4, (9, 5): 3, (10, 4): 4,
              (10, 5): 4, (10, 6): 3, (11, 5): 4, (11, 6): 4, (11, 7): 3}


@pytest.mark.parametrize("k, p", sorted(STANDARD_GENERATORS))
def test_the_standard_fractions_have_the_tabulated_resolution_and_orthogonal_columns(k, p):
    d = two_level(k, fraction=p)
    assert d.runs == 2 ** (k - p) and d.resolution == RESOLUTION[(k, p)]
    assert len(d.words) == 2 ** p - 1  # the defining relation: the group the p generators span
    m = d.matrix
    np.testing.assert_array_equal(m.T @ m, d.runs * np.eye(k))  # main-effect columns orthogonal and balanced
    assert len(d.alias_classes()) == d.runs - 1  # one contrast per run less the mean


def test_a_half_fraction_aliases_as_the_textbook_says():
    """2^(4-1) with D = ABC (Box, Hunter & Hunter 2005, §6.3): I = ABCD, A = BCD, AB = CD, resolution IV."""
    d = two_level(4, ["D = ABC"])
    assert d.defining_relation() == "I = ABCD" and d.resolution == 4
    assert d.aliases("A") == ["BCD"] and d.aliases("AB") == ["CD"] and d.aliases("AD") == ["BC"]
    assert [t for t, _ in model_terms(d)] == ["A", "B", "C", "D", "AB", "AC", "AD"]
    np.testing.assert_array_equal(d.column("D"), d.column("ABC"))
    # names instead of letters, and the full factorial
    assert two_level(4, ["d = a*b*c"], names=dict(zip("abcd", "ABCD"))).generators == ("D = ABC",)
    full = two_level(3)
    assert full.resolution is None and full.runs == 8 and full.words == ()


@pytest.mark.parametrize("generators, fraction, message", [
    (["D = AB", "E = AB"], None, "share a column"),
    (["C = AB"], 1, "either generators or fraction"),
    (["C = AB"], None, "generate the last 1 factors"),
    (["D = AQ"], None, "neither a factor's letter"),
    ([], 3, "no standard 2^(4-3) design"),
])
def test_a_design_that_cannot_be_built_says_why(generators, fraction, message):
    k = 5 if generators[:1] == ["D = AB"] else 4
    with pytest.raises(DesignError, match=message.replace("^", r"\^").replace("(", r"\(").replace(")", r"\)")):
        two_level(k, generators, fraction=fraction)


def test_the_effects_of_a_replicated_fraction_recover_known_effects_within_their_intervals():
    """y = 10 + 1.5 A - 1.0 B + 0.75 AB + N(0, 0.3): effects (twice the coefficients) 3, -2, 1.5; over 200
    replicated 2^(8-4) experiments the 95 % intervals cover each true effect about 95 % of the time."""
    d = two_level(8, fraction=4)
    rng = np.random.default_rng(7)
    truth = {"A": 3.0, "B": -2.0, "AB": 1.5}
    covered, trials = {t: 0 for t in ("A", "B", "C", "AB", "AC")}, 200
    for _ in range(trials):
        x = np.vstack([d.matrix, d.matrix])
        y = 10 + 1.5 * x[:, 0] - 1.0 * x[:, 1] + 0.75 * x[:, 0] * x[:, 1] + rng.normal(0, 0.3, len(x))
        a = analyse(d, x, y)
        assert a.error == "pure error" and a.error_df == 16
        for e in a.effects:
            if e.term in covered:
                covered[e.term] += e.low <= truth.get(e.term, 0.0) <= e.high
    for term, n in covered.items():
        assert 0.88 <= n / trials <= 0.99, (term, n)
    # one experiment: the told effects are the true ones, the others are not told
    x = np.vstack([d.matrix, d.matrix])
    y = 10 + 1.5 * x[:, 0] - 1.0 * x[:, 1] + 0.75 * x[:, 0] * x[:, 1] + rng.normal(0, 0.3, len(x))
    told = {e.term for e in analyse(d, x, y).effects if e.decided()}
    assert {"A", "B", "AB"} <= told and len(told) <= 4


def test_an_unreplicated_saturated_fraction_takes_lenths_pse_and_a_full_factorial_its_residual():
    d = two_level(8, fraction=4)
    y = 5 + 2.0 * d.matrix[:, 2] + np.random.default_rng(1).normal(0, 0.2, d.runs)
    a = analyse(d, d.matrix, y)
    assert a.error == "Lenth's PSE" and a.error_df == pytest.approx(5.0)
    c = next(e for e in a.effects if e.term == "C")
    assert c.decided() and c.low < 4.0 < c.high
    # a full 2^3: mains and two-factor interactions estimated, ABC left as the residual (1 df)
    full = two_level(3)
    a = analyse(full, full.matrix, 1 + full.matrix[:, 0] + np.array([0.1, -0.1, -0.1, 0.1, -0.1, 0.1, 0.1, -0.1]))
    assert a.error == "residual" and a.error_df == 1 and a.effects[0].estimate == pytest.approx(2.0)


def test_a_fold_over_clears_what_the_textbook_says():
    """Montgomery (2013, §8.6.2): the full fold-over of the 2^(7-4) resolution-III fraction is a 2^(7-3) of
    resolution IV whose defining relation is the seven four-letter words of the original's; a fold-over on one
    factor of the 2^(6-2) frees that factor's two-factor interactions (AD + EF into AD and EF), a fold-over on D of
    the 2^(4-1) (I = ABCD) completes the full factorial; columns stay orthogonal and runs distinct."""
    three = two_level(7, fraction=4)
    full = fold_over(three, three.letters)
    assert full.runs == 16 and full.resolution == 4 and full.label().startswith("2^(7-3), 16 runs")
    assert sorted(map(sorted, full.words)) == sorted(sorted(w) for w in three.words if len(w) == 4)
    one = fold_over(two_level(6, fraction=2), "D")
    assert one.defining_relation() == "I = ABCE" and one.aliases("AD") == [] and one.aliases("EF") == []
    assert "AD" in [t for t, _ in model_terms(one)] and "EF" in [t for t, _ in model_terms(one)]
    assert fold_over(two_level(4, fraction=1), "D").resolution is None  # the full 2^4
    for d in (full, one):
        np.testing.assert_array_equal(d.matrix.T @ d.matrix, d.runs * np.eye(len(d.letters)))
        assert len({tuple(r) for r in d.matrix}) == d.runs
        np.testing.assert_array_equal(d.matrix[:d.runs // 2], (three if d is full else two_level(6, fraction=2)).matrix)
    with pytest.raises(DesignError, match="repeats the design's own runs"):
        fold_over(two_level(6, fraction=2), "BC")  # every word holds an even number of B and C
    with pytest.raises(DesignError, match="folded over already"):
        fold_over(one, "A")


def test_a_fold_over_tells_apart_the_interactions_its_fraction_chained():
    """y = 10 + 0.6 AD (effect 1.2) + N(0, 0.05), two replicas: the 2^(6-2) tells the chain AD + EF; folded on D
    it tells AD (1.2) and leaves EF at nothing."""
    rng = np.random.default_rng(5)
    for design in (two_level(6, fraction=2), fold_over(two_level(6, fraction=2), "D")):
        coded = np.vstack([design.matrix, design.matrix])
        y = 10 + 0.6 * coded[:, 0] * coded[:, 3] + rng.normal(0, 0.05, len(coded))
        effects = {e.term: e for e in analyse(design, coded, y).effects}
        assert effects["AD"].decided() and effects["AD"].estimate == pytest.approx(1.2, abs=0.06)
        if design.folded:  # EF its own term now, at nothing within the noise
            assert effects["AD"].aliases == () and abs(effects["EF"].estimate) < 0.06
        else:  # one chain: the fraction cannot say which of AD and EF it is
            assert "EF" in effects["AD"].aliases and "EF" not in effects


def test_a_response_reads_a_column_or_a_series_at_a_time_and_a_censored_one_takes_the_end():
    """A run that ended early by its stop condition holds its last value at later times."""
    series = {"time": np.array([0.0, 1.0, 2.0]), "mixing_entropy": np.array([0.1, 0.5, 0.7])}
    row = {"status": "finished", "simulated_seconds": 8.0, "t95": None, "bed_height": 0.3}
    assert response_value("mixing_entropy@1.5", row, series, False) == (pytest.approx(0.6), False)
    assert response_value("mixing_entropy@3.0", row, series, False) == (None, False)  # not reached
    assert response_value("bed_height", row, series, False) == (0.3, False)
    assert response_value("t95", row, series, True) == (8.0, True)  # ended unmixed: censored at its end
    assert response_value("t95", {**row, "status": "running"}, series, True) == (None, False)
    # ended at 2 s of its 7 by its case's stop condition (mixed): its last value holds later; stopped by the
    # study at 2 s (a checkpoint), it holds none
    early = {**row, "simulated_seconds": 2.0, "duration": 7.0, "t95": 1.0}
    assert response_value("mixing_entropy@3.0", early, series, False) == (pytest.approx(0.7), False)
    assert response_value("mixing_entropy@3.0", {**early, "status": "stopped"}, series, False) == (None, False)


FALL = '''name = "fall"
[domain]
upper = [0.1, 0.1, 1.0]
[particles]
count = 8
diameter = "5 mm"
[particles.insertion]
lower = [0.0, 0.0, 0.8]
upper = [0.1, 0.1, 1.0]
gap = 0.005
[time]
dem_step = 5.0e-5
end = 0.05
[output]
vtk = false
timeseries_interval = 0.01
checkpoint_interval = 0.05
[run]
threads = 1
'''


def _fall_study(tmp_path, extra=""):
    (tmp_path / "fall.toml").write_text(FALL)
    path = tmp_path / "fall_design.toml"
    path.write_text(f'''name = "fall_design"
duration = 0.04
report = "table"
[design]
name = "fall"
case = "fall.toml"
generators = ["C = AB"]
replicas = 2
responses = ["rms_speed@0.04", "bed_top@0.04", "t95"]
censored = ["t95"]
[design.factors.gravity]
low = {{"domain.gravity" = [0.0, 0.0, -9.81]}}
high = {{"domain.gravity" = [0.0, 0.0, -4.905]}}
[design.factors.density]
low = {{}}
high = {{"particles.density" = 2884.0}}
[design.factors.step]
low = {{}}
high = {{"time.dem_step" = 2.5e-5}}
{extra}''')
    return path


def test_a_design_expands_into_runs_and_a_wrong_one_is_refused_with_its_key_paths(tmp_path):
    study = load_study(_fall_study(tmp_path), tmp_path / "out")
    assert [r.name for r in study.runs] == [f"fall_0{i}_r{k}" for k in (1, 2) for i in (1, 2, 3, 4)]
    first, last = study.runs[0], study.runs[3]
    assert first.point == {"design.gravity": -1, "design.density": -1, "design.step": 1}  # C = AB: + at (-, -)
    assert last.overrides["domain.gravity"] == [0.0, 0.0, -4.905] and last.overrides["time.dem_step"] == 2.5e-5
    assert study.runs[4].overrides["particles.insertion.seed"] == 2 and study.runs[4].priority == -1
    assert study.design["label"] == "2^(3-1), 4 runs, resolution III" and study.design["aliases"]["A"] == ["BC"]
    # folded over on all factors: the fraction's runs first, under their names, then its mirror
    path = _fall_study(tmp_path)
    path.write_text(path.read_text().replace('censored = ["t95"]', 'censored = ["t95"]\nfoldover = "all"'))
    folded = load_study(path, tmp_path / "folded")
    assert [r.name for r in folded.runs][:4] == [f"fall_0{i}_r1" for i in (1, 2, 3, 4)]
    assert [r.point for r in folded.runs[:4]] == [r.point for r in study.runs[:4]] and len(folded.runs) == 16
    assert folded.runs[4].point == {f: -c for f, c in folded.runs[0].point.items()}
    assert folded.design["label"] == "2^3, 8 runs (a fold-over on all factors), full factorial"
    assert folded.design["foldover"] == ["gravity", "density", "step"]
    for wrong, said in (('["hue"]', "'all' or a list of the design's factors"),
                        ('["gravity", "density"]', "repeats the design's own runs")):
        path.write_text(_fall_study(tmp_path).read_text().replace('censored = ["t95"]',
                                                                  f'censored = ["t95"]\nfoldover = {wrong}'))
        with pytest.raises(CaseError) as failure:
            load_study(path, tmp_path / "folded")
        assert any("design.foldover" in p and said in p for p in failure.value.problems), failure.value.problems
    bad = _fall_study(tmp_path, '[design.factors.colour]\nlow = {}\nhigh = {}\nhue = 3\n')
    text = bad.read_text().replace('generators = ["C = AB"]', 'generators = ["C = AB", "D = AQ"]').replace(
        '"t95"]\ncensored = ["t95"]', '"t95"]\ncensored = ["t99"]')
    bad.write_text(text)
    with pytest.raises(CaseError) as failure:
        load_study(bad, tmp_path / "out")
    problems = "\n".join(failure.value.problems)
    assert "design.factors.colour.hue = 3: unknown key" in problems
    assert "design.factors.colour" in problems and "two different levels" in problems
    assert "design.censored" in problems
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(bad), "--out", str(tmp_path / "o")],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 2 and "Traceback" not in result.stderr and not (tmp_path / "o").exists()


@pytest.mark.slow
def test_a_designed_study_runs_and_its_screening_recovers_the_known_effects(tmp_path):
    """Free fall for 0.04 s: the speed is g t exactly (velocity Verlet under a constant force), whatever the
    density or the DEM step: the effect of halving g on rms_speed@0.04 is -4.905 x 0.04 = -0.1962 m/s, on the
    highest particle's height +1/2 x 4.905 x 0.04^2 = +3.924 mm, and density and step have none. t95 never
    comes (one colour): every run is censored at its end."""
    path = _fall_study(tmp_path)
    out, archive = tmp_path / "out", tmp_path / "archive"
    result = subprocess.run([sys.executable, "-m", "fvdem", "study", str(path), "--out", str(out), "--workers", "1"],
                            capture_output=True, text=True, timeout=600)
    assert result.returncode == 0, result.stderr[-3000:]
    record = json.loads((out / "screening.json").read_text())
    speed = {e["term"]: e for e in record["results"]["rms_speed@0.04"]["effects"]}
    assert speed["A"]["estimate"] == pytest.approx(-0.1962, rel=1e-6) and speed["A"]["decided"]
    assert speed["B"]["estimate"] == 0.0 and speed["C"]["estimate"] == 0.0  # below rounding: none, not told
    assert not speed["B"]["decided"] and not speed["C"]["decided"]
    top = record["results"]["bed_top@0.04"]
    effects = {e["term"]: e for e in top["effects"]}
    assert effects["A"]["estimate"] == pytest.approx(0.5 * 4.905 * 0.04 ** 2, rel=1e-6)
    assert top["error"] == "pure error" and top["error_df"] == 4  # the two insertion seeds differ at the top
    assert abs(effects["B"]["estimate"]) < 1e-9 and not effects["B"]["decided"]
    t95 = record["results"]["t95"]
    assert len(t95["censored_runs"]) == 8 and all(abs(e["estimate"]) < 1e-12 for e in t95["effects"])
    page = (out / "screening.md").read_text()
    assert "I = ABC" in page and "| A | gravity |" in page and "Censored: 8 run(s)" in page
    assert (out / "pareto_rms_speed_at_0p04.png").stat().st_size > 1000
    # the archive keeps the series columns the responses read, and its report rebuilds the same effects
    subprocess.run([sys.executable, "-m", "fvdem", "study", str(out), "--archive", str(archive)], check=True,
                   capture_output=True, timeout=300)
    rebuilt = json.loads((archive / "screening.json").read_text())
    for response, result in record["results"].items():  # the archive keeps 6 significant digits
        again = rebuilt["results"][response]
        assert [e["term"] for e in again["effects"]] == [e["term"] for e in result["effects"]]
        for e, f in zip(result["effects"], again["effects"]):
            assert f["estimate"] == pytest.approx(e["estimate"], rel=1e-4, abs=1e-6) and f["decided"] == e["decided"]


def test_an_effect_within_its_interval_of_mattering_says_how_many_replicas_would_tell_it():
    """Within its interval of mattering (reaching both 0 and 10 % of the mean): the interval's half-width
    shrinks as 1/sqrt(replicas) until it clears 0; 0.7 about 0.5 at 2 replicas a point: 2 (0.7 / 0.5)^2 = 3.9."""
    from fvdem.study.design import Effect
    from fvdem.study.screening import _to_tell
    assert _to_tell(Effect("A", (), 0.5, 0.3, -0.2, 1.2), mean=5.0, replicas=2) == {"undecided": True,
                                                                                   "replicas_to_tell": 4}
    assert _to_tell(Effect("A", (), 0.01, 0.01, -0.01, 0.03), 5.0, 2)["undecided"] is False  # inside +- 0.5: none
    assert _to_tell(Effect("A", (), 2.0, 0.3, 1.4, 2.6), 5.0, 2) == {"undecided": False, "replicas_to_tell": None}
