"""The settling scene: particles without gas exchange — poured and settled into a bed (the paper's
initial beds, ``cases/bed_ar1.toml``), or beside an uncoupled gas (``coupling.enabled = false``).

Measured: the particles' state (the run stops when settled with ``time.stop_when_settled``), their
mixing when they carry two colours, and the gas when there is one.
"""
from __future__ import annotations

from .base import Scene, register_scene
from .observables import Gas, Mixing, Particles


def is_settling(case) -> bool:
    """Moving particles and no exchange with a gas."""
    return case.particles.count > 0 and not case.particles.fixed and not (case.gas.enabled and case.coupling.enabled)


@register_scene("settling", is_settling)
def settling(case) -> Scene:
    """Particles without gas exchange (settling, packing, pouring)."""
    observables = (Particles(),) + ((Gas(),) if case.gas.enabled else ())
    if case.particles.colour == "by_height":
        observables += (Mixing(case),)
    return Scene("settling", observables)
