"""The periodic suspension scene (Derksen): its dimensionless set-up and what it measures.

**Set-up.** ``[suspension]`` is Derksen's periodic liquid fluidization (``../shared/docs/equations.md`` §6),
written into a dimensional case when the case is read: ``fvdem.case.suspension`` (``expand_suspension``)
documents every derived key and which ones a case file may tune.

**Measured** (``Suspension``, ``fvdem.analysis.suspension``): slip Reynolds number, settling velocity,
particle velocity fluctuations and the mixture's z momentum each sample; orientation histograms
every tenth; in the summary, the statistics over the steady window (MSER) with batch-means errors.
"""
from __future__ import annotations

import numpy as np

from ..analysis.suspension import orientation_histogram, settling_velocity, steady_window, velocity_fluctuations
from ..case.suspension import TUNABLE, expand_suspension, suspension_quantities  # noqa: F401  (its set-up, re-exported)
from .base import Observable, Scene, register_scene
from .observables import Coupling, Gas, Mixing, Particles


# --------------------------------------------------------------------------- what it measures
class Suspension(Observable):
    """Slip Reynolds number ``(1 - phi) (u_f - u_p) d_e / nu`` (Derksen's ``(<u_z> - <u_pz>) d_e / nu``,
    see ``fvdem.analysis.suspension``), the settling velocity [m/s], the particle velocity fluctuations
    [m/s] and the z momentum of particles plus liquid [kg m/s] (zero in a force-balanced box); every
    tenth sample the orientation-angle density (spherocylinders). Summary: ``suspension_summary``."""

    name = "suspension"
    plots = ("suspension",)
    keeps_history = True
    COLUMNS = ("slip_reynolds", "settling_velocity", "velocity_fluctuation_vertical",
               "velocity_fluctuation_horizontal", "mixture_momentum_z")

    def columns(self, model):
        return self.COLUMNS

    def measure(self, model, values):
        p, gas, g, mesh = model.particles, model.gas, model.case.gas, model.gas.mesh
        settling, phi = settling_velocity(gas.voidage, mesh.cell_volumes, gas.flux_velocity(), p.velocity)
        sigma_z, sigma_h = velocity_fluctuations(p.velocity)
        momentum = float((p.mass * p.velocity[:, 2]).sum()
                         + g.density * (gas.voidage * mesh.cell_volumes * gas.velocity[:, 2]).sum()
                         + gas.returned_momentum[:, 2].sum())
        return {"slip_reynolds": settling * model.case.particles.equivalent_diameter * g.density / g.viscosity,
                "settling_velocity": settling, "solids_fraction": phi, "velocity_fluctuation_vertical": sigma_z,
                "velocity_fluctuation_horizontal": sigma_h, "mixture_momentum_z": momentum}

    def new_history(self):
        # (time [s], slip Re, settling velocity [m/s], sigma_z, sigma_h [m/s]) rows, and
        # (time [s], orientation-angle density per bin...) rows every tenth sample
        return {"samples": [], "orientations": []}

    def record(self, model, values, history):
        rows = history["samples"]
        if rows and rows[-1][0] >= model.time:
            return
        rows.append((model.time, *(values[k] for k in self.COLUMNS[:4])))
        if len(rows) % 10 == 1 and model.particles.half_length.max() > 0:
            density, _ = orientation_histogram(model.particles.axis)
            history["orientations"].append((model.time, *density.tolist()))

    def summary(self, model, values, history, run):
        return {"suspension": suspension_summary(model.case, history)}


def suspension_summary(case, history) -> dict | None:
    """Steady-window statistics of a periodic suspension: the window (MSER, see ``steady_window``),
    the mean slip Reynolds number with its batch-means standard error, the velocity fluctuations over
    the mean settling velocity, and the orientation-angle density over the window against the random
    ``sin`` (spherocylinders). None before 20 samples."""
    rows = np.asarray(history["samples"], float).reshape(-1, 5)
    if len(rows) < 20:
        return None
    window = steady_window(rows[:, 0], rows[:, 1])
    steady = rows[rows[:, 0] >= window["start"]]
    settling = float(steady[:, 2].mean())
    p = case.particles
    out = {"window_start": window["start"], "window_end": float(rows[-1, 0]), "samples": window["samples"],
           "slip_reynolds": window["mean"], "slip_reynolds_standard_error": window["standard_error"],
           "slip_reynolds_std": window["std"], "settling_velocity": settling,
           "solids_fraction": float(p.count * p.volume / np.prod(np.subtract(case.domain.upper, case.domain.lower))),
           "velocity_fluctuation_vertical_over_settling": float(np.sqrt((steady[:, 3] ** 2).mean())) / settling,
           "velocity_fluctuation_horizontal_over_settling": float(np.sqrt((steady[:, 4] ** 2).mean())) / settling,
           "equivalent_diameter": p.equivalent_diameter,
           "kinematic_viscosity": case.gas.viscosity / case.gas.density}
    orientation = np.asarray(history["orientations"], float)
    if len(orientation):
        late = orientation[orientation[:, 0] >= window["start"]]
        late = late if len(late) else orientation[-1:]
        edges = np.linspace(0.0, 0.5 * np.pi, orientation.shape[1])
        centres = 0.5 * (edges[1:] + edges[:-1])
        density = late[:, 1:].mean(axis=0)
        out.update({"orientation_angle_centres": centres.tolist(), "orientation_density": density.tolist(),
                    "orientation_random_density": np.sin(centres).tolist(),
                    "mean_abs_cos_vertical": float((np.cos(centres) * density).sum() * (edges[1] - edges[0])),
                    "orientation_samples": int(len(late))})
    return out


def is_periodic_suspension(case) -> bool:
    """Moving particles coupled to the liquid in a box periodic along every axis."""
    return (case.particles.count > 0 and case.gas.enabled and case.coupling.enabled and not case.particles.fixed
            and all(case.domain.periodic))


@register_scene("periodic_suspension", is_periodic_suspension)
def periodic_suspension(case) -> Scene:
    """Particles settling through a liquid in a fully periodic, force-balanced box (Derksen)."""
    observables = (Particles(), Gas()) + ((Mixing(case),) if case.particles.colour == "by_height" else ())
    return Scene("periodic_suspension", observables + (Suspension(), Coupling()))
