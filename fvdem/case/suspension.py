"""The ``[suspension]`` table's expansion into a dimensional case (the periodic suspension scene's set-up).

**Set-up.** ``[suspension]`` is Derksen's periodic liquid fluidization (``../shared/docs/equations.md`` §6): aspect ratio
``l/d``, density ratio ``gamma``, Galileo number ``Ga = g d^3 / nu^2`` (or ``Ga_e`` on the
volume-equivalent diameter ``d_e = (3 l d^2 / 2)^(1/3)``), mean solids fraction ``<phi>``, box in
diameters and cells per box. ``expand_suspension`` writes the dimensional set-up into the case table:

- particles: ``n = round(<phi> V_box / V_p)``; Derksen's flat-ended cylinder (diameter d, length l)
  becomes the spherocylinder of the same diameter and volume, length ``l + d/3`` (the cylinder part
  ``l - 2d/3`` plus two hemispherical caps), so ``d_e``, mass and ``<phi>`` are Derksen's; spheres
  have diameter d. Placed by compression (``particles.insertion.method = 'compress'``).
- liquid: density ``rho``, ``nu = sqrt(g d^3 / Ga)`` (or ``sqrt(g d_e^3 / Ga_e)``), ``mu = rho nu``;
  particles ``rho_p = gamma rho``.
- force balance: ``gas.mean_pressure_gradient = -rho_mix g`` with ``rho_mix = phi rho_p + (1 - phi) rho``
  (the actual ``phi`` of n particles). fvdem applies it as ``eps G`` to the liquid and ``V_p G`` to
  each particle: the total force on the box is zero, Derksen's body force ``(rho_p - rho) <phi> g``
  on the liquid in another split (``G - rho g`` on the liquid per volume equals it when phi = <phi>).
- box periodic in x, y, z; no walls; gas grid ``cells``.
- rotational drag on (``coupling.rotational_drag = 'stokes'``): in a liquid it damps the tumbling
  that contacts start; without it a rod spins freely and its orientation samples its rotation plane
  uniformly instead of Derksen's distribution.
- momentum exactly exchanged: trilinear voidage (the transpose of the interpolation, so the
  pressure-gradient forces on liquid and particles sum to zero over the periodic box) and SIMPLE
  iterated to convergence each step (PISO's velocity is not the momentum equation's solution with the
  final pressure: measured, the box's momentum drifts by 3e-5 of the particles' momentum with PISO
  and by 16 % with the divided voidage); direct linear solves and SIMPLE converged to 1e-12 hold it
  to round-off (4e-14; 2e-9 with Krylov solves to 1e-8, 1e-10 with SIMPLE converged to 1e-8).
- contact stiffness: a head-on collision at the gravitational velocity ``sqrt((gamma - 1) g d_e)``
  overlaps ``overlap x d`` (``k_n = m* v^2 / (overlap d)^2`` with ``m* = m/2``); DEM step 1/20 of the
  collision time; CFD step the multiple of it closest to ``0.5 cell / v`` (SIMPLE converges each
  step; the drag is semi-implicit); end ``duration d^2 / nu``.

Keys the scene derives may also be given in the case file only with the derived value; the tunable
ones (``contact.normal_stiffness``, ``time.dem_step``, ``gas.cfd_step``, ``time.end``,
``coupling.rotational_drag``, ``coupling.voidage``, ``gas.scheme``,
``gas.linear_solver``, ``gas.simple_tolerance``, ``output.*``) take the case file's value when given.
The scene that runs and measures it: ``fvdem.scenes.suspension``.
"""
from __future__ import annotations

import copy
import math

from ..dem.contact_law import collision_time

TUNABLE = {("contact", "normal_stiffness"), ("time", "dem_step"), ("gas", "cfd_step"), ("time", "end"),
           ("coupling", "rotational_drag"), ("coupling", "voidage"), ("gas", "scheme"), ("gas", "linear_solver"),
           ("gas", "simple_tolerance")}


