"""Case files: TOML -> validated, frozen dataclasses.

A case file has one table per part of the model (``[domain]``, ``[particles]``,
``[particles.insertion]``, ``[contact]``, ``[time]``, ``[output]``, ``[run]``). Every value is
checked before anything runs: unknown keys, wrong types, units and ranges are all collected and
reported together as ``CaseError`` with the key path, the value and what is allowed.

Quantities with a dimension are SI numbers, or strings with a unit: ``diameter = "5.3 mm"``.
The fully resolved case (defaults included) can be written back as TOML (``to_toml``).
"""
from __future__ import annotations

import copy
import difflib
import math
import re
import tomllib
from dataclasses import MISSING, dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from .coupling.closures import describe_laws, law, law_names
from .coupling.voidage import describe_voidage, voidage_names
from .dem.backends import backend_names, describe_backends
from .dem.contact_law import collision_time
from .errors import CaseError  # noqa: F401  (re-exported: fvdem.case.CaseError)
from .dem.particles import spherocylinder_volume, volume_equivalent_diameter

# --------------------------------------------------------------------------- units
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
    "dem_backend": (backend_names, describe_backends, "fvdem.dem.backends"),
}


def _choices(meta):
    if meta.get("registry"):
        return REGISTRIES[meta["registry"]][0]()
    return meta.get("choices")


# --------------------------------------------------------------------------- schema
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
class ContactConfig:
    normal_stiffness: float = spec(800.0, unit="stiffness", gt=0.0,
                                   doc="linear normal spring k_n [N/m] (default from the speed-accuracy front, "
                                       "docs/speed-accuracy.md; Mema et al. (2020): 2e4 with dem_step 1e-5)")
    restitution: float = spec(0.43, gt=0.0, le=1.0, doc="coefficient of restitution e in (0, 1]")
    friction: float = spec(0.46, ge=0.0, doc="sliding friction coefficient mu")
    rolling_friction: float = spec(0.46, ge=0.0, doc="rolling friction coefficient mu_r (CDT model)")
    tangential_stiffness_ratio: float = spec(2.0 / 7.0, gt=0.0, doc="k_t / k_n")
    tangential_damping_ratio: float = spec(1.0, ge=0.0, doc="eta_t / eta_n")
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
                                 "2.9 Umf); a 1 s ramp kept every particle off the roof")
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


# --------------------------------------------------------------------------- parsing
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
             "vec3": "a list of 3 numbers", "bool3": "a list of 3 booleans", "int3": "a list of 3 integers"}
    parts.append(kinds[meta["kind"]])
    for key, sym in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
        if meta.get(key) is not None:
            parts.append(f"{sym} {meta[key]:g}")
    if meta.get("unit"):
        parts.append(f"in {', '.join(UNITS[meta['unit']])} (plain numbers are SI)")
    return " ".join(parts)


# every number of a case lies within these magnitudes (or is 0): values such as 1e-320 or 1e308 overflow
# or divide by zero in the derived checks (collision time, step ratios, volumes) instead of being refused
MIN_MAGNITUDE, MAX_MAGNITUDE = 1e-30, 1e30


def _number(value, meta, path, problems):
    """A float in SI from a number or a 'value unit' string; None (and a problem) if invalid."""
    unit = meta.get("unit")
    if isinstance(value, bool):
        problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
        return None
    if isinstance(value, (int, float)):
        number = float(value)
    elif isinstance(value, str) and unit is not None:
        text = value.strip().split(None, 1)
        try:
            magnitude = float(text[0])
        except (ValueError, IndexError):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        symbol = text[1].strip() if len(text) > 1 else ""
        if symbol not in UNITS[unit]:
            problems.append(f"{path} = {value!r}: unit {symbol!r} is not a {unit} unit; allowed: "
                            + ", ".join(UNITS[unit]))
            return None
        number = magnitude * UNITS[unit][symbol]
    else:
        problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
        return None
    if not math.isfinite(number):
        problems.append(f"{path} = {value!r}: must be finite")
        return None
    if number != 0.0 and not MIN_MAGNITUDE <= abs(number) <= MAX_MAGNITUDE:
        problems.append(f"{path} = {value!r}: magnitude outside {MIN_MAGNITUDE:g} to {MAX_MAGNITUDE:g} (SI), beyond "
                        "any physical value of it and the range fvdem's arithmetic is checked for")
        return None
    return number


