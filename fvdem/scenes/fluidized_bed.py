"""The fluidized bed scene (Mema et al., 2020): particles carried by gas blown through a walled column's inlet.

Measured: the particles' state, the gas, the mixing of the two colours (when the particles carry
them: ``particles.colour = 'by_height'``), the exchange and the bed pressure drop over W/A.
"""
from __future__ import annotations

from .base import Scene, register_scene
from .observables import BedPressure, Coupling, Gas, Mixing, Particles


def is_fluidized_bed(case) -> bool:
    """Moving particles coupled to the gas in a column that is not periodic along every axis."""
    return (case.particles.count > 0 and case.gas.enabled and case.coupling.enabled and not case.particles.fixed
            and not all(case.domain.periodic))


@register_scene("fluidized_bed", is_fluidized_bed)
def fluidized_bed(case) -> Scene:
    """Particles fluidized by gas through a walled column's inlet (Mema et al., 2020)."""
    mixing = (Mixing(case),) if case.particles.colour == "by_height" else ()
    return Scene("fluidized_bed", (Particles(), Gas()) + mixing + (Coupling(), BedPressure()))
