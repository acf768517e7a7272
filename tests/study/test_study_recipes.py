"""The recipes of docs/ARCHITECTURE.md, "How to add a study report" and "How to add a stop condition", followed
on a synthetic study folder: a toy report registered by name makes its table, findings and status values and
keeps its columns in an archive; a toy stop condition tells the engine whether a run that ended by it is at its
end under the case as the study sets it now, lists its setting in the index and expects where a run ends."""
import json

import numpy as np
import pytest

from fvdem.case import load_case
from fvdem.scenes.stops import STOP_CONDITIONS, StopCondition, stop_settings
from fvdem.study import archive, load_study, report, write_index
from fvdem.study.records import RunState, run_at_end, state_of
from fvdem.study.registry import REPORTS, StudyReport
from fvdem.study.status import study_status

from study_runs import ROOT

CALM = 0.1  # J: the toy runs' energy below this is calm


def calm_at(series) -> float | None:
    """When a run's energy first fell below ``CALM`` (None while it has not)."""
    below = np.flatnonzero(np.asarray(series["energy"]) < CALM)
    return float(series["time"][below[0]]) if below.size else None


def peaks_above_two(rows) -> dict:
    """The toy finding: every ended run of family "a" peaked above 2 J."""
    ended = [r for r in rows if r["family"] == "a" and state_of(r["status"]) is RunState.ENDED]
    if not ended:
        return {"finding": "a peaks above 2 J", "verdict": "open", "why": "no run of a has ended"}
    holds = all(r["peak"] > 2.0 for r in ended)
    return {"finding": "a peaks above 2 J", "verdict": "holds" if holds else "does not hold",
            "values": {r["name"]: r["peak"] for r in ended}, "rule": "every ended run's peak above 2 J"}


TOY = StudyReport(
    "toy", "a toy: each run's peak energy, when it calmed, one finding",
    run_values=lambda summary: {"peak": summary.get("peak"), "calm_at": summary.get("calm_at")},
    live=lambda series: {"peak": float(np.max(series["energy"])), "calm_at": calm_at(series)},
    columns=lambda run, folder, summary, series: {
        "peak": summary.get("peak"), "last_energy": None if series is None else float(series["energy"][-1])},
    findings=lambda rows: [peaks_above_two(rows)], archived_columns=("energy",), archived_summary=("peak", "calm_at"),
    watch=("energy",))

# ends ``time.min_time`` after the run calmed (the case key stands in for a margin of its own)
TOY_STOP = StopCondition("calm", "time.min_time",
                         holds=lambda summary, margin: summary["simulated_time"] >= summary["calm_at"] + margin - 1e-9,
                         mark="calm_at", ends_at=lambda mark, margin: mark + margin, index_key="calm_margin",
                         expected="time.min_time past its calm")


@pytest.fixture
def toy(monkeypatch):
    monkeypatch.setitem(REPORTS, TOY.name, TOY)
    monkeypatch.setitem(STOP_CONDITIONS, TOY_STOP.name, TOY_STOP)


def _run(out, name, times, energy, summary=None, checkpoint=False):
    folder = out / "runs" / name
    folder.mkdir(parents=True)
    (folder / "timeseries.csv").write_text("time,energy\n" + "".join(
        f"{float(t)!r},{float(e)!r}\n" for t, e in zip(times, energy)))
    if summary is not None:
        (folder / "summary.json").write_text(json.dumps(summary))
    if checkpoint:
        (folder / "checkpoint.npz").write_bytes(b"a checkpoint")
    return folder


def _toy_study(out):
    """Three runs of 1 s: a_r1 ended (peak 3 J, calm at 0.7 s), a_r2 stopped at 0.5 s (a checkpoint; peak 2.5 J,
    calm at 0.5 s), b_r1 not started; the index lists the toy condition's margin, 0.2 s."""
    stops = dict(stop_settings(load_case(ROOT / "cases" / "demo.toml", {"time.min_time": 0.2})))  # as write_index
    assert stops["calm_margin"] == 0.2
    t = np.linspace(0.0, 1.0, 11)
    _run(out, "a_r1", t, 3.0 * np.exp(-5.0 * t), {"simulated_time": 1.0, "cpu_seconds": 20.0, "peak": 3.0,
                                                  "calm_at": 0.7})
    _run(out, "a_r2", t[:6], 2.5 * np.exp(-8.0 * t[:6]), {"simulated_time": 0.5, "stopped_early": True},
         checkpoint=True)
    entries = [{"name": name, "family": name[0], "status": status, "folder": str(out / "runs" / name), "point": {},
                "replica": int(name[-1]), "duration": 1.0, "physics": f"p-{name[0]}", **stops}
               for name, status in (("a_r1", "finished"), ("a_r2", "stopped"), ("b_r1", "pending"))]
    (out / "study.json").write_text(json.dumps({"study": "toy", "report": "toy", "runs": entries}))
    (out / "study.toml").write_text('name = "toy"\n')


