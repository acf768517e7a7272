"""Observables shared by the scenes (``fvdem.scenes.base.Observable``): the particles' state, the gas,
the mixing of two colours, the gas-particle exchange and a column's pressure drop over the bed weight."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..analysis.bed import bed_top, bed_weight_per_area, packed_bed_summary
from ..analysis.mixing import MIXED, colour_by_layer, mixing_cells, mixing_indices, mixing_time, random_mixture_entropy
from ..analysis.compare import register_comparison
from ..analysis.plots import COLOUR_LAYERS, PLOTS, plot_colour_layers, read_timeseries
from ..io.vtk import read_pvd
from .base import Observable


class Particles(Observable):
    """DEM state: kinetic energy [J], largest overlap / d, contacts per particle, bed top (99th
    percentile of the particle tops) [m], rms and largest speed [m/s], the particles' momentum
    against gravity [kg m/s] (``sum m v . (-g/|g|)``: its change over a window is what a pressure-drop
    average over that window owes to the bed's acceleration) and the force the walls exert on the
    particles against gravity [N] (``sum F_contact . (-g/|g|)``: the pair forces cancel in the sum, so it
    is the walls' alone, distributor included: the part of the weight the gas does not carry); the
    summary adds the packed bed (core solids fraction, equivalent height), cost per particle-step and
    neighbour rebuilds."""

    name = "particles"
    plots = ("colours", "orientation")
    COLUMNS = ("kinetic_energy", "max_overlap_over_diameter", "contacts_per_particle", "bed_top", "rms_speed",
               "max_speed", "vertical_momentum", "wall_force_vertical")

    def columns(self, model):
        return self.COLUMNS

    def measure(self, model, values):
        p = model.particles
        out = model.dem.diagnostics()
        del out["time"]
        out["bed_top"] = bed_top(p.position, p.axis, p.radius, p.half_length)
        gravity = np.asarray(model.dem.gravity, dtype=np.float64)
        g = float(np.linalg.norm(gravity))
        up = -gravity / g if g > 0.0 else np.array([0.0, 0.0, 1.0])
        out["vertical_momentum"] = float(p.mass @ (p.velocity @ up))
        out["wall_force_vertical"] = float((p.contact_force @ up).sum())
        return out

    def summary(self, model, values, history, run):
        n, case = model.particles.count, model.case
        out = {"particles": n, "shape": case.particles.shape,
               "ns_per_particle_step_last_run": 1e9 * run["wall"] / (run["steps"] * n) if run["steps"] else None,
               "collision_time": case.collision_time(), "neighbour_rebuilds": model.dem.rebuild_count,
               **{k: values[k] for k in ("kinetic_energy", "max_overlap_over_diameter", "contacts_per_particle",
                                         "wall_contacts", "rms_speed", "max_speed")}}
        out.update(packed_bed_summary(model.particles, model.dem.box))
        return out

    def ends(self, model, values, history):
        """``time.stop_when_settled``: "settled" once the rms speed is below ``time.settled_speed``, from
        ``time.min_time`` on."""
        t = model.case.time
        return ("settled" if t.stop_when_settled and model.time >= t.min_time and model.step_count > 0
                and values["rms_speed"] < t.settled_speed else "")


class Gas(Observable):
    """Largest cell speed [m/s], mean pressure of the first cell layer [Pa]; in a walled column the
    pressure drop the particles hold up [Pa]; with a porous zone its pressure gradient and Ergun's."""

    name = "gas"
    plots = ("gas_profile", "void_fraction")

    def columns(self, model):
        columns = ("gas_max_speed", "gas_inlet_pressure")
        if model.gas.zone.any():
            columns += ("porous_zone_pressure_gradient",)
        if not model.gas.periodic:
            columns += ("bed_pressure_drop",)
        return columns

    def measure(self, model, values):
        return model.gas.diagnostics()

    def summary(self, model, values, history, run):
        out = {k: v for k, v in values.items() if k.startswith(("gas_", "porous_", "ergun_", "expected_"))}
        out.update(gas_cells=model.gas.mesh.cell_count, gas_courant_number=model.gas.courant_number())
        return out


class Mixing(Observable):
    """Mixing entropy and Lacey index of two colours on the ``mixing_cells`` grid; the summary adds
    the mixing time t95 (entropy first at 0.95; None while not reached) and the entropy the final bed
    would have with its colours shuffled at random (``mixing_entropy_random``: how close to 1 this grid
    lets a mixed bed come)."""

    name = "mixing"
    plots = ("mixing", "colour_layers")
    comparisons = ("mixing",)
    keeps_history = True

    def __init__(self, case):
        self.cells = mixing_cells(case)
        self._t95, self._scanned = None, False  # ``ends``: t95 once reached, the history searched

    def columns(self, model):
        return ("mixing_entropy", "lacey_index")

    def measure(self, model, values):
        p, d = model.particles, model.case.domain
        entropy, lacey = mixing_indices(p.position, p.colour, d.lower, d.upper, self.cells)
        return {"mixing_entropy": entropy, "lacey_index": lacey}

    def record(self, model, values, history):
        if not history or history[-1][0] < model.time:
            history.append((model.time, values["mixing_entropy"]))

    def summary(self, model, values, history, run):
        rows = np.asarray(history, float).reshape(-1, 2)
        p, d = model.particles, model.case.domain
        return {"mixing_entropy": values["mixing_entropy"], "lacey_index": values["lacey_index"],
                "mixing_entropy_random": random_mixture_entropy(p.position, p.colour, d.lower, d.upper, self.cells),
                "mixing_cells": list(self.cells), "t95": mixing_time(rows[:, 0], rows[:, 1]) if len(rows) else None}

    def ends(self, model, values, history):
        """``time.stop_after_mixed``: "mixed" once that long has passed since t95."""
        margin = model.case.time.stop_after_mixed
        if margin is None or not history:
            return ""
        if self._t95 is None and (history[-1][1] >= MIXED or not self._scanned):  # found once, then kept
            rows = np.asarray(history, float)  # (the whole history once: a resumed run may have mixed before)
            self._t95, self._scanned = mixing_time(rows[:, 0], rows[:, 1]), True
        return "mixed" if past_mixing(self._t95, margin, model.time) else ""


def past_mixing(t95, margin, time) -> bool:
    """Whether ``time`` [s] is ``margin`` (``time.stop_after_mixed``) past the mixing time ``t95`` (None: not
    mixed, no margin: never)."""
    return t95 is not None and margin is not None and time >= t95 + margin - 1e-9


class Coupling(Observable):
    """The exchange: over-packed cells, the drag and pressure-gradient force on the particles along z
    [N]; the summary names the closures and gives the particle weight per cross-section W/A [Pa]."""

    name = "coupling"

    def columns(self, model):
        return ("over_packed_cells", "total_drag_z", "total_pressure_force_z")

    def measure(self, model, values):
        return model.bridge.diagnostics()

    def summary(self, model, values, history, run):
        m, c = model.bridge.model, model.case.coupling
        return {"coupling": {"drag": m.drag, "lift": m.lift, "torque": m.torque, "drag_treatment": c.drag_treatment,
                             "voidage": c.voidage},
                "bed_weight_per_area": weight_per_area(model)}


def weight_per_area(model) -> float:
    d = model.case.domain
    return bed_weight_per_area(model.particles, d.lower, d.upper, d.gravity)


class BedPressure(Observable):
    """A column's bed pressure drop over W/A (1 when the gas carries the bed); the summary gives its
    mean and standard deviation over the run's second half."""

    name = "bed_pressure"
    keeps_history = True

    def columns(self, model):
        return ("pressure_drop_over_weight",)

    def measure(self, model, values):
        return {"pressure_drop_over_weight": values["bed_pressure_drop"] / weight_per_area(model)}

    def record(self, model, values, history):
        if model.step_count > 0:
            history.append((model.time, values["bed_pressure_drop"]))

    def summary(self, model, values, history, run):
        rows = np.asarray(history, float).reshape(-1, 2)
        late = rows[rows[:, 0] >= 0.5 * model.time] if len(rows) else rows
        if not len(late):
            return {}
        mean = float(late[:, 1].mean())
        return {"bed_pressure_drop_mean_second_half": mean, "bed_pressure_drop_std_second_half": float(late[:, 1].std()),
                "pressure_drop_over_weight": mean / weight_per_area(model), "pressure_samples_second_half": int(len(late))}


def colour_layer_record(out) -> dict | None:
    """Per particle snapshot of a run, the particles and the colour-1 fraction in horizontal layers of the
    mixing grid's height (``colour_by_layer``; its vertical cells, from the case), up to the highest layer
    any snapshot reaches: ``{"z_lower", "layer_height", "times", "count", "fraction"}`` (fractions to 4 digits,
    None in an empty layer). From the snapshots, else from an archived ``colour_layers.json``; None without
    either, or without colours."""
    import json

    import meshio

    from ..case import CaseError, load_case
    out = Path(out)
    snapshots = [(t, name) for t, name in read_pvd(out / "particles.pvd") if (out / name).exists()]
    if not snapshots:
        stored = out / COLOUR_LAYERS
        return json.loads(stored.read_text()) if stored.exists() else None
    try:
        case = load_case(out / "case.toml")
    except (CaseError, OSError):
        return None
    layers = mixing_cells(case)[2]
    lower, upper = case.domain.lower, case.domain.upper
    times, counts, fractions = [], [], []
    for t, name in snapshots:
        state = meshio.read(out / name)
        if "colour" not in state.point_data or not len(state.points):
            return None
        count, fraction = colour_by_layer(state.points, state.point_data["colour"], lower, upper, layers)
        times.append(t)
        counts.append(count)
        fractions.append(fraction)
    kept = int(max(np.nonzero(c)[0].max() for c in counts)) + 1
    return {"z_lower": float(lower[2]), "layer_height": (float(upper[2]) - float(lower[2])) / layers, "times": times,
            "count": [c[:kept].tolist() for c in counts],
            "fraction": [[None if np.isnan(x) else round(float(x), 4) for x in f[:kept]] for f in fractions]}


def has_colour_layers(out) -> bool:
    """Two colours (the run measured their mixing) and particle snapshots, or an archived colour-layer record."""
    out = Path(out)
    if not (out / "timeseries.csv").exists() or "mixing_entropy" not in read_timeseries(out):
        return False
    return len(read_pvd(out / "particles.pvd")) > 1 or (out / COLOUR_LAYERS).exists()


# Mixing's chart of where the bed is still unmixed (a record of the snapshots, so drawn here, above fvdem.io)
PLOTS["colour_layers"] = (lambda out: plot_colour_layers(out, colour_layer_record(out)), has_colour_layers)


def colour_layer_items(runs) -> list:
    """``(label, colour-by-layer record, t95)`` of the runs that have one (two colours, and particle snapshots
    or an archived record: what ``fvdem report`` draws it from), for ``plot_colour_layer_panels``."""
    from ..analysis.plots import run_labels, series_t95
    items = []
    for run, label in zip(runs, run_labels(runs)):
        record = colour_layer_record(run) if has_colour_layers(run) else None
        if record is not None:
            items.append((label, record, series_t95(read_timeseries(run))))
    return items


def mixing_groups(runs) -> list[str]:
    """The line of each run on the t95 chart: its case name (runs of one case at several U/Umf make one
    line), unless two runs of that name share a U/Umf (two `demo` runs): then each such run is its own,
    named by its folder."""
    from ..analysis.plots import run_labels
    from ..case import load_case
    cases = [load_case(Path(r) / "case.toml") for r in runs]
    points = [(c.name, c.gas.u_over_umf, c.gas.inlet_velocity) for c in cases]
    labels = run_labels(runs)
    return [labels[k] if points.count(points[k]) > 1 else cases[k].name for k in range(len(runs))]


@register_comparison("mixing", lambda runs: all((Path(r) / "case.toml").exists() for r in runs) and all(
    "mixing_entropy" in read_timeseries(r) for r in runs))
def compare_mixing(runs, out, options) -> list:
    """Mixing entropy against time (mixing_compare.png; by case and U/Umf, the paper's layout:
    mixing_by_velocity.png), t95 against U/Umf (t95.png) and where each bed is still unmixed
    (colour_layers_compare.png, runs with snapshots or an archived record)."""
    from ..analysis.plots import plot_colour_layer_panels, plot_mixing, plot_mixing_by_velocity, plot_t95
    out = Path(out)
    paths = [plot_mixing(runs, out / "mixing_compare.png"), plot_mixing_by_velocity(runs, out / "mixing_by_velocity.png"),
             plot_t95(runs, out / "t95.png", names=mixing_groups(runs))]
    layers = colour_layer_items(runs)
    if layers:
        paths.append(plot_colour_layer_panels(layers, out / "colour_layers_compare.png"))
    return paths
