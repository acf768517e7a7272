"""The case file's schema: one frozen dataclass per table (``[domain]``, ``[particles]``, ...), each field
with its rule (kind, unit, range, choices or registry, doc) in its metadata (``spec``); the units a
dimensioned value may carry; the registries whose names some keys take."""
from __future__ import annotations

from dataclasses import MISSING, dataclass, field
from pathlib import Path

from ..coupling.closures import describe_laws, law_names
from ..coupling.stochastic import describe_stochastic_forces, stochastic_force_names
from ..coupling.voidage import describe_voidage, voidage_names
from ..dem.backends import backend_names, describe_backends
from ..dem.contact_law import DEFAULTS as CONTACT, collision_time
from ..dem.particles import spherocylinder_volume, volume_equivalent_diameter


UNITS = {
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "um": 1e-6},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    "density": {"kg/m^3": 1.0, "kg/m3": 1.0, "g/cm^3": 1e3, "g/cm3": 1e3},
    "stiffness": {"N/m": 1.0, "kN/m": 1e3, "N/mm": 1e3},
    "velocity": {"m/s": 1.0, "cm/s": 1e-2, "mm/s": 1e-3},
    "acceleration": {"m/s^2": 1.0, "m/s2": 1.0},
}


def spec(default=MISSING, *, kind="float", unit=None, gt=None, ge=None, lt=None, le=None, choices=None,
         registry=None, optional=False, doc=""):
    """A dataclass field with its validation rule in the metadata. ``registry``: the allowed names are
    those registered in ``REGISTRIES[registry]`` when the case is checked (not a fixed list)."""
    meta = dict(kind=kind, unit=unit, gt=gt, ge=ge, lt=lt, le=le, choices=choices, registry=registry,
                optional=optional, doc=doc)
    if isinstance(default, (list, dict)):
        return field(default_factory=lambda: default, metadata=meta)
    return field(default=default, metadata=meta)


def section(cls, doc=""):
    return field(default_factory=cls, metadata=dict(kind="section", doc=doc))


# registries whose names case keys take: (names, one line per name, the module that registers them)
REGISTRIES = {
    "drag": (lambda: law_names("drag"), lambda: describe_laws("drag"), "fvdem.coupling.closures"),
    "lift": (lambda: law_names("lift"), lambda: describe_laws("lift"), "fvdem.coupling.closures"),
    "torque": (lambda: law_names("torque"), lambda: describe_laws("torque"), "fvdem.coupling.closures"),
    "voidage": (voidage_names, describe_voidage, "fvdem.coupling.voidage"),
    "stochastic_force": (stochastic_force_names, describe_stochastic_forces, "fvdem.coupling.stochastic"),
    "dem_backend": (backend_names, describe_backends, "fvdem.dem.backends"),
}


def _choices(meta):
    if meta.get("registry"):
        return REGISTRIES[meta["registry"]][0]()
    return meta.get("choices")


@dataclass(frozen=True)
class DomainConfig:
    lower: tuple = spec((0.0, 0.0, 0.0), kind="vec3", unit="length", doc="lower corner of the box [m]")
    upper: tuple = spec((0.15, 0.15, 1.05), kind="vec3", unit="length", doc="upper corner of the box [m]")
    periodic: tuple = spec((False, False, False), kind="bool3",
                           doc="periodic axes (x, y, z); the other axes have walls on both faces")
    gravity: tuple = spec((0.0, 0.0, -9.81), kind="vec3", unit="acceleration", doc="gravity [m/s^2]")


@dataclass(frozen=True)
class InsertionConfig:
    lower: tuple | None = spec(None, kind="vec3", unit="length", optional=True,
                               doc="insertion region lower corner [m] (default: domain)")
    upper: tuple | None = spec(None, kind="vec3", unit="length", optional=True,
                               doc="insertion region upper corner [m] (default: domain)")
    orientation: str = spec("random", kind="str", choices=("random", "vertical", "horizontal"),
                            doc="axis orientation of inserted spherocylinders")
    gap: float = spec(0.0, unit="length", ge=0.0, doc="extra clearance between inserted particles [m]")
    seed: int = spec(1, kind="int", ge=0, le=2**32 - 1, doc="random seed")
    method: str = spec("sequential", kind="str", choices=("sequential", "compress"),
                        doc="'sequential': random sequential insertion (up to a solids fraction of about 0.35 of "
                            "the region); 'compress': fully periodic boxes only, insertion into a larger box "
                            "compressed to the domain (random packings up to 0.55)")


