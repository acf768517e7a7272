"""Case files: bad input is refused before anything runs, with key path, value and what is allowed."""
import subprocess
import sys

import pytest

import fvdem
from fvdem.case import CaseError, load_case, parse_override, schema_reference, to_toml

from paths import ROOT

CASES = sorted((ROOT / "cases").glob("*.toml"))

SMALL = """
name = "small"
[domain]
upper = [0.05, 0.05, 0.1]
[particles]
count = 50
diameter = "5.3 mm"
[time]
end = 0.002
[output]
progress = false
snapshot_interval = 0.001
timeseries_interval = 0.0005
checkpoint_interval = 0.001
"""


def write_case(tmp_path, text, name="case.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def fvdem_cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "fvdem.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=300)


@pytest.mark.parametrize("edit, expected", [
    (("[particles]", "[particles]\ndiamter = 0.005"), ["particles.diamter", "unknown key", "did you mean 'diameter'"]),
    (("diameter = \"5.3 mm\"", "diameter = -0.005"), ["particles.diameter = -0.005", "out of range", "> 0"]),
    (("diameter = \"5.3 mm\"", "diameter = \"5.3 kg\""), ["particles.diameter", "unit 'kg' is not a length unit",
                                                          "mm"]),
    (("diameter = \"5.3 mm\"", "diameter = \"big\""), ["particles.diameter = 'big'", "a number"]),
    (("count = 50", "count = 50.5"), ["particles.count = 50.5", "an integer"]),
    (("count = 50", "count = 5000"), ["particles.count = 5000", "64 %"]),
    (("[time]", "[contact]\nrestitution = 1.5\n[time]"), ["contact.restitution = 1.5", "<= 1"]),
    (("[time]", "[contact]\nrestitution = 0.0\n[time]"), ["contact.restitution = 0.0", "> 0"]),
    (("[time]", "[contact]\nfriction = -0.1\n[time]"), ["contact.friction = -0.1", ">= 0"]),
    (("end = 0.002", "end = 0.002\ndem_step = 1e-3"), ["time.dem_step", "exceeds 1/10 of the collision time"]),
    (("count = 50", "count = 50\nshape = \"spherocylinder\""), ["particles.length", "required"]),
    (("count = 50", "count = 50\nshape = \"cube\""), ["particles.shape = 'cube'", "'sphere', 'spherocylinder'"]),
    (("upper = [0.05, 0.05, 0.1]", "upper = [0.05, 0.05]"), ["domain.upper", "a list of 3 numbers"]),
    (("[output]", "[outptu]"), ["outptu", "unknown key", "did you mean 'output'"]),
    (("end = 0.002", "end = 0.002\nstop_after_mixed = -1.0"), ["time.stop_after_mixed = -1.0", ">= 0"]),
    (('diameter = "5.3 mm"\n[time]\nend = 0.002', 'diameter = "5.3 mm"\ncolour = "single"\n[time]\nend = 0.002\n'
      "stop_after_mixed = 2.0"), ["time.stop_after_mixed = 2", "two colours", "particles.colour = 'by_height'"]),
])
def test_bad_case_is_refused_with_key_value_and_rule(tmp_path, edit, expected):
    path = write_case(tmp_path, SMALL.replace(*edit, 1))
    with pytest.raises(CaseError) as info:
        load_case(path)
    message = str(info.value)
    for fragment in expected:
        assert fragment in message, message


def test_all_problems_are_reported_together(tmp_path):
    text = SMALL.replace('diameter = "5.3 mm"', "diameter = -1\ndensity = -5").replace("[time]", "[time]\nbogus = 1")
    with pytest.raises(CaseError) as info:
        load_case(write_case(tmp_path, text))
    assert len(info.value.problems) == 3


def test_cli_refuses_bad_case_with_exit_code_2_and_no_traceback(tmp_path):
    path = write_case(tmp_path, SMALL.replace('diameter = "5.3 mm"', "diameter = -0.005"))
    out = tmp_path / "out"
    for command in (["check", path], ["run", path, "--out", out]):
        result = fvdem_cli(*command)
        assert result.returncode == 2
        assert "particles.diameter = -0.005" in result.stderr
        assert "Traceback" not in result.stderr + result.stdout
    assert not out.exists()  # nothing ran, nothing written


def test_cli_refuses_bad_override(tmp_path):
    path = write_case(tmp_path, SMALL)
    result = fvdem_cli("check", path, "--set", "contact.restitution=2")
    assert result.returncode == 2 and "contact.restitution = 2" in result.stderr
    result = fvdem_cli("check", path, "--set", "nonsense")
    assert result.returncode == 2 and "KEY=VALUE" in result.stderr


