"""Study reports of published studies, each a package that registers its ``StudyReport`` with the study engine
(``fvdem.study.registry``): the engine knows them by name only (``report = "..."`` in a study file) and imports
the modules named in ``fvdem.study.registry.REPORT_MODULES`` on first use.

- ``mema2020``: Mema et al. (2020), seed 000: the bed's run table, the paper's figures and findings (two sets of
  rules), and the ``bed`` report (the run table without the findings)."""
from . import mema2020  # noqa: F401  (registers its reports)
