"""The study reports registered by name (``StudyReport``, ``register_report``, ``report_for``): what a study's
report makes of its runs, chosen by the study file's ``report = "..."``. A leaf of the study package: the
engine's modules read the registry here, the report modules (``REPORT_MODULES``) register themselves on
first use, and ``fvdem.study.reports`` writes the tables, figures and archives from them."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable


@dataclass(frozen=True)
class StudyReport:
    """What a study's report makes of its runs (each hook optional: ``None`` leaves the generic part alone)."""

    name: str
    summary: str
    run_values: Callable[[dict], dict] | None = None  # summary.json -> values study.json keeps per run
    headline: Callable[[dict], str] | None = None  # a finished run's result -> its progress-line detail
    live: Callable[[dict], dict] | None = None  # time series of a run in progress -> summary-like values
    columns: Callable[[dict, Path, dict, dict | None], dict] | None = None  # (run, folder, data, series) -> columns
    figures: Callable[[Path, list], list] | None = None  # (study folder, runs with a time series) -> PNG paths
    table_figures: Callable[[Path, list], list] | None = None  # (study folder, the table's rows) -> PNG paths
    findings: Callable[[list], list] | None = None  # table rows -> findings.json
    plan: Callable[[list, list, str | None], str] | None = None  # (rows, findings, study name) -> plan.toml
    archived_columns: tuple = ()  # time-series columns an archive keeps besides ``time``
    archived_summary: tuple = ()  # summary keys an archive keeps besides ``ARCHIVED_SUMMARY``
    archive_extra: Callable[[Path, Path], None] | None = None  # (run folder, its archive folder): extra files
    archive_files: tuple = ()  # the files ``archive_extra`` may write: one an archived run lacks is made again
    watch: tuple = ()  # time-series columns whose last value ``fvdem study --status`` shows per run


REPORTS: dict[str, StudyReport] = {}
DEFAULT_REPORT = "table"
# the packages whose import registers reports, imported on first use (the engine names no report of its own but
# "table"; ``fvdem.reports`` imports each published study's report package)
REPORT_MODULES = ("fvdem.reports",)


def register_report(report: StudyReport) -> StudyReport:
    """Make ``report`` available to study files (``report = "<name>"``)."""
    REPORTS[report.name] = report
    return report


def report_for(name: str | None) -> StudyReport:
    """The registered report ``name`` (the default for None); ``report_for(None)`` also fills ``REPORTS``."""
    import importlib
    for module in REPORT_MODULES:  # each once (imported modules are cached)
        importlib.import_module(module)
    return REPORTS[name or DEFAULT_REPORT]


register_report(StudyReport("table", "the generic table: status, simulated and wall seconds, replica of each run"))