def suspension_quantities(s, gravity: float) -> dict:
    """Derived dimensional quantities of a ``SuspensionConfig`` (SI)."""
    d = s.diameter
    if s.particle == "sphere":
        volume, length, d_e = math.pi / 6 * d ** 3, None, d
    else:
        ell = s.aspect_ratio * d
        volume, length, d_e = math.pi / 4 * d * d * ell, ell + d / 3.0, (1.5 * ell * d * d) ** (1.0 / 3.0)
    if s.galileo is not None:
        nu = math.sqrt(gravity * d ** 3 / s.galileo)
    else:
        nu = math.sqrt(gravity * d_e ** 3 / s.galileo_equivalent)
    box = [b * d for b in s.box]
    box_volume = math.prod(box)
    count = max(1, round(s.solids_fraction * box_volume / volume))
    phi = count * volume / box_volume
    rho, rho_p = s.liquid_density, s.density_ratio * s.liquid_density
    mixture = phi * rho_p + (1.0 - phi) * rho
    mass = rho_p * volume
    velocity = math.sqrt((s.density_ratio - 1.0) * gravity * d_e)
    stiffness = 0.5 * mass * velocity ** 2 / (s.overlap * d) ** 2
    return {"volume": volume, "length": length, "equivalent_diameter": d_e, "kinematic_viscosity": nu,
            "box": box, "count": count, "solids_fraction": phi, "particle_density": rho_p,
            "mixture_density": mixture, "mass": mass, "gravitational_velocity": velocity,
            "normal_stiffness": stiffness, "viscous_time": d * d / nu,
            "archimedes": (s.density_ratio - 1.0) * gravity * d_e ** 3 / nu ** 2}


def _steps(q, s, case) -> tuple[float, float]:
    tc = collision_time(q["normal_stiffness"], 0.5 * q["mass"], case.contact.restitution)
    dem = float(f"{tc / 20.0:.2g}")
    while dem > tc / 20.0:
        dem *= 0.9
        dem = float(f"{dem:.2g}")
    cell = min(b / n for b, n in zip(q["box"], s.cells))
    multiple = max(1, round(0.5 * cell / q["gravitational_velocity"] / dem))
    return dem, multiple * dem


def expand_suspension(case, table: dict, problems: list) -> dict:
    """The case table with the suspension's derived keys written in (see the module docstring);
    conflicts with keys the case file sets go to ``problems``."""
    s = case.suspension
    if (s.galileo is None) == (s.galileo_equivalent is None):
        problems.append("suspension: give exactly one of galileo (on d) and galileo_equivalent (on d_e)")
        return table
    gravity_vector = case.domain.gravity
    gravity = math.sqrt(sum(g * g for g in gravity_vector))
    if gravity == 0.0:
        problems.append("domain.gravity = [0, 0, 0]: a suspension needs gravity")
        return table
    q = suspension_quantities(s, gravity)
    user_stiffness = "normal_stiffness" in table.get("contact", {})
    stiffness = case.contact.normal_stiffness if user_stiffness else q["normal_stiffness"]
    q_steps = dict(q, normal_stiffness=stiffness)
    dem, cfd = _steps(q_steps, s, case)
    particles = {"shape": "sphere" if s.particle == "sphere" else "spherocylinder", "count": q["count"],
                 "diameter": s.diameter, "density": q["particle_density"], "colour": "single"}
    if q["length"] is not None:
        particles["length"] = q["length"]
    derived = {
        ("domain", "lower"): (0.0, 0.0, 0.0), ("domain", "upper"): tuple(q["box"]),
        ("domain", "periodic"): (True, True, True),
        ("gas", "enabled"): True, ("gas", "cells"): tuple(s.cells), ("gas", "density"): s.liquid_density,
        ("gas", "viscosity"): s.liquid_density * q["kinematic_viscosity"],
        ("gas", "mean_pressure_gradient"): tuple(0.0 - q["mixture_density"] * g for g in gravity_vector),
        ("contact", "normal_stiffness"): stiffness, ("time", "dem_step"): dem, ("gas", "cfd_step"): cfd,
        ("time", "end"): s.duration * q["viscous_time"], ("coupling", "rotational_drag"): "stokes",
        ("coupling", "voidage"): "trilinear", ("gas", "scheme"): "simple", ("gas", "linear_solver"): "direct",
        ("gas", "simple_tolerance"): 1e-12,
        **{("particles", k): v for k, v in particles.items()},
    }
    out = copy.deepcopy(table)
    for (sec, key), value in derived.items():
        given = table.get(sec, {})
        if key in given and (sec, key) not in TUNABLE:
            have = getattr(getattr(case, sec), key)
            if not _same(have, value):
                problems.append(f"{sec}.{key} = {given[key]!r}: set by [suspension] to {_show(value)}; remove it "
                                "(or leave [suspension] disabled)")
            continue
        if key in given:
            continue
        out.setdefault(sec, {})[key] = list(value) if isinstance(value, tuple) else value
    insertion = out.setdefault("particles", {}).setdefault("insertion", {})
    insertion.setdefault("method", "compress")
    if s.particle == "sphere" and "aspect_ratio" in table.get("suspension", {}):
        problems.append("suspension.aspect_ratio: only for particle = 'cylinder'")
    return out


def _same(a, b) -> bool:
    if isinstance(b, tuple):
        return a is not None and len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(b, (bool, str)) or b is None:
        return a == b
    return a is not None and math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=1e-15)


def _show(value) -> str:
    if isinstance(value, tuple):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    return f"{value:.6g}" if isinstance(value, float) else repr(value)
