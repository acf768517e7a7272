"""The DEM system: owns the particle arrays, neighbour list and contact histories, and advances
them with the numba kernels. One step (velocity Verlet):

1. ``kick_drift``: half kick with the forces of the previous step, drift, orientation update;
2. rebuild the neighbour list (cell sort + history transfer) if some particle moved > skin/2;
   the skin is fixed or adapted at each rebuild (``adapt_skin``);
3. ``contact_forces``: contact forces and torques of every listed pair and wall, both sides of a pair
   added straight onto the particles (race-free by blocks of cell layers);
4. ``kick``: second half kick.

External (e.g. hydrodynamic) forces in ``particles.external_force/torque`` are held over the step;
with ``implicit_drag`` the kicks also integrate ``drag_coefficient (fluid_velocity - velocity)``
implicitly.
"""
from __future__ import annotations

from dataclasses import dataclass
from time import perf_counter

import numba
import numpy as np

from ..errors import SimulationError  # noqa: F401  (re-exported: fvdem.dem.system.SimulationError)
from ..timing import Timings

from .contact_law import DEFAULTS, HISTORY_COLUMNS, K_N, ZETA_N, collision_time, contact_parameters, normal_damping
from .forces import contact_forces
from .integrate import kick, kick_drift
from .neighbours import (build_half_list, carry_history, cell_indices, cell_starts, compact_rows, contact_blocks,
                         permute_wall_history, row_offsets, wrap_periodic)
from .particles import ParticleArrays


# The adaptive skin (``DEMSystem(..., skin=None)``): at each rebuild the skin is scaled by
# sqrt(SKIN_TARGET_INTERVAL / steps since the last rebuild), within SKIN_RANGE smallest diameters.
# Measured on the subset study's fluidized 32,500-particle beds at 2.9 Umf (docs/benchmarks.md, "The
# neighbour list in a moving bed"): a rebuild costs 3-4 DEM steps' contact forces, so the optimum is
# near 8 steps between rebuilds for rods and flat from 7 to 20 for spheres; at the old fixed 0.1 d the
# bed rebuilt every 2 (rods) to 4 (spheres) steps. A settled bed keeps the floor, 0.1 d.
SKIN_TARGET_INTERVAL = 8
SKIN_RANGE = (0.1, 1.0)
# the neighbour search of particles longer than ELONGATED_EXTENT diameters uses half-reach cells, searched
# two either way: (2 x 2 + 1)^3 half-reach cells cover 15.6 reach^3 against 27 for 3^3 reach-wide cells.
# On the settled 32,500-rod bed (13 rods per reach-wide cell; one thread, same process, alternating) a
# rebuild cost 1,940-1,980 ns per rod against 2,100-2,400, the contact forces unchanged (540-566 ns
# against 548-564); spheres (1.4 per cell) gained nothing measurable from smaller cells
ELONGATED_EXTENT = 1.5
# the contact kernel's rows are cut into about this many blocks of cell layers (fewer when the bed has
# fewer layers): even blocks run in parallel, then odd ones, so each phase needs several blocks per
# thread to balance; the cut, and so the summation order, does not depend on the thread count
CONTACT_BLOCKS = 64


def adapted_skin(skin: float, interval: int, lower: float, upper: float) -> float:
    """The next list's skin [m] from the current one and the DEM steps ``interval`` it lasted:
    ``skin * sqrt(SKIN_TARGET_INTERVAL / interval)``, the factor within [1/2, 2], the result within
    ``[lower, upper]``. Displacements grow about linearly with time in a moving bed, so a list's
    lifetime scales with its skin and the interval converges geometrically to the target."""
    factor = min(2.0, max(0.5, (SKIN_TARGET_INTERVAL / max(interval, 1)) ** 0.5))
    return min(upper, max(lower, skin * factor))