@dataclass(frozen=True)
class ParticlesConfig:
    shape: str = spec("sphere", kind="str", choices=("sphere", "spherocylinder"))
    count: int = spec(1000, kind="int", ge=0, le=10**9, doc="number of particles (0: a gas-only case)")
    diameter: float = spec(5.3e-3, unit="length", gt=0.0, doc="sphere or cylinder diameter [m]")
    length: float | None = spec(None, unit="length", gt=0.0, optional=True,
                                doc="spherocylinder length including caps [m] (> diameter)")
    density: float = spec(1442.0, unit="density", gt=0.0, doc="particle density [kg/m^3]")
    colour: str = spec("by_height", kind="str", choices=("by_height", "single"),
                       doc="tracer colour: 'by_height' gives the lower half 0 and the upper half 1")
    initial_state: str | None = spec(None, kind="str", optional=True,
                                     doc="start from a saved state (.npz written by a run), path relative "
                                         "to the case file; insertion is then skipped")
    fixed: bool = spec(False, kind="bool",
                       doc="hold the particles in place (a fixed bed): no motion or contacts are computed; "
                           "the gas still flows through them and feels their drag")
    insertion: InsertionConfig = section(InsertionConfig)

    @property
    def radius(self) -> float:
        return 0.5 * self.diameter

    @property
    def aspect_ratio(self) -> float:
        """Total length over diameter (1 for spheres)."""
        return 1.0 if self.shape == "sphere" else self.length / self.diameter

    @property
    def half_length(self) -> float:
        """Half the cylindrical part [m] (0 for spheres)."""
        return 0.0 if self.shape == "sphere" else 0.5 * (self.length - self.diameter)

    @property
    def volume(self) -> float:
        return float(spherocylinder_volume(self.radius, self.half_length))

    @property
    def mass(self) -> float:
        return self.density * self.volume

    @property
    def equivalent_diameter(self) -> float:
        """Diameter of the sphere of the particle's volume, d_e [m]."""
        return float(volume_equivalent_diameter(self.radius, self.half_length))


@dataclass(frozen=True)
class ContactConfig:  # the defaults: fvdem.dem.contact_law.DEFAULTS (ContactModel's too)
    normal_stiffness: float = spec(CONTACT["normal_stiffness"], unit="stiffness", gt=0.0,
                                   doc="linear normal spring k_n [N/m] (default from the speed-accuracy front, "
                                       "docs/speed-accuracy.md; Mema et al. (2020): 2e4 with dem_step 1e-5)")
    restitution: float = spec(CONTACT["restitution"], gt=0.0, le=1.0, doc="coefficient of restitution e in (0, 1]")
    friction: float = spec(CONTACT["friction"], ge=0.0, doc="sliding friction coefficient mu")
    rolling_friction: float = spec(CONTACT["rolling_friction"], ge=0.0,
                                   doc="rolling friction coefficient mu_r (CDT model)")
    wall_friction: float | None = spec(CONTACT["wall_friction"], ge=0.0, optional=True,
                                       doc="particle-wall sliding friction (default: friction, as particle-particle)")
    wall_rolling_friction: float | None = spec(CONTACT["wall_rolling_friction"], ge=0.0, optional=True,
                                               doc="particle-wall rolling friction (default: rolling_friction)")
    tangential_stiffness_ratio: float = spec(CONTACT["tangential_stiffness_ratio"], gt=0.0, doc="k_t / k_n")
    tangential_damping_ratio: float = spec(CONTACT["tangential_damping_ratio"], ge=0.0, doc="eta_t / eta_n")
    neighbour_skin: float | None = spec(None, unit="length", gt=0.0, optional=True,
                                        doc="neighbour-list skin [m], fixed (default: adapted at each rebuild to keep "
                                            "about 8 DEM steps between rebuilds, from 0.1 to 1 diameter)")