def _check_range(number, meta, path, raw, problems):
    for key, ok in (("gt", lambda a, b: a > b), ("ge", lambda a, b: a >= b), ("lt", lambda a, b: a < b),
                    ("le", lambda a, b: a <= b)):
        bound = meta.get(key)
        if bound is not None and not ok(number, bound):
            problems.append(f"{path} = {raw!r}: out of range; allowed: {_describe_rule(meta)}")
            return


def _convert(value, meta, path, problems):
    kind = meta["kind"]
    if value is None:
        return None
    if kind == "float":
        number = _number(value, meta, path, problems)
        if number is not None:
            _check_range(number, meta, path, value, problems)
        return number
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        _check_range(value, meta, path, value, problems)
        return value
    if kind == "bool":
        if not isinstance(value, bool):
            problems.append(f"{path} = {value!r}: expected true or false")
            return None
        return value
    if kind == "str":
        if not isinstance(value, str):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        if _choices(meta) and value not in _choices(meta):
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        return value
    if kind in ("vec3", "bool3", "int3"):
        if not isinstance(value, (list, tuple)) or len(value) != 3:
            problems.append(f"{path} = {value!r}: expected {_describe_rule(meta)}")
            return None
        item_meta = dict(meta, kind={"vec3": "float", "bool3": "bool", "int3": "int"}[kind])
        items = [_convert(v, item_meta, f"{path}[{k}]", problems) for k, v in enumerate(value)]
        return None if any(v is None for v in items) else tuple(items)
    raise AssertionError(kind)


def _key_path(path: str, key) -> str:
    """``path.key``, or ``path['key']`` for a key that is not a plain name (empty, spaces, digits first)."""
    if isinstance(key, str) and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_-]*", key):
        return f"{path}.{key}" if path else key
    return f"{path}[{key!r}]"


