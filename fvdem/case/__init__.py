"""Case files: TOML -> validated, frozen dataclasses.

A case file has one table per part of the model (``[domain]``, ``[particles]``,
``[particles.insertion]``, ``[contact]``, ``[time]``, ``[output]``, ``[run]``). Every value is
checked before anything runs: unknown keys, wrong types, units and ranges are all collected and
reported together as ``CaseError`` with the key path, the value and what is allowed.

Quantities with a dimension are SI numbers, or strings with a unit: ``diameter = "5.3 mm"``.
The fully resolved case (defaults included) can be written back as TOML (``to_toml``).

The package, one module per job: ``schema`` (the dataclasses and their rules), ``parse`` (a table to a
validated case), ``checks`` (the checks across keys), ``suspension`` (the ``[suspension]`` table's
expansion into a dimensional case), ``write`` (a case back to TOML) and ``docs`` (the key reference).
"""
from ..errors import CaseError
from .docs import docs_reference, schema_reference
from .parse import case_from_dict, load_case, parse_override
from .schema import (UNITS, Case, ContactConfig, CouplingConfig, DomainConfig, GasConfig, InsertionConfig,
                     OutputConfig, ParticlesConfig, PorousZoneConfig, RunConfig, SuspensionConfig, TimeConfig,
                     _choices, spec)
from .write import case_as_dict, to_toml

__all__ = ["Case", "CaseError", "load_case", "case_from_dict", "to_toml", "parse_override", "schema_reference",
           "docs_reference", "case_as_dict", "UNITS", "Case", "ContactConfig", "CouplingConfig", "DomainConfig",
           "GasConfig", "InsertionConfig", "OutputConfig", "ParticlesConfig", "PorousZoneConfig", "RunConfig",
           "SuspensionConfig", "TimeConfig", "spec"]