@dataclass(frozen=True)
class TimeConfig:
    dem_step: float = spec(5.0e-5, unit="time", gt=0.0,
                           doc="DEM time step [s] (default: 1/14 of the default spring's collision time for the "
                               "paper's particles; Mema et al. (2020): 1e-5)")
    end: float = spec(0.1, unit="time", gt=0.0, doc="simulated end time [s]")
    stop_when_settled: bool = spec(False, kind="bool", doc="end early once the bed is at rest")
    settled_speed: float = spec(0.005, unit="velocity", gt=0.0,
                                doc="'at rest' means a root-mean-square particle speed below this [m/s]")
    min_time: float = spec(0.0, unit="time", ge=0.0, doc="never stop as settled before this time [s]")
    stop_after_mixed: float | None = spec(None, unit="time", ge=0.0, optional=True,
                                          doc="end this long after the mixing entropy first reaches 0.95 (t95) "
                                              "[s]; needs particles.colour = 'by_height' (default: run to time.end)")


@dataclass(frozen=True)
class OutputConfig:
    snapshot_interval: float = spec(0.05, unit="time", gt=0.0, doc="particle VTU snapshots every [s]")
    timeseries_interval: float = spec(1.0e-3, unit="time", gt=0.0, doc="timeseries.csv rows every [s]")
    checkpoint_interval: float = spec(0.1, unit="time", gt=0.0, doc="checkpoints every [s]")
    vtk: bool = spec(True, kind="bool", doc="write ParaView snapshots")
    mixing_cells: tuple | None = spec(None, kind="int3", ge=1, optional=True,
                                      doc="analysis grid of the mixing entropy (default: half the gas grid, "
                                          "the paper's 5 x 5 x 35 on 10 x 10 x 70; without gas 5 x 5 x 35)")
    progress: bool = spec(True, kind="bool", doc="show a progress bar")


@dataclass(frozen=True)
class PorousZoneConfig:
    enabled: bool = spec(False, kind="bool", doc="a fixed bed: a zone of given voidage with Ergun drag on the gas")
    lower: tuple | None = spec(None, kind="vec3", unit="length", optional=True, doc="zone lower corner [m]")
    upper: tuple | None = spec(None, kind="vec3", unit="length", optional=True, doc="zone upper corner [m]")
    voidage: float = spec(0.45, gt=0.0, le=1.0, doc="gas volume fraction in the zone")
    particle_diameter: float = spec(5.3e-3, unit="length", gt=0.0, doc="Ergun particle diameter [m]")


