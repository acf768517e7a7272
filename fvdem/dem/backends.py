"""DEM backends, registered by name (the case key ``run.dem_backend``), and the interface the rest of fvdem
uses of one. Today there is one backend, ``cpu``: ``DEMSystem``, numba kernels on the host's cores.

The interface (``DEMBackend``) is what the model, the coupling bridge, the scenes and the run monitors
touch of a DEM, and nothing else:

- ``particles``: the host view of the particle arrays (``ParticleArrays``), read-only outside the DEM:
  positions, velocities, orientations and colours the observables and writers read, and the coupling inputs
  the DEM holds (those of the last coupled step). A backend that keeps its arrays elsewhere (a GPU) copies
  them here when asked.
- ``coupled_step(steps, inputs)``: ``steps`` steps with the coupling inputs (``CouplingInputs``: arrays the
  caller owns, in the host view's order at the call, copied in) held over them; returns the drag impulse
  the kicks applied (N, 3), in that same order. A backend that re-sorts its particles (the CPU one does, by
  cell) keeps that to itself.
- ``step(steps)``, ``step_count``, ``time``, ``dt``, ``gravity``, ``box``.
- ``diagnostics()`` (scalars: kinetic energy, largest overlap, contacts, speeds), ``rebuild_count``,
  ``check_health()`` (``SimulationError`` with the cause), ``timings`` (``fvdem.timing.Timings``, shared
  with the run: phases ``neighbour_list``, ``contact_forces``, ``integration``).
- ``state()`` / ``restore(data)``: every array needed to continue bit-for-bit (checkpoints).

Add one: docs/ARCHITECTURE.md, "How to add a DEM backend".
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Protocol, runtime_checkable

import numpy as np


@dataclass
class CouplingInputs:
    """What the gas hands the particles for one coupled step, per particle in the order of the DEM's host
    view at the call. The caller (the coupling bridge) owns the arrays; the DEM copies them in.

    - ``drag_coefficient`` (N,) [kg/s], or ``None``: the kicks integrate the drag ``c (u - v)`` implicitly
      (backward Euler, stable for any step) and return its impulse; ``None``: no drag in the kicks (an
      explicit drag is then part of ``external_force``).
    - ``fluid_velocity`` (N, 3) [m/s]: ``u`` of the drag.
    - ``external_force`` (N, 3) [N], ``external_torque`` (N, 3) [N m]: held over the steps (pressure
      gradient, lift, explicit drag; hydrodynamic torque).
    """

    drag_coefficient: np.ndarray | None
    fluid_velocity: np.ndarray
    external_force: np.ndarray
    external_torque: np.ndarray

    @classmethod
    def zeros(cls, count: int) -> "CouplingInputs":
        """Buffers for ``count`` particles, all zero (an implicit drag of coefficient 0)."""
        return cls(np.zeros(count), np.zeros((count, 3)), np.zeros((count, 3)), np.zeros((count, 3)))


@runtime_checkable
class DEMBackend(Protocol):
    """What fvdem uses of a DEM (see the module docstring): ``isinstance(system, DEMBackend)`` holds when every
    member is there, and ``build_backend`` refuses a backend that lacks one (``missing_members``)."""

    particles: object  # ParticleArrays, the host view
    dt: float  # the DEM step [s]
    gravity: np.ndarray  # (3,) [m/s^2]
    box: object  # system.Box: lower, upper, periodic
    timings: object  # fvdem.timing.Timings, the run's (set by the model)
    step_count: int
    rebuild_count: int

    @property
    def time(self) -> float: ...
    def step(self, steps: int = 1) -> None: ...
    def coupled_step(self, steps: int, inputs: CouplingInputs) -> np.ndarray: ...
    def diagnostics(self) -> dict: ...
    def check_health(self) -> None: ...
    def state(self) -> dict: ...
    def restore(self, data) -> None: ...


# the protocol's members, read off the class (its annotated attributes, then its methods and properties)
MEMBERS = tuple(dict.fromkeys([*DEMBackend.__annotations__, *(
    name for name, value in vars(DEMBackend).items()
    if not name.startswith("_") and (callable(value) or isinstance(value, property)))]))


def missing_members(system) -> list:
    """The members of ``DEMBackend`` that ``system`` lacks (empty: it meets the interface)."""
    return [name for name in MEMBERS if not hasattr(system, name)]


# name -> (factory(particles, box, contact, dt, gravity, skin) -> DEMBackend, one line on what it is)
BACKENDS: dict[str, tuple[Callable, str]] = {}


def register_backend(name: str, factory: Callable, description: str) -> None:
    """Make a backend available to ``run.dem_backend``."""
    BACKENDS[name] = (factory, description)


def backend_names() -> list:
    return sorted(BACKENDS)


def describe_backends() -> str:
    return "; ".join(f"`{name}`: {BACKENDS[name][1]}" for name in backend_names())


def build_backend(name: str, particles, box, contact, dt, gravity, skin) -> DEMBackend:
    """The DEM of backend ``name`` (a name ``run.dem_backend`` was checked against)."""
    factory, _ = BACKENDS[name]
    system = factory(particles, box, contact, dt, gravity, skin)
    missing = missing_members(system)
    if missing:
        raise TypeError(f"DEM backend {name!r} ({type(system).__name__}) lacks {', '.join(missing)} of the "
                        "interface fvdem uses (fvdem.dem.backends.DEMBackend)")
    return system


def _cpu(particles, box, contact, dt, gravity, skin):
    from .system import DEMSystem
    return DEMSystem(particles, box, contact, dt, gravity, skin)


register_backend("cpu", _cpu, "numba kernels on the host's cores (DEMSystem; struct-of-arrays, race-free blocks)")

__all__ = ["CouplingInputs", "DEMBackend", "MEMBERS", "missing_members", "BACKENDS", "register_backend", "backend_names", "describe_backends",
           "build_backend"]
