"""The checks across keys of a validated case (stability of the gas step, the DEM step against the
collision time, the coupling's settings against the gas and the particles)."""
from __future__ import annotations

import math

from ..coupling.closures import law
from ..gas.inlet import step_of
from .schema import Case


MAX_INLET_COURANT = 1.0


def _gas_checks(case: Case, problems: list) -> None:
    g = case.gas
    if case.particles.count == 0 and not g.enabled:
        problems.append("particles.count = 0: a case without particles needs the gas phase (gas.enabled = true)")
    if case.particles.fixed and not g.enabled:
        problems.append("particles.fixed = true: fixed particles without the gas phase leave nothing to "
                        "simulate (set gas.enabled = true)")
    if not g.enabled:
        return
    periodic = case.domain.periodic
    if any(periodic) and not all(periodic):
        problems.append(f"domain.periodic = {list(periodic)}: with the gas phase the box is periodic on all axes "
                        "or on none")
    if any(g.mean_pressure_gradient) and not all(periodic):
        problems.append(f"gas.mean_pressure_gradient = {list(g.mean_pressure_gradient)}: only for a fully periodic "
                        "box (a walled column has its own pressure)")
    if all(periodic) and g.inlet_velocity > 0:
        problems.append(f"gas.inlet_velocity = {g.inlet_velocity:g}: a periodic box has no inlet")
    _inlet_checks(case, problems)
    if case.particles.count > 0:
        ratio = g.cfd_step / case.time.dem_step
        if abs(ratio - round(ratio)) > 1e-9 * ratio or round(ratio) < 1:
            problems.append(f"gas.cfd_step = {g.cfd_step:g}: must be a whole multiple of time.dem_step = "
                            f"{case.time.dem_step:g}")
    # the gas solver's explicit parts (the old-flux Rhie-Chow correction, the exact-exchange return)
    # diverge from an inlet Courant number of about 1.3 with PISO (tools/stability_map.py, cfd map): refuse
    # > 1; SIMPLE iterates each step to convergence and takes large (steady-state) steps
    spacing = min((hi - lo) / n for lo, hi, n in zip(case.domain.lower, case.domain.upper, g.cells))
    fastest = max([g.inlet_velocity, *(u for _, u in g.inlet_steps)])  # the inlet's largest velocity
    courant = fastest * g.cfd_step / spacing
    if g.scheme == "piso" and courant > MAX_INLET_COURANT:
        problems.append(f"gas.cfd_step = {g.cfd_step:g}: the inlet Courant number U dt / dx = {courant:.3g} "
                        f"(U {fastest:g} m/s, cell {spacing:.3g} m) exceeds {MAX_INLET_COURANT:g}; the gas "
                        f"PISO solver diverges from about 1.3 (docs/speed-accuracy.md); use cfd_step <= "
                        f"{MAX_INLET_COURANT * spacing / fastest:.3g} s")
    zone = g.porous_zone
    if zone.enabled and (zone.lower is None or zone.upper is None):
        problems.append("gas.porous_zone: lower and upper corners are required when enabled")
    if zone.enabled and case.particles.count > 0 and case.coupling.enabled:
        problems.append("gas.porous_zone: a case with coupled particles models its bed with the particles; "
                        "disable the porous zone or set coupling.enabled = false")
    if case.particles.count > 0 and case.coupling.enabled:
        _coupling_checks(case, problems)


def _inlet_checks(case: Case, problems: list) -> None:
    """``gas.inlet_steps``: a walled column's, after the start-up ramp, one CFD step each."""
    g = case.gas
    if not g.inlet_steps:
        return
    if all(case.domain.periodic):
        problems.append("gas.inlet_steps: a periodic box has no inlet")
    first_time = g.inlet_steps[0][0]
    if first_time < g.inlet_ramp:
        problems.append(f"gas.inlet_steps: the first step at {first_time:g} s falls inside the start-up ramp "
                        f"(gas.inlet_ramp = {g.inlet_ramp:g} s)")
    steps = [step_of(t, g.cfd_step) for t, _ in g.inlet_steps]
    for (a, _), (b, _), step_a, step_b in zip(g.inlet_steps, g.inlet_steps[1:], steps, steps[1:]):
        if step_a == step_b:
            problems.append(f"gas.inlet_steps: the steps at {a:g} s and {b:g} s fall in one CFD step "
                            f"(gas.cfd_step = {g.cfd_step:g} s)")


def _coupling_checks(case: Case, problems: list) -> None:
    """Each chosen law fits the particles: its shapes and the aspect ratio it was fitted for (registry)."""
    c, p = case.coupling, case.particles
    shape = "sphere" if p.shape == "sphere" or p.length is None else "spherocylinder"
    aspect = 1.0 if shape == "sphere" else p.length / p.diameter
    for kind in ("drag", "lift", "torque"):
        chosen = law(kind, getattr(c, kind))
        if shape not in chosen.shapes:
            if kind == "drag":
                fitted = (f"aspect-ratio-{chosen.aspect_ratio:g} " if chosen.aspect_ratio is not None else "")
                problems.append(f"coupling.drag = {chosen.name!r}: fitted for {fitted}"
                                f"{' and '.join(chosen.shapes)}s; spheres use 'hoelzer-sommerfeld'")
            else:
                problems.append(f"coupling.{kind} = {chosen.name!r}: a sphere has no orientation-dependent "
                                f"{kind}; use coupling.{kind} = 'none'")
        elif chosen.aspect_ratio is not None and abs(aspect - chosen.aspect_ratio) > 0.05 * chosen.aspect_ratio:
            problems.append(f"coupling.{kind} = {chosen.name!r}: its coefficients are fitted for aspect ratio "
                            f"{chosen.aspect_ratio:g}; the particles have {aspect:.3g} (use 'hoelzer-sommerfeld' "
                            "drag and no lift/torque)")
    if c.stochastic_force != "none":
        if p.fixed:
            problems.append(f"coupling.stochastic_force = {c.stochastic_force!r}: fixed particles do not move; the "
                            "stochastic force is for moving particles (set it to 'none')")
        elif c.drag == "none":
            problems.append(f"coupling.stochastic_force = {c.stochastic_force!r}: its level is a fraction of the "
                            "drag, and coupling.drag = 'none' (choose a drag law or set it to 'none')")