@dataclass(frozen=True)
class GasConfig:
    enabled: bool = spec(False, kind="bool", doc="solve the gas phase (FiPy grid over the domain)")
    cells: tuple = spec((10, 10, 70), kind="int3", ge=1, le=10000, doc="grid cells along x, y, z")
    density: float = spec(1.2, unit="density", gt=0.0, doc="gas density [kg/m^3]")
    viscosity: float = spec(1.568e-5, gt=0.0, doc="dynamic viscosity [Pa s]")
    inlet_velocity: float = spec(0.0, unit="velocity", ge=0.0,
                                 doc="superficial gas velocity through the bottom (distributor) [m/s]")
    u_over_umf: float | None = spec(None, gt=0.0, optional=True,
                                    doc="inlet velocity as a multiple of gas.umf (sets inlet_velocity = u_over_umf x umf)")
    inlet_ramp: float = spec(0.0, unit="time", ge=0.0,
                             doc="start-up: the inlet velocity rises linearly from 0 to inlet_velocity over this time "
                                 "[s] (0: full velocity from the start). Under a packed bed a full-speed start lifts it "
                                 "as one plug into the roof (issue 17: 16 % of a 32,500-sphere bed pinned there at "
                                 "2.9 Umf); a 1 s ramp kept every particle off the roof there. It does not keep a "
                                 "fluidized bed from throwing particles up later: Mema et al.'s AR-4 beds at 2.9 Umf "
                                 "pinned 3 % of their rods at the 1.05 m outlet after the ramp (docs/validation.md)")
    inlet_steps: tuple = spec((), kind="schedule", unit="velocity", ge=0.0,
                              doc="after the start-up ramp: [time, velocity] pairs, the inlet velocity [m/s] set from "
                                  "the CFD step starting at time [s] on and held until the next pair (times "
                                  "increasing, a CFD step apart at least, none inside gas.inlet_ramp); e.g. a "
                                  "defluidization ramp, velocity held at each value in turn (tools/validate_umf.py)")
    umf: float | None = spec(None, unit="velocity", gt=0.0, optional=True,
                             doc="minimum fluidization velocity [m/s] that u_over_umf refers to (Mema et al. (2020): "
                                 "1.58 m/s AR-1, 1.7 m/s AR-4)")
    walls: str = spec("no-slip", kind="str", choices=("no-slip", "free-slip"), doc="side-wall condition")
    cfd_step: float = spec(5.0e-4, unit="time", gt=0.0,
                           doc="CFD time step [s] = coupling interval (default from the speed-accuracy front; "
                               "Mema et al. (2020): 1e-4)")
    scheme: str = spec("piso", kind="str", choices=("piso", "simple"), doc="pressure-velocity coupling")
    correctors: int = spec(2, kind="int", ge=1, le=100, doc="PISO pressure corrections per step")
    linear_solver: str = spec("iterative", kind="str", choices=("iterative", "direct"))
    linear_tolerance: float = spec(1.0e-8, gt=0.0, lt=1.0,
                                   doc="relative tolerance of the linear solves; the last PISO corrector's pressure "
                                       "solve stops once continuity holds to it of the largest face flux (or of its "
                                       "own imbalance, if that is larger)")
    corrector_tolerance: float = spec(1.0e-8, gt=0.0, lt=1.0,
                                      doc="relative tolerance of the pressure solves of every PISO corrector but the "
                                          "last (OpenFOAM's p relTol against pFinal; at most linear_tolerance's "
                                          "accuracy is used). Since the last corrector stops at continuity to "
                                          "linear_tolerance of the flow, a loose first solve no longer saves CG "
                                          "iterations (1e-3: 140 against 131 in 10 steps of a fluidized AR-4 bed) and "
                                          "moves the flow by 6 % of PISO's own splitting error: the default solves "
                                          "every corrector to linear_tolerance (docs/benchmarks.md)")
    pressure_preconditioner: str = spec("multigrid", kind="str", choices=("multigrid", "factorization"),
                                        doc="preconditioner of the pressure correction's CG (iterative solves): "
                                            "'multigrid' (aggregation multigrid built from each step's matrix; walled "
                                            "columns) or 'factorization' (the LU of a recent matrix, renewed as the bed "
                                            "moves; always used in periodic boxes)")
    simple_tolerance: float = spec(1.0e-8, gt=0.0, lt=1.0,
                                   doc="SIMPLE: iterate each step until the continuity residual and the relative "
                                       "velocity change are below this")
    body_force: tuple = spec((0.0, 0.0, 0.0), kind="vec3", doc="body force on the gas [N/m^3] (drives a periodic box)")
    mean_pressure_gradient: tuple = spec((0.0, 0.0, 0.0), kind="vec3",
                                         doc="imposed -<grad p> [Pa/m] of a periodic box, acting on both phases: "
                                             "eps G per volume on the fluid, V_p G on each particle (e.g. G = "
                                             "mixture density x |g| upwards holds up a suspension)")
    porous_zone: PorousZoneConfig = section(PorousZoneConfig)