def test_a_toy_report_makes_its_table_findings_status_and_archive(toy, tmp_path):
    out, dest = tmp_path / "study", tmp_path / "archive"
    _toy_study(out)
    written = report(out)
    rows = {r["name"]: r for r in json.loads((out / "table.json").read_text())}
    assert rows["a_r1"]["status"] == "finished" and rows["a_r1"]["peak"] == 3.0
    assert rows["a_r2"]["status"] == "stopped" and rows["a_r2"]["peak"] == pytest.approx(2.5)  # live, from its series
    assert rows["a_r2"]["last_energy"] == pytest.approx(2.5 * np.exp(-4.0))
    assert rows["b_r1"]["status"] == "pending" and rows["b_r1"]["last_energy"] is None
    (finding,) = json.loads((out / "findings.json").read_text())
    assert finding["verdict"] == "holds" and finding["values"] == {"a_r1": 3.0}  # the ended run alone
    assert out / "findings.md" in written
    status = {r["name"]: r for r in study_status(out)["runs"]}
    assert status["a_r1"]["state"] == RunState.ENDED and status["a_r1"]["peak"] == 3.0
    assert status["a_r2"]["state"] == RunState.IN_PROGRESS and status["a_r2"]["energy"] == pytest.approx(
        2.5 * np.exp(-4.0))  # a watched column
    # the archive keeps the report's columns and summary keys, and its report is the study folder's
    archive(out, dest)
    assert (dest / "runs" / "a_r1" / "timeseries.csv").read_text().startswith("time,energy\n")
    assert json.loads((dest / "runs" / "a_r1" / "summary.json").read_text())["peak"] == 3.0
    assert [r["peak"] for r in json.loads((dest / "table.json").read_text())] == [r["peak"] for r in rows.values()]
    assert (dest / "findings.json").read_text() == (out / "findings.json").read_text()


def test_a_toy_stop_condition_tells_the_engine_a_runs_end_its_setting_and_expected_end(toy, tmp_path):
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "summary.json").write_text(json.dumps({"simulated_time": 0.6, "ended": "calm", "calm_at": 0.4}))
    demo = ROOT / "cases" / "demo.toml"
    assert run_at_end(folder, load_case(demo, {"time.min_time": 0.2}))  # 0.2 s past its calm: at its end
    assert not run_at_end(folder, load_case(demo, {"time.min_time": 0.3}))  # the margin raised: it goes on
    del STOP_CONDITIONS["calm"]
    assert not run_at_end(folder, load_case(demo, {"time.min_time": 0.2}))  # an end no condition reads back
    STOP_CONDITIONS["calm"] = TOY_STOP
    # the index lists each run's setting under the condition's key, from its case, beside the others'
    study_file = tmp_path / "toy.toml"
    study_file.write_text(f'name = "toy"\nduration = 1.0\nreport = "toy"\n[settings]\n"time.min_time" = 0.2\n'
                          f'[families.a]\ncase = "{demo}"\n')
    (tmp_path / "out").mkdir()
    (entry,) = write_index(tmp_path / "out", load_study(study_file, tmp_path / "out"))["runs"]
    assert entry["calm_margin"] == 0.2 and "stop_after_mixed" in entry
    # --status: a run on its way that has calmed ends the margin past it (a_r2: calm at 0.5 s, 0.5 s held: 0.2 s
    # left); a run not started ends where the ended runs of its physics did (b_r1: none, its duration)
    out = tmp_path / "study"
    _toy_study(out)
    status = {r["name"]: r for r in study_status(out)["runs"]}
    assert status["a_r2"]["calm_at"] == pytest.approx(0.5) and status["a_r2"]["expected_left"] == pytest.approx(0.2)
    assert status["b_r1"]["expected_left"] == 1.0
