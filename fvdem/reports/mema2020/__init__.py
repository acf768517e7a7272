"""Mema et al. (2020)'s study (seed 000) as a study report, one module per job: ``table`` (the run table's
columns, what an archive keeps of a run), ``figures`` (the paper's figures), ``rules`` (the first set of the
findings' rules), ``spread`` (replicas: orders and likeness told within their spread), ``families`` (how the
findings count the study's families), ``plan`` (the replicas that would decide the open findings), ``readings``
(the second set of rules, fixed before stage 3, reported beside the first) and ``report`` (registers
``mema2020`` and ``bed``)."""
from . import report  # noqa: F401  (registers the reports)
from . import readings  # noqa: F401,E402  (adds the second set of rules)
from .rules import check_findings  # noqa: F401
from .table import void_fraction_record, void_fraction_samples  # noqa: F401