@dataclass(frozen=True)
class Box:
    """Axis-aligned domain [m]. Non-periodic axes have planar walls on both faces."""

    lower: tuple
    upper: tuple
    periodic: tuple = (False, False, False)

    @property
    def length(self) -> np.ndarray:
        return np.asarray(self.upper, float) - np.asarray(self.lower, float)

    @property
    def wall_faces(self) -> np.ndarray:
        """Flags for the faces x-, x+, y-, y+, z-, z+."""
        return np.repeat(~np.asarray(self.periodic, bool), 2)


@dataclass(frozen=True)
class ContactModel:
    """Contact law parameters (SI; the case's [contact] keys of the same names, ``docs/case-reference.md``).
    The defaults are the case's, ``contact_law.DEFAULTS``."""

    normal_stiffness: float = DEFAULTS["normal_stiffness"]  # k_n [N/m]
    restitution: float = DEFAULTS["restitution"]
    friction: float = DEFAULTS["friction"]
    rolling_friction: float = DEFAULTS["rolling_friction"]
    tangential_stiffness_ratio: float = DEFAULTS["tangential_stiffness_ratio"]  # k_t / k_n
    tangential_damping_ratio: float = DEFAULTS["tangential_damping_ratio"]  # eta_t / eta_n
    wall_friction: float | None = DEFAULTS["wall_friction"]  # particle-wall sliding friction (None: ``friction``)
    wall_rolling_friction: float | None = DEFAULTS["wall_rolling_friction"]  # (None: ``rolling_friction``)

    def parameters(self, dt: float, mass: float) -> np.ndarray:
        """Kernel parameter vector; the damping is calibrated for particles of ``mass`` [kg] at ``dt``."""
        return contact_parameters(self.normal_stiffness, self.tangential_stiffness_ratio * self.normal_stiffness,
                                  self.restitution, self.tangential_damping_ratio, self.friction,
                                  self.rolling_friction, dt, mass, self.wall_friction, self.wall_rolling_friction)

    def collision_time(self, mass: float) -> float:
        """Binary collision time [s] of two particles of ``mass`` [kg] (reduced mass m/2)."""
        return collision_time(self.normal_stiffness, 0.5 * mass, self.restitution)


