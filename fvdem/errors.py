"""fvdem's errors, in a leaf module every layer may import (no arrow upward from the gas or the DEM):

- ``CaseError`` (a ``ValueError``): invalid input, a case, study or cluster file or a command-line value;
  ``problems`` lists one message per offending key. The command line exits 2 with them, no traceback.
- ``SimulationError`` (a ``RuntimeError``): a run cannot continue (non-finite values, particles lost,
  unstable settings), with the cause and the setting to change.
- ``OutputError`` (a ``RuntimeError``): an output folder cannot be used as asked (it exists, there is
  nothing to resume, the disk is full).

Their historical homes (``fvdem.case``, ``fvdem.dem.system``, ``fvdem.io.run_folder``) re-export them.
"""
from __future__ import annotations


class CaseError(ValueError):
    """Invalid case input. ``problems`` lists one message per offending key."""

    def __init__(self, problems):
        self.problems = list(problems)
        super().__init__("\n".join(self.problems))


class SimulationError(RuntimeError):
    """A run cannot continue (non-finite values, particles lost, unstable settings)."""


class OutputError(RuntimeError):
    """The output folder cannot be used as asked (exists, or nothing to resume)."""


__all__ = ["CaseError", "SimulationError", "OutputError"]
