"""The fixed bed scene: gas through particles that do not move — fixed DEM particles or a porous zone
of given voidage (or an empty column).

Measured: the gas (with a porous zone: its pressure gradient against Ergun's), and, with fixed
DEM particles, their state, the exchange and, in a walled column, the pressure drop over W/A.
"""
from __future__ import annotations

from .base import Scene, register_scene
from .observables import BedPressure, Coupling, Gas, Mixing, Particles


def is_fixed_bed(case) -> bool:
    """Gas, and no particles or fixed ones."""
    return case.gas.enabled and (case.particles.count == 0 or case.particles.fixed)


@register_scene("fixed_bed", is_fixed_bed)
def fixed_bed(case) -> Scene:
    """Gas through a fixed bed of particles or a porous zone."""
    observables = ()
    if case.particles.count > 0:
        observables += (Particles(),)
    observables += (Gas(),)
    if case.particles.count > 0 and case.particles.colour == "by_height":
        observables += (Mixing(case),)
    if case.particles.count > 0 and case.coupling.enabled:
        observables += (Coupling(),) + (() if all(case.domain.periodic) else (BedPressure(),))
    return Scene("fixed_bed", observables)