class DEMSystem:
    """Particles, walls and contacts advanced in time. Arrays are numpy; see ``ParticleArrays``."""

    def __init__(self, particles: ParticleArrays, box: Box, contact: ContactModel, dt: float,
                 gravity=(0.0, 0.0, -9.81), skin: float | None = None):
        self.particles = particles
        self.box = box
        self.contact = contact
        self.dt = float(dt)
        self.timings = Timings()  # the run's (a Model shares one over DEM, gas and bridge)
        if particles.count:
            tc = contact.collision_time(float(particles.mass.min()))
            if self.dt > 0.5 * tc:
                raise SimulationError(f"DEM time step {self.dt:.3g} s exceeds half the collision time {tc:.3g} s: "
                                      "contacts cannot be resolved (use at most 1/10 of it)")
        self.gravity = np.asarray(gravity, dtype=np.float64)
        diam = 2.0 * float(particles.radius.min()) if particles.count else 0.0
        # skin=None: adapted at each rebuild (module constants), starting from the floor
        self.adaptive_skin = skin is None
        self.skin = float(skin) if skin is not None else SKIN_RANGE[0] * diam
        try:
            self.params = contact.parameters(self.dt, float(np.median(particles.mass)))
        except ValueError as exc:
            raise SimulationError(str(exc)) from None
        self.track_orientation = bool(np.any(particles.half_length > 0.0))
        self.implicit_drag = False  # the kicks integrate particles.drag_coefficient (set by coupled_step's inputs)
        self._uniform = self._pair_constants(particles)
        self.step_count = 0
        self.rebuild_count = 0
        n = particles.count
        self._box_lo = np.asarray(box.lower, np.float64)
        self._box_hi = np.asarray(box.upper, np.float64)
        self._box_len = box.length
        self._periodic = np.asarray(box.periodic, np.bool_)
        self._walls = box.wall_faces
        self._extent = 2.0 * float(np.max(particles.radius + particles.half_length)) if n else 0.0
        reach = self._extent + self.skin
        for d in range(3):
            if self._periodic[d] and self._box_len[d] < 3.0 * reach:
                raise SimulationError(
                    f"periodic axis {'xyz'[d]}: box length {self._box_len[d]:.4g} m must be at least 3 x the "
                    f"neighbour reach {reach:.4g} m (2 x particle half-extent + skin)")
        # the adaptive skin's bounds; a periodic axis must keep 3 cells of the reach
        periodic_room = min((self._box_len[d] / 3.0 - self._extent for d in range(3) if self._periodic[d]),
                            default=np.inf)
        self._skin_bounds = (self.skin, max(self.skin, min(SKIN_RANGE[1] * diam, periodic_room)))
        self._last_rebuild_step = 0
        # elongated particles crowd a reach-wide cell (13 AR-4 rods against 1.4 spheres in the settled
        # beds): half-reach cells, searched two either way, test fewer candidates (docs/benchmarks.md)
        self.cell_span = 2 if n and self._extent > ELONGATED_EXTENT * 2.0 * float(particles.radius.min()) else 1
        self._cell_grid()
        self._cell_of = np.empty(n, np.int64)
        self.displacement = np.zeros(n)
        self.reference_position = particles.position.copy()
        self.reference_axis = particles.axis.copy()
        self.wall_history = np.zeros((n * 12, HISTORY_COLUMNS))
        self.wall_mask = np.zeros(n, np.int64)  # bit face*2+end: that wall slot holds a contact
        self.row_start = np.zeros(n + 1, np.int64)  # CSR half list: row i is neighbours[row_start[i]:row_start[i+1]]
        self.neighbours = np.zeros(0, np.int32)
        self.history = np.zeros((0, HISTORY_COLUMNS))
        self._row_max_overlap = np.zeros(n)
        self._row_contacts = np.zeros(n, np.int64)
        self._row_wall_contacts = np.zeros(n, np.int64)
        self._row_buffer = np.empty((n, 16), np.int32)  # one-pass list rows; widened when a row overflows
        self._scratch = np.empty((numba.config.NUMBA_NUM_THREADS, 0), np.int32)  # the list's candidates
        self.rebuild()
        self.compute_forces()

    def _pair_constants(self, particles) -> np.ndarray:
        """``(eta_n, r_eff, inertia_eff)`` of a pair when all particles are identical (saves three
        divisions and a square root per contact), else ``(-1, -1, -1)``."""
        same = all(np.ptp(a) == 0.0 for a in (particles.mass, particles.radius, particles.inertia[:, 0],
                                               particles.inertia[:, 1])) and particles.count > 0
        if not same:
            return np.full(3, -1.0)
        m, r = float(particles.mass[0]), float(particles.radius[0])
        i_min = float(particles.inertia[0].min())
        eta = normal_damping(self.params[ZETA_N], 0.5 * m, self.params[K_N])
        return np.array([eta, 0.5 * r, 0.5 * i_min])

    # ------------------------------------------------------------------ stepping
    @property
    def time(self) -> float:
        """Simulated time [s] (step count times dt: no accumulated round-off)."""
        return self.step_count * self.dt

    def step(self, steps: int = 1) -> None:
        """Advance ``steps`` DEM time steps. Inside the run of steps, each step's second half kick is
        done in the next step's pass over the particles (``kick_drift(kicks=2)``: bit-identical, one
        memory pass fewer per step); the last step ends with its own, so the state between calls is
        the full step's."""
        integration = neighbours = forces = 0.0
        for k in range(steps):
            p = self.particles
            t0 = perf_counter()
            kick_drift(p.position, p.velocity, p.angular_momentum, p.angular_velocity, p.axis,
                       p.half_length, p.mass, p.inertia, p.contact_force, p.contact_torque, p.external_force,
                       p.external_torque, self.gravity, self.dt, self.reference_position, self.reference_axis,
                       self.displacement, self.track_orientation, p.drag_coefficient, p.fluid_velocity,
                       p.drag_impulse, self.implicit_drag, 1 if k == 0 else 2)
            t1 = perf_counter()
            if self.displacement.max() > 0.5 * self.skin:
                self.rebuild(adapt=True)
                p = self.particles
            t2 = perf_counter()
            self.compute_forces()
            t3 = perf_counter()
            if k == steps - 1:
                kick(p.velocity, p.angular_momentum, p.angular_velocity, p.axis, p.half_length, p.mass, p.inertia,
                     p.contact_force, p.contact_torque, p.external_force, p.external_torque, self.gravity, self.dt,
                     self.track_orientation, p.drag_coefficient, p.fluid_velocity, p.drag_impulse, self.implicit_drag)
            self.step_count += 1
            integration += (t1 - t0) + (perf_counter() - t3)
            neighbours += t2 - t1
            forces += t3 - t2
        self.timings.add("integration", integration)
        self.timings.add("neighbour_list", neighbours)
        self.timings.add("contact_forces", forces)

    def coupled_step(self, steps: int, inputs) -> np.ndarray:
        """``step(steps)`` with the coupling inputs (``backends.CouplingInputs``, in the particles' order at the
        call) copied into the particles' rows and held over the steps; returns the drag impulse [N s] (N, 3)
        the kicks applied over the steps, in that same order. The DEM re-sorts its particles by cell when it
        rebuilds its neighbour list (the inputs move with them); that stays inside it."""
        p = self.particles
        self.implicit_drag = inputs.drag_coefficient is not None
        p.drag_coefficient[:] = inputs.drag_coefficient if self.implicit_drag else 0.0
        p.fluid_velocity[:] = inputs.fluid_velocity
        p.external_force[:] = inputs.external_force
        p.external_torque[:] = inputs.external_torque
        p.drag_impulse[:] = 0.0
        ids_before = p.ids.copy()
        self.step(steps)
        p = self.particles
        return rows_in_order(p.drag_impulse, p.ids, ids_before)

    def compute_forces(self) -> None:
        p = self.particles
        block_start, deferred, deferred_rows = self._blocks
        contact_forces(not self.track_orientation, p.position, p.velocity, p.angular_velocity, p.axis, p.radius,
                       p.half_length, p.mass, p.inertia, self.row_start, self.neighbours, self.history, block_start,
                       deferred, deferred_rows, self._walls, self._box_lo, self._box_hi, self.wall_history,
                       self.wall_mask, self._box_len, self._periodic, self.params, self._uniform, p.contact_force,
                       p.contact_torque, self._row_max_overlap, self._row_contacts, self._row_wall_contacts)

    # ------------------------------------------------------------------ neighbour list

    def _cell_grid(self) -> None:
        """Cells at least ``1 / cell_span`` of a neighbour reach (largest extent + skin) wide, searched
        ``cell_span`` cells either way (a periodic axis is at least 3 reaches long, so it has at least
        ``2 cell_span + 1`` cells and no cell is searched twice)."""
        reach = self._extent + self.skin
        self._n_cells = np.maximum(1, np.floor(self.cell_span * self._box_len / reach).astype(np.int64)) \
            if reach > 0 else np.ones(3, np.int64)
        self._cell_size = self._box_len / self._n_cells

    def rebuild(self, adapt: bool = False) -> None:
        """Sort particles by cell, rebuild the half list, carry contact histories over. With the
        adaptive skin and ``adapt`` (a rebuild the displacements asked for, from ``step``), the new
        list's skin follows from how long the last one lasted; a rebuild asked for from outside keeps it."""
        p = self.particles
        n = p.count
        if adapt and self.adaptive_skin and self.rebuild_count > 0:
            skin = adapted_skin(self.skin, self.step_count - self._last_rebuild_step, *self._skin_bounds)
            if skin != self.skin:
                self.skin = skin
                self._cell_grid()
        self._last_rebuild_step = self.step_count
        wrap_periodic(p.position, self._box_lo, self._box_len, self._periodic)
        cell_indices(p.position, self._box_lo, self._cell_size, self._n_cells, self._cell_of)
        order = np.argsort(self._cell_of, kind="stable")
        if np.any(order != np.arange(n)):
            p.permute(order)
            wall_history = np.zeros_like(self.wall_history)
            permute_wall_history(self.wall_history, self.wall_mask, order, wall_history)
            self.wall_history = wall_history
            self._cell_of = self._cell_of[order]
            self.wall_mask = np.ascontiguousarray(self.wall_mask[order])
        total_cells = int(np.prod(self._n_cells))
        start = cell_starts(self._cell_of, total_cells)
        counts = np.zeros(n, np.int64)
        if self.track_orientation:  # the rods' per-thread scratch: one more column than a rod has candidates
            candidates = (2 * self.cell_span + 1) ** 3 * int(np.diff(start).max(initial=0)) + 1
            if self._scratch.shape[1] < candidates:
                self._scratch = np.empty((numba.config.NUMBA_NUM_THREADS, candidates + candidates // 2), np.int32)
        args = (p.position, p.axis, p.radius, p.half_length, self._box_lo, self._box_len, self._periodic,
                self._cell_size, self._n_cells, self._cell_of, start, self.skin, self.cell_span,
                not self.track_orientation, 0.5 * self._extent)
        if self._row_buffer.shape[0] != n:
            self._row_buffer = np.empty((n, self._row_buffer.shape[1]), np.int32)
        build_half_list(*args, self._row_buffer, counts, self._scratch)
        longest = int(counts.max()) if n else 0
        if longest >= self._row_buffer.shape[1]:  # a row filled or overflowed: widen the buffer (with room), redo
            self._row_buffer = np.empty((n, longest + longest // 2 + 1), np.int32)
            build_half_list(*args, self._row_buffer, counts, self._scratch)
        row_start = row_offsets(counts)
        neighbours = np.empty(row_start[-1], np.int32)
        compact_rows(self._row_buffer, counts, row_start, neighbours)
        history = np.zeros((len(neighbours), HISTORY_COLUMNS))
        old_to_new = np.empty(n, np.int64)
        old_to_new[order] = np.arange(n)
        carry_history(self.row_start, self.neighbours, self.history, row_start, neighbours, history, old_to_new)
        self.row_start, self.neighbours, self.history = row_start, neighbours, history
        self._cut_blocks()
        self.reference_position[:] = p.position
        self.reference_axis[:] = p.axis
        self.rebuild_count += 1

    def _restore_cells(self) -> None:
        """The particles' cells at the last rebuild (restored lists): from the positions the list was
        built at, on the grid of the restored skin, as ``rebuild`` computed them."""
        self._cell_of = np.empty(self.particles.count, np.int64)
        cell_indices(self.reference_position, self._box_lo, self._cell_size, self._n_cells, self._cell_of)

    def _cut_blocks(self) -> None:
        """The contact kernel's race-free blocks of the current list (``neighbours.contact_blocks``)."""
        self._blocks = contact_blocks(self.row_start, self.neighbours, self._cell_of,
                                      int(self._n_cells[0] * self._n_cells[1]), self.cell_span, CONTACT_BLOCKS)

    # ------------------------------------------------------------------ diagnostics
    def diagnostics(self) -> dict:
        """Scalar diagnostics of the current state (all floats, SI)."""
        n = self.particles.count
        pair_contacts = int(self._row_contacts.sum())
        speed2 = np.einsum("ij,ij->i", self.particles.velocity, self.particles.velocity)
        return {
            "time": self.time,
            "kinetic_energy": self.particles.kinetic_energy(),
            "max_overlap_over_diameter": float(self._row_max_overlap.max()) if n else 0.0,
            "contacts_per_particle": 2.0 * pair_contacts / n if n else 0.0,
            "wall_contacts": int(self._row_wall_contacts.sum()),
            "max_speed": float(np.sqrt(speed2.max())) if n else 0.0,
            "rms_speed": float(np.sqrt(speed2.mean())) if n else 0.0,
        }

    def check_health(self) -> None:
        """Raise ``SimulationError`` with the cause if the state is non-finite or particles escaped."""
        p = self.particles
        if not np.all(np.isfinite(p.position)) or not np.all(np.isfinite(p.velocity)):
            bad = np.where(~np.all(np.isfinite(p.position) & np.isfinite(p.velocity), axis=1))[0]
            raise SimulationError(
                f"non-finite position or velocity at t = {self.time:.6g} s for {len(bad)} particle(s) "
                f"(first id {int(p.ids[bad[0]])}); DEM time step {self.dt:.3g} s, collision time "
                f"{self.contact.collision_time(float(p.mass.min())):.3g} s")
        tol = (p.radius + p.half_length)[:, None]
        outside = ((p.position < self._box_lo - tol) | (p.position > self._box_hi + tol)) & ~self._periodic
        if outside.any():
            i = int(np.where(outside.any(axis=1))[0][0])
            raise SimulationError(
                f"particle id {int(p.ids[i])} left the domain through a wall at t = {self.time:.6g} s "
                f"(position {p.position[i].round(5).tolist()} m): overlaps grew past the particle size; "
                f"reduce the time step or raise the stiffness")

    # ------------------------------------------------------------------ checkpoint state
    def state(self) -> dict:
        """Everything needed to continue bit-for-bit (arrays and counters)."""
        data = {f"particles.{k}": v for k, v in self.particles.as_dict().items()}
        data.update({
            "dem.wall_history": self.wall_history, "dem.wall_mask": self.wall_mask,
            "dem.row_start": self.row_start, "dem.neighbours": self.neighbours,
            "dem.history": self.history, "dem.reference_position": self.reference_position,
            "dem.reference_axis": self.reference_axis,
            "dem.counters": np.array([self.step_count, self.rebuild_count, self._last_rebuild_step], np.int64),
            "dem.skin": np.array([self.skin]),
        })
        return data

    def restore(self, data) -> None:
        """Load a ``state()`` dictionary (e.g. from an ``.npz`` checkpoint)."""
        self.particles = ParticleArrays.from_dict({k.split(".", 1)[1]: data[k] for k in data
                                                   if k.startswith("particles.")})
        self.wall_history = np.array(data["dem.wall_history"], order="C", copy=True)
        self.wall_mask = np.array(data["dem.wall_mask"], order="C", copy=True)
        self.neighbours = np.array(data["dem.neighbours"], order="C", copy=True)
        self.row_start = np.array(data["dem.row_start"], order="C", copy=True)
        self.history = np.array(data["dem.history"], order="C", copy=True)
        self.reference_position = np.array(data["dem.reference_position"], order="C", copy=True)
        self.reference_axis = np.array(data["dem.reference_axis"], order="C", copy=True)
        counters = [int(x) for x in data["dem.counters"]]
        self.step_count, self.rebuild_count = counters[:2]
        # checkpoints before the adaptive skin: the list was built with the fixed skin of then
        self._last_rebuild_step = counters[2] if len(counters) > 2 else self.step_count
        if "dem.skin" in data:
            self.skin = float(data["dem.skin"][0])
            self._cell_grid()
        self._restore_cells()
        self._cut_blocks()
        self.compute_forces_diagnostics_only()

    def compute_forces_diagnostics_only(self) -> None:
        """Refresh per-row diagnostics after a restore without touching forces or histories."""
        saved = (self.particles.contact_force.copy(), self.particles.contact_torque.copy(),
                 self.history.copy(), self.wall_history.copy(), self.wall_mask.copy())
        self.compute_forces()
        self.particles.contact_force[:], self.particles.contact_torque[:] = saved[0], saved[1]
        self.history[:], self.wall_history[:], self.wall_mask[:] = saved[2], saved[3], saved[4]


def rows_in_order(values, ids_now, ids_before):
    """Rows of ``values`` (in the order of ``ids_now``) rearranged into the order of ``ids_before``."""
    if np.array_equal(ids_now, ids_before):
        return values
    row_of = np.empty(int(max(ids_now.max(), ids_before.max())) + 1, np.int64)
    row_of[ids_now] = np.arange(len(ids_now))
    return values[row_of[ids_before]]