def _cross_checks(case: Case, problems: list) -> None:
    lower, upper = case.domain.lower, case.domain.upper
    if any(u <= lo for lo, u in zip(lower, upper)):
        problems.append(f"domain.upper = {list(upper)}: must exceed domain.lower = {list(lower)} on every axis")
        return
    _gas_checks(case, problems)
    if case.time.stop_after_mixed is not None and (case.particles.count == 0 or case.particles.colour != "by_height"):
        problems.append(f"time.stop_after_mixed = {case.time.stop_after_mixed:g}: the mixing entropy needs two "
                        "colours (particles.colour = 'by_height'); remove the key or colour the particles")
    if case.particles.count == 0:
        return
    p = case.particles
    if p.shape == "spherocylinder":
        if p.length is None:
            problems.append("particles.length: required for shape 'spherocylinder' (length including caps, m)")
            return
        if p.length <= p.diameter:
            problems.append(f"particles.length = {p.length:g}: must exceed particles.diameter = {p.diameter:g} "
                            "(a length equal to the diameter is a sphere)")
            return
    elif p.length is not None:
        problems.append(f"particles.length = {p.length:g}: only for shape 'spherocylinder'; remove it for spheres")
        return
    box_volume = math.prod(u - lo for lo, u in zip(lower, upper))
    solid = p.count * p.volume
    if solid > 0.64 * box_volume:
        problems.append(f"particles.count = {p.count}: {p.count} particles of {p.volume:.4g} m^3 fill "
                        f"{solid / box_volume:.1%} of the domain; at most 64 % (random close packing) fits")
    extent = p.diameter + 2 * p.half_length
    for d, axis in enumerate("xyz"):
        if upper[d] - lower[d] < extent:
            problems.append(f"domain: the box is {upper[d] - lower[d]:g} m along {axis}, narrower than one "
                            f"particle ({extent:g} m)")
    if p.initial_state is None and p.insertion.method == "compress":
        if not all(case.domain.periodic):
            problems.append("particles.insertion.method = 'compress': only for a fully periodic box "
                            "(domain.periodic = [true, true, true])")
        elif solid > 0.55 * box_volume:
            problems.append(f"particles.count = {p.count}: solids fraction {solid / box_volume:.3f} above 0.55, "
                            "more than a random packing made by compression reaches")
    elif p.initial_state is None:
        ins = p.insertion
        lo = ins.lower or lower
        hi = ins.upper or upper
        if any(h <= l for l, h in zip(lo, hi)):
            problems.append(f"particles.insertion.upper = {list(hi)}: must exceed the lower corner {list(lo)}")
        else:
            region = math.prod(h - l for l, h in zip(lo, hi))
            if solid > 0.35 * region:
                problems.append(f"particles.insertion: {p.count} particles fill {solid / region:.1%} of the "
                                "insertion region; random insertion reaches at most 35 %: enlarge the region")
            if any(l < dl - 1e-12 or h > dh + 1e-12 for l, h, dl, dh in zip(lo, hi, lower, upper)):
                problems.append(f"particles.insertion: region {list(lo)}-{list(hi)} must lie inside the domain")
    reach = 2.0 * (p.radius + p.half_length) + case.neighbour_skin()
    for d, axis in enumerate("xyz"):
        if case.domain.periodic[d] and upper[d] - lower[d] < 3.0 * reach:
            problems.append(f"domain.periodic: the periodic box is {upper[d] - lower[d]:g} m along {axis}; it must "
                            f"be at least 3 x the neighbour reach {reach:.4g} m")
    try:
        tc = case.collision_time()
    except ValueError as exc:  # the dashpot cannot reach the restitution (e.g. e -> 0)
        problems.append(f"contact.restitution = {case.contact.restitution:g}: {exc}")
        return
    if case.time.dem_step > tc / 10.0:
        problems.append(f"time.dem_step = {case.time.dem_step:.3g}: DEM time step {case.time.dem_step:.3g} s exceeds "
                        f"1/10 of the collision time {tc:.3g} s (k_n = {case.contact.normal_stiffness:g} N/m, "
                        f"particle mass {p.mass:.3g} kg); use at most {tc / 10.0:.3g} s")
    for key in ("snapshot_interval", "timeseries_interval", "checkpoint_interval"):
        value = getattr(case.output, key)
        if value < case.time.dem_step:
            problems.append(f"output.{key} = {value:g}: shorter than the DEM time step {case.time.dem_step:g} s")
