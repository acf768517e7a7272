"""Scenes: the kinds of run and what each measures (``base``), registered by name.

=====================  ==================================================================
``periodic_suspension``  moving particles in a fully periodic coupled box (Derksen)
``fluidized_bed``        moving particles coupled to gas in a walled column (Mema et al., 2020)
``fixed_bed``            gas through fixed particles or a porous zone
``settling``             particles without gas exchange
=====================  ==================================================================

``scene_for(case)`` picks the first that applies, in this order; ``SCENES`` lists them. The
``[suspension]`` table's expansion into a dimensional case is ``suspension.expand_suspension``.
"""
from .base import SCENES, Observable, Scene, comparisons_of, plots_of, register_scene, scene_for
from . import suspension, fluidized_bed, fixed_bed, settling  # noqa: F401,E402  (registration order)
from .suspension import TUNABLE, expand_suspension, suspension_quantities

__all__ = ["SCENES", "Observable", "Scene", "comparisons_of", "plots_of", "register_scene", "scene_for", "expand_suspension",
           "suspension_quantities", "TUNABLE"]