def _build(cls, table, path, problems):
    if not isinstance(table, dict):
        problems.append(f"{path or 'case'} = {table!r}: expected a table")
        return cls()
    known = {f.name: f for f in fields(cls) if f.metadata.get("kind") != "internal"}
    for key in table:
        if key not in known:
            where = _key_path(path, key)
            close = difflib.get_close_matches(key, known, n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            problems.append(f"{where}: unknown key{hint}; allowed keys here: {', '.join(known)}")
    values = {}
    for name, f in known.items():
        where = f"{path}.{name}" if path else name
        meta = f.metadata
        if meta["kind"] == "section":
            sub_cls = f.default_factory
            values[name] = _build(sub_cls, table.get(name, {}), where, problems)
            continue
        if name not in table:
            continue
        converted = _convert(table[name], meta, where, problems)
        if converted is not None:
            values[name] = converted
    return cls(**values)


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
    if case.particles.count > 0:
        ratio = g.cfd_step / case.time.dem_step
        if abs(ratio - round(ratio)) > 1e-9 * ratio or round(ratio) < 1:
            problems.append(f"gas.cfd_step = {g.cfd_step:g}: must be a whole multiple of time.dem_step = "
                            f"{case.time.dem_step:g}")
    # the gas solver's explicit parts (the old-flux Rhie-Chow correction, the exact-exchange return)
    # diverge from an inlet Courant number of about 1.3 with PISO (tools/stability_map.py, cfd map): refuse
    # > 1; SIMPLE iterates each step to convergence and takes large (steady-state) steps
    spacing = min((hi - lo) / n for lo, hi, n in zip(case.domain.lower, case.domain.upper, g.cells))
    courant = g.inlet_velocity * g.cfd_step / spacing
    if g.scheme == "piso" and courant > MAX_INLET_COURANT:
        problems.append(f"gas.cfd_step = {g.cfd_step:g}: the inlet Courant number U dt / dx = {courant:.3g} "
                        f"(U {g.inlet_velocity:g} m/s, cell {spacing:.3g} m) exceeds {MAX_INLET_COURANT:g}; the gas "
                        f"PISO solver diverges from about 1.3 (docs/speed-accuracy.md); use cfd_step <= "
                        f"{MAX_INLET_COURANT * spacing / g.inlet_velocity:.3g} s")
    zone = g.porous_zone
    if zone.enabled and (zone.lower is None or zone.upper is None):
        problems.append("gas.porous_zone: lower and upper corners are required when enabled")
    if zone.enabled and case.particles.count > 0 and case.coupling.enabled:
        problems.append("gas.porous_zone: a case with coupled particles models its bed with the particles; "
                        "disable the porous zone or set coupling.enabled = false")
    if case.particles.count > 0 and case.coupling.enabled:
        _coupling_checks(case, problems)


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


def _cross_checks(case: Case, problems: list) -> None:
    lower, upper = case.domain.lower, case.domain.upper
    if any(u <= lo for lo, u in zip(lower, upper)):
        problems.append(f"domain.upper = {list(upper)}: must exceed domain.lower = {list(lower)} on every axis")
        return
    _gas_checks(case, problems)
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


def _set_path(table: dict, dotted: str, value: Any) -> None:
    keys = dotted.split(".")
    node = table
    for key in keys[:-1]:
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            raise CaseError([f"--set {dotted!r}: '{key}' is not a table"])
    node[keys[-1]] = value


def parse_override(text: str):
    """``'a.b=value'`` -> ``('a.b', value)`` with value parsed as TOML (bare words as strings)."""
    if "=" not in text:
        raise CaseError([f"--set {text!r}: expected KEY=VALUE, e.g. time.end=0.5"])
    key, raw = text.split("=", 1)
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key.strip(), value


def case_from_dict(table: dict, source: str | None = None, overrides: dict | None = None) -> Case:
    """Validate a case table (as read from TOML). ``overrides`` maps dotted keys to values
    (``{"time.end": 0.5}``) and is applied, to a copy, before validation. Raises ``CaseError``."""
    if overrides:
        table = copy.deepcopy(table)
        for key, value in overrides.items():
            _set_path(table, key, value)
    problems: list[str] = []
    case = _build(Case, table, "", problems)
    if not problems and case.gas.u_over_umf is not None:
        g = case.gas
        if g.umf is None:
            problems.append(f"gas.u_over_umf = {g.u_over_umf:g}: needs gas.umf (the minimum fluidization velocity, m/s)")
        elif "inlet_velocity" in table.get("gas", {}) and abs(g.inlet_velocity - g.u_over_umf * g.umf) > 1e-12:
            problems.append(f"gas.inlet_velocity = {g.inlet_velocity:g} and gas.u_over_umf = {g.u_over_umf:g}: "
                            "give one of them")
        else:
            case = replace(case, gas=replace(g, inlet_velocity=g.u_over_umf * g.umf))
    if not problems and case.suspension.enabled:
        from .scenes import expand_suspension
        table = expand_suspension(case, table, problems)
        if not problems:
            case = _build(Case, table, "", problems)
    if not problems:
        _cross_checks(case, problems)
    if problems:
        raise CaseError(problems)
    return replace(case, source=source)


def load_case(path, overrides: dict | None = None) -> Case:
    """Read and validate a TOML case file. ``overrides`` maps dotted keys to values
    (``{"time.end": 0.5}``) and is applied before validation. Raises ``CaseError``."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            table = tomllib.load(fh)
    except FileNotFoundError:
        raise CaseError([f"{path}: no such case file"]) from None
    except IsADirectoryError:
        raise CaseError([f"{path}: is a directory, not a case file"]) from None
    except PermissionError:
        raise CaseError([f"{path}: not readable (permission denied)"]) from None
    except UnicodeDecodeError as exc:
        raise CaseError([f"{path}: not a text file (not UTF-8 at byte {exc.start}); a case file is TOML text"]) from None
    except tomllib.TOMLDecodeError as exc:
        raise CaseError([f"{path}: not valid TOML: {exc}"]) from None
    except OSError as exc:
        raise CaseError([f"{path}: cannot be read ({exc.strerror or exc})"]) from None
    if not table:
        raise CaseError([f"{path}: empty case file (no tables or keys); see `fvdem schema` or cases/ for examples"])
    return case_from_dict(table, source=str(path), overrides=overrides)


# --------------------------------------------------------------------------- writing
_SCALAR_ARRAY = re.compile(r"\[\n((?:    [^\n\"'\[\]]*,\n)+)\]")


def _dumps(table: dict) -> str:
    """TOML by tomli-w, with arrays of numbers and booleans on one line (``upper = [0.15, 0.15, 1.05]``)."""
    import tomli_w
    return _SCALAR_ARRAY.sub(lambda m: "[" + ", ".join(item.strip().rstrip(",") for item in m.group(1).splitlines())
                             + "]", tomli_w.dumps(table))


def _toml_value(value) -> str:
    """One value as TOML (the reference tables' defaults)."""
    return _dumps({"v": list(value) if isinstance(value, tuple) else value})[4:].strip()


def case_as_dict(case) -> dict:
    """The case as nested tables of plain values (unset optional values left out), the form TOML takes."""
    table = {}
    for f in fields(case):
        kind = f.metadata.get("kind")
        value = getattr(case, f.name)
        if kind == "internal" or value is None:
            continue
        table[f.name] = case_as_dict(value) if kind == "section" else list(value) if isinstance(value, tuple) else value
    return table


def to_toml(case: Case, header: str | None = None) -> str:
    """The fully resolved case as TOML (unset optional values are omitted), written by tomli-w so that
    any string (newlines, quotes, backslashes, Unicode) reads back as it was; ``header``: a comment line
    (e.g. what made the run) after the first."""
    lines = ["# fully resolved case written by fvdem (defaults included, SI units)"]
    if header:
        lines += [f"# {part}" for part in header.splitlines()]
    return "\n".join(lines) + "\n" + _dumps(case_as_dict(case))


def schema_reference(live: bool = True) -> str:
    """Markdown reference of every case key, generated from the dataclasses. ``live``: registry-backed
    keys list today's registered names and what each is; otherwise they name their registry (the form
    of the committed docs/case-reference.md)."""
    out = []

    def walk(cls, prefix):
        rows = []
        for f in fields(cls):
            meta = f.metadata
            if meta.get("kind") == "internal":
                continue
            if meta.get("kind") == "section":
                walk(f.default_factory, f"{prefix}{f.name}.")
                continue
            default = f.default if f.default is not MISSING else f.default_factory()
            doc = meta.get("doc", "")
            if meta.get("registry") and live:
                doc += ": " + REGISTRIES[meta["registry"]][1]()
            rows.append(f"| `{prefix}{f.name}` | {_toml_value(default) if default is not None else '(auto)'} | "
                        f"{_describe_rule(meta, live)} | {doc} |")
        if rows:
            out.append(f"\n### `[{prefix.rstrip('.') or 'top level'}]`\n")
            out.append("| key | default | allowed | meaning |\n|---|---|---|---|")
            out.extend(rows)

    walk(Case, "")
    return "\n".join(out) + "\n"


def docs_reference() -> str:
    """docs/case-reference.md: the case-key reference with registry-backed keys naming their registry
    (tests/test_case.py checks that the committed file is this)."""
    return ("# Case-file reference\n\nGenerated by `fvdem schema --docs` from `fvdem/case.py`; do not edit. "
            "`fvdem schema` prints the same tables with today's registered drag, lift, torque and voidage "
            "names, and `fvdem laws` lists each with its validity and reference.\n" + schema_reference(live=False))


__all__ = ["Case", "CaseError", "load_case", "case_from_dict", "to_toml", "parse_override", "schema_reference", "docs_reference"]