@dataclass(frozen=True)
class CouplingConfig:
    enabled: bool = spec(True, kind="bool", doc="exchange momentum between gas and particles (when both are present)")
    drag: str = spec("hoelzer-sommerfeld", kind="str", registry="drag",
                     doc="drag closure. Gas-fluidized coarse beds: the paper's laws to reproduce Mema et al. (2020), 'gidaspow' "
                         "for Umf (simulated in the paper's bed: spheres 1.59-1.75 m/s against the measured 1.58, "
                         "the closure's Umf at the packing the bed collapses to, 0.577-0.537; AR-4 rods 1.61 "
                         "against 1.7; the particle-resolved laws 35-113 % above for spheres); liquid suspensions: "
                         "'tenneti' or 'beetstra' (simulated: 34-45 % slower settling than the default at solids "
                         "0.2-0.4) (docs/coupling.md, tools/closure_atlas.py)")
    lift: str = spec("none", kind="str", registry="lift", doc="lift closure (spherocylinders only)")
    torque: str = spec("none", kind="str", registry="torque", doc="hydrodynamic torque closure (spherocylinders only)")
    pressure_gradient_force: bool = spec(True, kind="bool", doc="apply -V_p grad p to the particles")
    voidage: str = spec("divided", kind="str", registry="voidage", doc="voidage mapping")
    satellites: int = spec(5, kind="int", ge=1, le=1000, doc="satellite points along a spherocylinder's axis")
    minimum_voidage: float = spec(0.2, gt=0.0, lt=1.0, doc="voidage floor; cells below it are reported as over-packed")
    drag_treatment: str = spec("semi-implicit", kind="str", choices=("semi-implicit", "explicit"),
                               doc="'semi-implicit': implicit in the gas (through beta) and in each DEM kick, "
                                   "stable for any step; 'explicit': the drag force at the coupling time held "
                                   "over the CFD step (unstable beyond 2 particle response times)")
    two_way: bool = spec(True, kind="bool", doc="feed the particle forces back into the gas (false: one-way coupling)")
    rotational_drag: str = spec("none", kind="str", choices=("none", "stokes"),
                                doc="viscous resistance to particle rotation: 'stokes' applies pi mu d_e^3 omega "
                                    "(the volume-equivalent sphere's), integrated exactly over the CFD step; "
                                    "negligible in a gas, it sets the orientations of rods in a liquid")
    stochastic_force: str = spec("none", kind="str", registry="stochastic_force",
                                 doc="drag fluctuation each particle feels from its neighbours, unresolved by the "
                                     "grid: a per-particle Ornstein-Uhlenbeck force along and across the slip whose "
                                     "reaction goes to the gas (fvdem/coupling/stochastic.py; docs/validation-suspension.md, "
                                     "\"Velocity fluctuations with a stochastic drag force\")")
    stochastic_seed: int = spec(1, kind="int", ge=0, le=2**63 - 1,
                                doc="seed of the stochastic force's random stream (numpy PCG64; its state is kept "
                                    "in checkpoints)")
    stochastic_scale: float = spec(1.0, gt=0.0, le=10.0,
                                   doc="factor on the stochastic force's standard deviations: 1 is the model as "
                                       "published; any other value is a calibration")
    stochastic_along_scale: float = spec(1.0, ge=0.0, le=10.0,
                                         doc="factor on the stochastic force's standard deviation along the slip "
                                             "alone (on top of stochastic_scale): the share of the along-slip "
                                             "fluctuation the grid does not resolve; 1 is the model as published, "
                                             "any other value a calibration")
    stochastic_zero_mean: str = spec("box", kind="str", choices=("box", "cell"),
                                     doc="over which particles the stochastic force's mean is removed each CFD step: "
                                         "'box' all of them (the model as published), 'cell' those whose centres "
                                         "share a grid cell (variance kept), so that the sub-grid fluctuation adds "
                                         "no force to a cell as a whole")


