"""Seed 000's study report (Mema et al. (2020), §5-§6), registered as ``"mema2020"``, and the ``"bed"`` report
(its run table without the paper's figures and findings): the hooks of each (``fvdem.study.registry.StudyReport``)
from the package's modules, one per job (``table``, ``figures``, ``rules``, ``plan``)."""
from __future__ import annotations

from dataclasses import replace

from ...analysis.plots import COLOUR_LAYERS
from ...study.registry import StudyReport, register_report
from .figures import draw_figures, draw_table_figures
from .plan import plan_points
from .rules import check_findings
from .table import CHANNELS, VOID_FRACTION, archive_extra, headline, live_values, table_columns


MEMA2020 = register_report(StudyReport(
    "mema2020", "seed 000 (Mema et al., 2020): mixing and t95 figures, pressure drop, binarity, the paper's findings",
    run_values=lambda summary: {"t95": summary.get("t95")}, headline=headline, live=live_values, columns=table_columns,
    figures=draw_figures, table_figures=draw_table_figures, findings=check_findings, plan=plan_points,
    archived_columns=("mixing_entropy", "lacey_index", "pressure_drop_over_weight", "bed_pressure_drop", "bed_top",
                      "rms_speed", "max_overlap_over_diameter", "gas_max_speed"),
    archived_summary=("t95", "pressure_drop_over_weight", "bed_pressure_drop_std_second_half", "bed_weight_per_area",
                      "bed_height", "mixing_cells", "mixing_entropy_random"),
    archive_extra=archive_extra, archive_files=(VOID_FRACTION, CHANNELS, COLOUR_LAYERS), watch=("mixing_entropy",)))

# the same per-run table without the paper's figures and findings: a designed screening of a bed (its responses
# are these columns: t95, dense_bed_expansion, pressure_drop_std_over_weight, corner_gas_share, ...)
register_report(replace(
    MEMA2020, name="bed", summary="a fluidized bed's run table (t95, expansion, pressure-drop fluctuation, channels, "
    "rod alignment, overlaps) without the paper's findings: for screenings and studies of one's own bed",
    figures=None, table_figures=None, findings=None, plan=None))
