"""tools/compare_findings.py: two archives' verdicts side by side (stage 2 against stage 3), matched by claim,
counted per side; bad input refused with a clear message and exit 2."""
import json
import subprocess
import sys

from paths import ROOT, TOOLS

ARCHIVES = ROOT / "docs" / "data"


def _tool(*args):
    return subprocess.run([sys.executable, str(TOOLS / "compare_findings.py"), *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def test_two_archives_findings_side_by_side_with_what_changed(tmp_path):
    old = [{"finding": "A mixes faster", "verdict": "does not hold"}, {"finding": "B expands", "verdict": "holds"},
           {"finding": "C by the curves", "verdict": "open", "readings": "second"}]
    new = {"findings": [{"finding": "B expands", "verdict": "holds"},
                        {"finding": "A mixes faster", "verdict": "holds"},
                        {"finding": "D new claim", "verdict": "open", "readings": "second"}]}
    (tmp_path / "old").mkdir()
    (tmp_path / "old" / "findings.json").write_text(json.dumps(old))
    (tmp_path / "new.json").write_text(json.dumps(new))
    out = tmp_path / "side.md"
    result = _tool(tmp_path / "old", tmp_path / "new.json", "--labels", "stage 2", "stage 3", "--out", out)
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout.strip().splitlines()[-1])["rows"]
    assert [(r["finding"], r["old"], r["new"], r["changed"]) for r in rows] == [
        ("A mixes faster", "does not hold", "holds", True), ("B expands", "holds", "holds", False),
        ("C by the curves", "open", None, False), ("D new claim", None, "open", False)]
    text = out.read_text()
    assert "| A mixes faster | first | does not hold | holds | yes |" in text
    assert "| D new claim | second | - | open |  |" in text
    assert "stage 2: 3 findings: 1 holds, 1 does not hold, 1 open." in text and "Changed: 1 of 2" in text
    again = _tool(tmp_path / "old", tmp_path / "new.json", "--out", out)  # never overwrites a result
    assert again.returncode == 2 and "exists" in again.stderr and out.read_text() == text


def test_the_committed_stage_2_archive_against_its_results_file_changes_nothing():
    result = _tool(ARCHIVES / "mema2020", ARCHIVES / "mema2020.json")
    assert result.returncode == 0, result.stderr
    rows = json.loads(result.stdout.strip().splitlines()[-1])["rows"]
    assert len(rows) == 21 and not any(r["changed"] for r in rows)


def test_bad_input_is_refused_with_the_path_and_exit_2(tmp_path):
    (tmp_path / "empty").mkdir()
    (tmp_path / "bad.json").write_text("{not json")
    (tmp_path / "nofindings.json").write_text(json.dumps({"runs": []}))
    for path, words in ((tmp_path / "empty", "no findings.json"), (tmp_path / "missing", "no such file"),
                        (tmp_path / "bad.json", "not JSON"), (tmp_path / "nofindings.json", "holds no findings")):
        result = _tool(path, ARCHIVES / "mema2020")
        assert result.returncode == 2 and words in result.stderr and "Traceback" not in result.stderr, result.stderr
