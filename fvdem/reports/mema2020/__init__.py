"""Mema et al. (2020)'s study (seed 000) as a study report: ``report`` (the run table's columns, the paper's
figures, the first set of findings' rules, the archive's extras; registers ``mema2020`` and ``bed``) and
``readings`` (the second set of rules, fixed before stage 3, reported beside the first)."""
from .report import check_findings, void_fraction_record, void_fraction_samples  # noqa: F401  (registers them)
from . import readings  # noqa: F401,E402  (adds the second set of rules)