def test_missing_case_file_is_an_input_error(tmp_path):
    result = fvdem_cli("check", tmp_path / "nope.toml")
    assert result.returncode == 2 and "no such case file" in result.stderr


def test_units_and_overrides():
    key, value = parse_override("particles.diameter=\"3 mm\"")
    assert (key, value) == ("particles.diameter", "3 mm")
    case = load_case(ROOT / "cases" / "bed_ar4.toml", {key: value, "particles.count": 100})
    assert case.particles.diameter == pytest.approx(3e-3)
    assert case.particles.half_length == pytest.approx(4.5e-3)
    assert case.particles.count == 100


def test_resolved_case_round_trips(tmp_path):
    case = load_case(ROOT / "cases" / "bed_ar4.toml")
    again = load_case(write_case(tmp_path, to_toml(case)))
    assert again == case
    assert "particles.insertion.orientation" in schema_reference()


AWKWARD = ['line one\nline two', 'quotes " and \'', 'back\\slash \\n not a newline', 'tab\there',
           'triple """ quotes \'\'\'', 'Ünïcode µm ° — 粒子', '# not a comment', '[not.a.table]', '',
           'trailing backslash \\', 'a = "b"\n[c]\nd = 1']


@pytest.mark.parametrize("path", CASES, ids=[p.name for p in CASES])
def test_every_case_file_round_trips_through_its_written_toml(path, tmp_path):
    """The run folder's case.toml (tomli-w) reads back to the same case: every value, defaults included."""
    import tomllib

    from fvdem.case import case_as_dict
    case = load_case(path)
    text = to_toml(case, header="made by a test\nsecond line")
    assert tomllib.loads(text) == case_as_dict(case)
    assert text.splitlines()[1:3] == ["# made by a test", "# second line"]


@pytest.mark.parametrize("description", AWKWARD)
def test_awkward_strings_round_trip_and_a_run_with_them_resumes(description, tmp_path):
    case = load_case(write_case(tmp_path, SMALL), {"description": description, "name": "odd"})
    again = load_case(write_case(tmp_path, to_toml(case), "again.toml"))
    assert again.description == description and again == case


def test_a_run_whose_description_spans_lines_resumes(tmp_path):
    """A multi-line description once broke --resume: the hand-written writer left the newline raw."""
    path = write_case(tmp_path, SMALL.replace('name = "small"', 'name = "small"\ndescription = """first\nsecond "quoted" line"""'))
    out = tmp_path / "run"
    first = fvdem_cli("run", path, "--out", out, "--set", "time.end=0.002", "--no-progress")
    assert first.returncode == 0, first.stderr
    resumed = fvdem_cli("run", path, "--out", out, "--resume", "--set", "time.end=0.004", "--no-progress")
    assert resumed.returncode == 0, resumed.stderr
    assert load_case(out / "case.toml").description == 'first\nsecond "quoted" line'


@pytest.mark.parametrize("path", CASES, ids=[p.name for p in CASES])
def test_every_case_file_validates_and_runs_a_step(path):
    case = load_case(path)
    # smoke: build the model (insertion or initial state) and advance one DEM step
    if case.particles.initial_state and not case.resolve_path(case.particles.initial_state).exists():
        pytest.skip(f"{path.name} starts from {case.particles.initial_state}, produced by another case")
    sim = fvdem.Simulation(case, progress=False)
    sim.run(sim.time_step)
    assert sim.step_count == 1


def test_run_writes_outputs_and_never_overwrites(tmp_path):
    path = write_case(tmp_path, SMALL)
    out = tmp_path / "out"
    result = fvdem_cli("run", path, "--out", out)
    assert result.returncode == 0, result.stderr
    for name in ("case.toml", "summary.json", "timeseries.csv", "particles.pvd", "particles_00000.vtu",
                 "checkpoint.npz", "final_state.npz"):
        assert (out / name).exists(), name
    before = (out / "summary.json").read_text()
    result = fvdem_cli("run", path, "--out", out)
    assert result.returncode == 2 and "--overwrite" in result.stderr
    assert (out / "summary.json").read_text() == before
    assert fvdem_cli("run", path, "--out", out, "--overwrite").returncode == 0


def test_docs_case_reference_is_generated_from_the_schema():
    """docs/case-reference.md is ``fvdem schema --docs``; registry-backed keys name their registry, so a
    new drag law leaves it current (issue 15's recipe touches only the closures module and its test)."""
    from fvdem.case import docs_reference
    committed = (ROOT / "docs" / "case-reference.md").read_text()
    assert committed == docs_reference(), "regenerate: fvdem schema --docs > docs/case-reference.md"
    assert "fvdem laws drag" in committed and "'hoelzer-sommerfeld'" not in committed.split("coupling.drag`")[1][:200]