@dataclass(frozen=True)
class SuspensionConfig:
    enabled: bool = spec(False, kind="bool",
                         doc="set the case up from Derksen's dimensionless scene: a fully periodic box of "
                             "liquid and identical particles held up by a mean pressure gradient (derives "
                             "domain, particles, liquid, gradient, contact stiffness and steps)")
    particle: str = spec("cylinder", kind="str", choices=("cylinder", "sphere"),
                         doc="'cylinder': Derksen's flat-ended cylinder of aspect ratio l/d, modelled as the "
                             "spherocylinder of equal diameter and volume (length l + d/3); 'sphere': diameter d")
    aspect_ratio: float = spec(2.0, gt=2.0 / 3.0, le=10.0, doc="cylinder length over diameter l/d")
    density_ratio: float = spec(2.0, gt=1.0, doc="particle over liquid density gamma")
    galileo: float | None = spec(None, gt=0.0, optional=True, doc="Ga = g d^3 / nu^2 on the diameter d")
    galileo_equivalent: float | None = spec(None, gt=0.0, optional=True,
                                            doc="Ga_e = g d_e^3 / nu^2 on the volume-equivalent diameter "
                                                "d_e = (3 l d^2 / 2)^(1/3)")
    solids_fraction: float = spec(0.2, gt=0.0, le=0.55, doc="mean solids volume fraction <phi>")
    box: tuple = spec((9.0, 9.0, 18.0), kind="vec3", gt=0.0, doc="box size in diameters d (Derksen: 9 x 9 x 18)")
    cells: tuple = spec((3, 3, 6), kind="int3", ge=1, le=10000, doc="liquid grid cells along x, y, z")
    diameter: float = spec(1.0e-3, unit="length", gt=0.0, doc="particle diameter d [m]: sets the dimensional scale")
    liquid_density: float = spec(1000.0, unit="density", gt=0.0, doc="liquid density rho [kg/m^3]")
    duration: float = spec(20.0, gt=0.0, doc="simulated time in viscous times d^2 / nu")
    overlap: float = spec(0.02, gt=0.0, lt=0.2,
                          doc="contact stiffness: largest overlap / d of a head-on collision at the "
                              "gravitational velocity sqrt((gamma - 1) g d_e)")


@dataclass(frozen=True)
class RunConfig:
    threads: int = spec(0, kind="int", ge=0, le=4096, doc="numba threads (0: all cores)")
    dem_backend: str = spec("cpu", kind="str", registry="dem_backend",
                            doc="the DEM's implementation (docs/ARCHITECTURE.md, \"Add a DEM backend\")")


@dataclass(frozen=True)
class Case:
    name: str = spec("case", kind="str", doc="case name (default output folder runs/<name>)")
    description: str = spec("", kind="str")
    domain: DomainConfig = section(DomainConfig)
    particles: ParticlesConfig = section(ParticlesConfig)
    contact: ContactConfig = section(ContactConfig)
    time: TimeConfig = section(TimeConfig)
    output: OutputConfig = section(OutputConfig)
    gas: GasConfig = section(GasConfig)
    coupling: CouplingConfig = section(CouplingConfig)
    suspension: SuspensionConfig = section(SuspensionConfig)
    run: RunConfig = section(RunConfig)
    source: str | None = field(default=None, compare=False, metadata=dict(kind="internal"))

    def resolve_path(self, relative: str) -> Path:
        """A path from the case file, relative to the case file's folder."""
        path = Path(relative)
        if path.is_absolute() or self.source is None:
            return path
        return Path(self.source).parent / path

    def neighbour_skin(self) -> float:
        """The fixed skin, or the adaptive skin's floor (its start) [m]."""
        return self.contact.neighbour_skin or 0.1 * self.particles.diameter

    def collision_time(self) -> float:
        """Binary collision time [s] of two particles (reduced mass m/2)."""
        return collision_time(self.contact.normal_stiffness, 0.5 * self.particles.mass, self.contact.restitution)


def _describe_rule(meta, live: bool = True) -> str:
    """The allowed values in words; ``live=False`` names a registry-backed key's registry instead of
    today's names (for the committed docs/case-reference.md, which a new law must not make stale)."""
    parts = []
    if meta.get("registry") and not live:
        names, _, module = REGISTRIES[meta["registry"]]
        return f"a name registered in `{module}` (`fvdem laws {meta['registry']}` lists them)"
    if _choices(meta):
        return "one of " + ", ".join(repr(c) for c in _choices(meta))
    kinds = {"float": "a number", "int": "an integer", "bool": "true or false", "str": "a string",
             "vec3": "a list of 3 numbers", "bool3": "a list of 3 booleans", "int3": "a list of 3 integers",
             "schedule": "a list of [time, value] pairs, times >= 0 increasing (in " + ", ".join(UNITS["time"])
                         + "), values"}
    parts.append(kinds[meta["kind"]])
    for key, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
        if meta.get(key) is not None:
            parts.append(f"{sym} {meta[key]:g}")
    if meta.get("unit"):
        parts.append(f"in {', '.join(UNITS[meta['unit']])} (plain numbers are SI)")
    return " ".join(parts)
