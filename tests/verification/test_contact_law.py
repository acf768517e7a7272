"""Contact law against analytical binary-collision results."""
import math

import numpy as np
import pytest

from fvdem.dem.contact_law import ZETA_N, collision_time, damping_ratio
from fvdem.dem.system import Box, ContactModel

from conftest import DENSITY, SPHERE_D, by_id, make_system, paper_contact

R = SPHERE_D / 2
WALLED = Box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), (False, False, False))


def run_until_separated(system, max_steps=100_000):
    """Step until the particles have touched and separated again."""
    touched = False
    for _ in range(max_steps):
        system.step()
        d = system.diagnostics()
        if d["contacts_per_particle"] > 0 or d["wall_contacts"] > 0:
            touched = True
        elif touched:
            return
    raise AssertionError("collision did not end")


def test_damping_ratio_limits():
    assert damping_ratio(1.0) == 0.0
    # collision time of an undamped contact is pi sqrt(m*/k)
    assert collision_time(2e4, 1e-4, 1.0) == pytest.approx(math.pi * math.sqrt(1e-4 / 2e4))
    # weak damping: clipping hardly matters and the unclipped formula is recovered
    e = 0.999
    assert damping_ratio(e) == pytest.approx(-math.log(e) / math.sqrt(math.pi ** 2 + math.log(e) ** 2), rel=2e-3)


@pytest.mark.parametrize("restitution", [0.1, 0.43, 0.8])
def test_damping_ratio_against_direct_ode_integration(restitution):
    """Integrate m x'' = -max(k x + eta x', 0) to the moment the force vanishes (scipy, tight
    tolerances) and compare the rebound speed and duration with the closed form used."""
    from scipy.integrate import solve_ivp
    k, m = 2e4, 5e-5
    eta = 2 * damping_ratio(restitution) * math.sqrt(m * k)

    def rhs(t, y):
        return [y[1], -(k * y[0] + eta * y[1]) / m]

    def force_vanishes(t, y):
        return k * y[0] + eta * y[1]
    force_vanishes.terminal = True
    force_vanishes.direction = -1
    sol = solve_ivp(rhs, (0, 1.0), [0.0, 1.0], events=force_vanishes, rtol=1e-12, atol=1e-15,
                    first_step=1e-9)
    assert -sol.y_events[0][0][1] == pytest.approx(restitution, rel=1e-7)
    assert sol.t_events[0][0] == pytest.approx(collision_time(k, m, restitution), rel=1e-7)


def head_on_restitution(restitution, steps_per_collision, phase, v=0.8):
    """Measured restitution of a head-on sphere pair whose first touch falls at ``phase`` (0-1)
    of a time step."""
    contact = paper_contact(restitution=restitution)
    dt = contact.collision_time(DENSITY * math.pi / 6 * SPHERE_D ** 3) / steps_per_collision
    gap = v * dt * (3 + phase)
    s = make_system([[0.05, 0.05, 0.05], [0.05 + SPHERE_D + gap, 0.05, 0.05]], R,
                    velocity=[[v / 2, 0, 0], [-v / 2, 0, 0]], contact=contact, dt=dt)
    run_until_separated(s)
    vel = by_id(s, "velocity")
    assert vel[0, 0] + vel[1, 0] == pytest.approx(0.0, abs=1e-14)  # momentum
    return (vel[1, 0] - vel[0, 0]) / v


@pytest.mark.parametrize("restitution", [0.43, 0.7, 0.95])
@pytest.mark.parametrize("phase", [0.0, 0.5, 0.9])
def test_head_on_sphere_collision_reproduces_restitution(restitution, phase):
    assert head_on_restitution(restitution, 50, phase) == pytest.approx(restitution, rel=0.01)


def test_restitution_at_the_paper_time_step():
    """At the paper's dt = 1e-5 s (t_c/14 for the seed's particles) the damping calibrated for the
    discrete integrator gives the set restitution on average over touch phases, and each single
    impact within 1 %; the calibration tends to the continuous clipped-dashpot value as dt -> 0."""
    contact = paper_contact(restitution=0.43)
    ratio = contact.collision_time(DENSITY * math.pi / 6 * SPHERE_D ** 3) / 1e-5
    assert 13 < ratio < 15
    phases = np.linspace(0, 1, 8, endpoint=False) + 1 / 16  # between the calibration's phases
    measured = np.array([head_on_restitution(0.43, ratio, ph) for ph in phases]) / 0.43 - 1
    assert abs(measured.mean()) < 0.002
    assert np.abs(measured).max() < 0.01
    from fvdem.dem.contact_law import calibrated_damping_ratio
    assert calibrated_damping_ratio(0.43, 1e-3) == pytest.approx(damping_ratio(0.43), rel=1e-3)


def test_damping_calibration_replica_matches_the_kernels():
    """The pure-Python replica used for calibration reproduces the numba kernels' collision."""
    from fvdem.dem.contact_law import discrete_restitution
    contact = paper_contact(restitution=0.43)
    m = DENSITY * math.pi / 6 * SPHERE_D ** 3
    dt = contact.collision_time(m) / 14
    zeta = contact.parameters(dt, m)[ZETA_N]
    step = dt * math.sqrt(contact.normal_stiffness / (0.5 * m))
    for phase in (0.1, 0.6):
        assert head_on_restitution(0.43, 14, phase) == pytest.approx(discrete_restitution(zeta, step, phase),
                                                                     rel=2e-3)


def test_sphere_wall_collision_reproduces_restitution():
    s = make_system([[0.05, 0.05, R * 1.05]], R, velocity=[[0, 0, -1.0]], box=WALLED, steps_per_collision=200)
    run_until_separated(s)
    assert by_id(s, "velocity")[0, 2] == pytest.approx(0.43, rel=0.01)


@pytest.mark.parametrize("arrangement", ["side_by_side", "crossed"])
def test_spherocylinder_collisions_reproduce_restitution(arrangement):
    r, h = 1.5e-3, 4.5e-3
    # approach along z; rods lie in the x-y plane, parallel or crossed at right angles
    axis = [[1, 0, 0], [1, 0, 0]] if arrangement == "side_by_side" else [[1, 0, 0], [0, 1, 0]]
    s = make_system([[0.05, 0.05, 0.05], [0.05, 0.05, 0.05 + 2 * r * 1.02]], r, h, axis=axis,
                    velocity=[[0, 0, 0.3], [0, 0, -0.3]], steps_per_collision=200)
    run_until_separated(s)
    vel = by_id(s, "velocity")
    assert (vel[1, 2] - vel[0, 2]) / 0.6 == pytest.approx(0.43, rel=0.01)
    # central impact: no spin picked up
    assert np.abs(by_id(s, "angular_velocity")).max() < 1e-6


@pytest.mark.parametrize("tangential_speed", [0.05, 0.3, 2.0])
def test_oblique_wall_impact_respects_coulomb_limit(tangential_speed):
    mu = 0.3
    vn = 0.5
    s = make_system([[0.05, 0.05, R * 1.02]], R, velocity=[[tangential_speed, 0, -vn]], box=WALLED,
                    contact=paper_contact(friction=mu, rolling_friction=0.0))
    m = s.particles.mass[0]
    run_until_separated(s)
    v = by_id(s, "velocity")[0]
    impulse_n = m * (v[2] + vn)
    impulse_t = m * abs(v[0] - tangential_speed)
    assert impulse_t <= mu * impulse_n * (1 + 1e-9)
    if tangential_speed == 2.0:
        # sliding throughout: the tangential impulse is exactly mu times the normal one
        assert impulse_t == pytest.approx(mu * impulse_n, rel=0.01)


def _sphere_on_floor(contact, v0, rolling=False):
    """A sphere resting on the floor at its static overlap, moving at ``v0`` along x, sliding (no spin) or
    ``rolling`` (spin v0 / R), its forces computed."""
    s = make_system([[0.02, 0.05, R]], R, velocity=[[v0, 0, 0]], contact=contact, gravity=(0, 0, -9.81),
                    box=Box((0.0, 0.0, 0.0), (1.0, 0.1, 0.1), (False, False, False)))
    m = s.particles.mass[0]
    s.particles.position[0, 2] = R - m * 9.81 / contact.normal_stiffness
    if rolling:
        s.particles.angular_momentum[0, 1] = s.particles.inertia[0, 0] * v0 / R
    s.reference_position[:] = s.particles.position
    s.compute_forces()
    return s


def test_sliding_sphere_reaches_pure_rolling_at_five_sevenths():
    mu = 0.3
    v0 = 0.5
    # settling vertically first would take long: start at the static overlap instead
    s = _sphere_on_floor(paper_contact(friction=mu, rolling_friction=0.0), v0)
    slide_time = 2 * v0 / (7 * mu * 9.81)  # analytical time to reach rolling
    s.step(int(1.5 * slide_time / s.dt))
    v = by_id(s, "velocity")[0, 0]
    w = by_id(s, "angular_velocity")[0, 1]
    assert v == pytest.approx(5 / 7 * v0, rel=0.01)
    assert w * R == pytest.approx(v, rel=0.01)  # rolling without slip


def test_rolling_friction_decelerates_rolling_sphere():
    """Constant directional torque: a rolling sphere decelerates at 5/7 mu_r g (energy balance)."""
    mu_r = 0.05
    contact = paper_contact(friction=0.5, rolling_friction=mu_r)
    v0 = 0.3
    s = _sphere_on_floor(contact, v0, rolling=True)
    t = 0.05
    s.step(int(t / s.dt))
    v = by_id(s, "velocity")[0, 0]
    assert v == pytest.approx(v0 - 5 / 7 * mu_r * 9.81 * t, rel=0.02)


@pytest.mark.parametrize("mu_r", [0.05, 0.46])
def test_rolling_friction_decelerates_a_rod_rolling_on_its_side(mu_r):
    """A spherocylinder (3 x 12 mm, the paper's AR-4 rod) lying on the floor and rolling about its own axis rests on
    both cap ends, each carrying half its weight and each resisting the roll with ``mu_r r F_n``: the torques sum
    to ``mu_r r m g``, which dissipates ``mu_r m g v``; with ``E = (m + I_axis / r^2) v^2 / 2`` it decelerates at
    ``mu_r g m / (m + I_axis / r^2)`` (energy balance), rolling without slip and without turning."""
    r, h = 1.5e-3, 4.5e-3
    contact = paper_contact(friction=0.5, rolling_friction=mu_r)
    v0, t = 0.3, 0.02
    s = make_system([[0.05, 0.05, r]], r, h, velocity=[[v0, 0, 0]], axis=[[0.0, 1.0, 0.0]], contact=contact,
                    gravity=(0, 0, -9.81), box=Box((0.0, 0.0, 0.0), (1.0, 0.1, 0.1), (False, False, False)))
    p = s.particles
    m, i_axis = p.mass[0], p.inertia[0].min()
    p.position[0, 2] = r - m * 9.81 / 2 / contact.normal_stiffness  # each end's static overlap
    p.angular_momentum[0, 1] = i_axis * v0 / r
    s.reference_position[:] = p.position
    s.compute_forces()
    s.step(int(t / s.dt))
    expected = v0 - mu_r * 9.81 * m / (m + i_axis / r ** 2) * t
    v, w = by_id(s, "velocity")[0], by_id(s, "angular_velocity")[0]
    assert abs(v[0] - expected) < 1e-3 * (v0 - expected)
    assert w[1] * r == pytest.approx(v[0], rel=1e-4) and abs(by_id(s, "axis")[0, 1]) == pytest.approx(1.0)


def test_newton_third_law_and_angular_momentum_pair_by_pair():
    """Random overlapping spherocylinder pairs with random motion: the two forces are exact
    negatives and the torques cancel the moment of the force couple (a contact creates no momentum
    and no angular momentum)."""
    rng = np.random.default_rng(5)
    r, h = 1.5e-3, 4.5e-3
    box = Box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), (True, True, True))
    checked = 0
    for _ in range(40):
        centre = np.array([0.05, 0.05, 0.05])
        pos = np.array([centre, centre + rng.normal(scale=2.5e-3, size=3)])
        s = make_system(pos, r, h, velocity=rng.normal(scale=0.1, size=(2, 3)), axis=rng.normal(size=(2, 3)),
                        box=box)
        s.particles.angular_momentum[:] = rng.normal(scale=1e-9, size=(2, 3))
        s.step(2)
        p = s.particles
        f = p.contact_force
        if not f.any():
            continue
        np.testing.assert_array_equal(f[0], -f[1])
        moment = p.contact_torque.sum(axis=0) + np.cross(p.position[0] - p.position[1], f[0])
        assert np.linalg.norm(moment) <= 1e-12 * np.linalg.norm(f[0]) * r
        checked += 1
    assert checked > 20


def test_contact_forces_of_a_cluster_sum_to_zero():
    rng = np.random.default_rng(6)
    n = 40
    r, h = 1.5e-3, 4.5e-3
    box = Box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), (True, True, True))
    s = make_system(0.01 + rng.uniform(0, 0.012, size=(n, 3)), r, h, velocity=rng.normal(scale=0.1, size=(n, 3)),
                    axis=rng.normal(size=(n, 3)), box=box)
    s.step(3)
    p = s.particles
    assert s.diagnostics()["contacts_per_particle"] > 2
    scale = np.abs(p.contact_force).max()
    assert np.abs(p.contact_force.sum(axis=0)).max() <= 1e-13 * scale * n
    total_torque = (np.cross(p.position, p.contact_force) + p.contact_torque).sum(axis=0)
    assert np.abs(total_torque).max() <= 1e-13 * scale * n * 0.02


@pytest.mark.parametrize("where", ["side", "cap"])
def test_sphere_on_spherocylinder_collision(where):
    """A sphere hitting a rod's side (central: no spin) or its cap end: restitution of the normal
    relative velocity, momentum conserved, contact point on the rod's surface."""
    from fvdem.dem.particles import ParticleArrays
    from fvdem.dem.system import DEMSystem
    r_rod, h = 1.5e-3, 4.5e-3
    r_sph = 2.0e-3
    if where == "side":
        pos = [[0.05, 0.05, 0.05], [0.05, 0.05, 0.05 + (r_rod + r_sph) * 1.01]]
        approach = np.array([0.0, 0.0, 1.0])
    else:
        pos = [[0.05, 0.05, 0.05], [0.05 + h + (r_rod + r_sph) * 1.01, 0.05, 0.05]]
        approach = np.array([1.0, 0.0, 0.0])
    particles = ParticleArrays.create(np.array(pos), [r_rod, r_sph], [h, 0.0], DENSITY,
                                      axis=[[1, 0, 0], [1, 0, 0]],
                                      velocity=np.array([0.2 * approach, -0.2 * approach]))
    contact = paper_contact(restitution=0.6, friction=0.3, rolling_friction=0.0)
    box = Box((0.0, 0.0, 0.0), (0.1, 0.1, 0.1), (True, True, True))
    m = particles.mass
    reduced = m[0] * m[1] / (m[0] + m[1])
    dt = contact.collision_time(2 * reduced) / 100  # collision_time takes the particle mass (m*/2 inside)
    s = DEMSystem(particles, box, contact, dt, gravity=(0, 0, 0))
    p0 = (m[:, None] * by_id(s, "velocity")).sum(axis=0)
    run_until_separated(s)
    v = by_id(s, "velocity")
    assert np.allclose((m[:, None] * v).sum(axis=0), p0, atol=1e-15)
    assert ((v[1] - v[0]) @ approach) / 0.4 == pytest.approx(0.6, rel=0.01)
    assert np.abs(by_id(s, "angular_velocity")).max() < 1e-6  # both impacts are central


@pytest.mark.parametrize("tangential_speed", [0.02, 0.1])
def test_oblique_pair_impact_restitution_and_coulomb_limit(tangential_speed):
    """Two spheres meeting with a tangential relative velocity: normal restitution as set,
    tangential impulse <= mu x normal impulse, momentum and angular momentum conserved. (At large
    sliding speeds the pair moves sideways during the contact and the normal rotates, so a fixed
    axis is no longer the normal: gross sliding is tested against a wall, whose normal is fixed.)"""
    mu, vn = 0.3, 0.4
    contact = paper_contact(friction=mu, rolling_friction=0.0)
    normal = np.array([1.0, 0.0, 0.0])
    s = make_system([[0.05, 0.05, 0.05], [0.05 + SPHERE_D * 1.01, 0.05, 0.05]], R,
                    velocity=[[vn / 2, tangential_speed / 2, 0], [-vn / 2, -tangential_speed / 2, 0]],
                    contact=contact, steps_per_collision=50)
    m = s.particles.mass[0]

    def angular_momentum():
        p = s.particles
        return (np.cross(p.position, p.mass[:, None] * p.velocity) + p.angular_momentum).sum(axis=0)
    initial = angular_momentum()
    run_until_separated(s)
    v = by_id(s, "velocity")
    assert (v[1] - v[0]) @ normal / vn == pytest.approx(0.43, rel=0.01)
    impulse_n = m * abs(v[0] @ normal - vn / 2)
    impulse_t = m * abs(v[0, 1] - tangential_speed / 2)
    assert impulse_t <= mu * impulse_n * (1 + 1e-9)
    np.testing.assert_allclose(v.sum(axis=0), 0.0, atol=1e-14)
    assert np.abs(angular_momentum() - initial).max() <= 1e-12 * np.abs(initial).max()


def _rotated_history_reference(h, n):
    """The stored tangential displacement projected on the plane normal to ``n`` and rescaled to its
    length (the textbook form, one square root)."""
    projected = h - np.dot(h, n) * n
    return projected * np.linalg.norm(h) / np.linalg.norm(projected)


@pytest.mark.parametrize("tilt", [0.0, 1e-9, 1e-6, 3e-3, 9e-3, 1.1e-2, 0.1, 0.7])
def test_the_history_rotation_keeps_its_length_on_both_branches(tilt):
    """The history turned into the new tangent plane, from a normal that turned a little (a packed
    contact) to a lot, equals the textbook projection and rescaling to 1e-15."""
    from fvdem.dem.contact_law import tangential_force
    rng = np.random.default_rng(int(tilt * 1e9) % 1000)
    for _ in range(20):
        n = rng.normal(size=3)
        n /= np.linalg.norm(n)
        in_plane = np.cross(n, rng.normal(size=3))
        in_plane *= 1e-5 / np.linalg.norm(in_plane)
        h = in_plane + tilt * 1e-5 * n  # a history tilted out of the plane by about ``tilt``
        history = np.zeros((1, 4))
        history[0, :3] = h
        # no velocity, no force limit hit: the history stays the rotated one
        tangential_force(history, 0, n[0], n[1], n[2], 0.0, 0.0, 0.0, 1.0, 800.0, 1 / 800.0, 0.0, 1.0, 1e-5)
        expected = _rotated_history_reference(h, n)
        assert np.abs(history[0, :3] - expected).max() <= 1e-15 * np.linalg.norm(h)
        assert abs(np.dot(history[0, :3], n)) <= 1e-15 * np.linalg.norm(h)


@pytest.mark.parametrize("speed", [0.0, 1e-6, 1e-3, 1.0, 100.0])
def test_rolling_torque_on_both_sides_of_its_cap(speed):
    """``-min(mu_r R* F_n / |w_r|, I* / dt) w_r`` with ``w_r`` the rolling part of ``w``, on both
    sides of the cap (a slow roll is stopped within the step, a fast one gets mu_r R* F_n)."""
    from fvdem.dem.contact_law import rolling_torque
    n = np.array([0.0, 0.6, 0.8])
    w = np.array([speed, 0.3 * speed, 2.0 * speed])
    w_roll = w - np.dot(w, n) * n
    mu_r, r_eff, f_n, inertia, inv_dt = 0.46, 1.3e-3, 0.2, 2e-10, 1e5
    torque = np.array(rolling_torque(n[0], n[1], n[2], w[0], w[1], w[2], f_n, mu_r, r_eff, inertia, inv_dt))
    if speed == 0.0:
        np.testing.assert_array_equal(torque, 0.0)
        return
    norm = np.linalg.norm(w_roll)
    expected = -min(mu_r * r_eff * f_n / norm, inertia * inv_dt) * w_roll
    np.testing.assert_allclose(torque, expected, rtol=1e-14, atol=0.0)
    capped = mu_r * r_eff * f_n / norm > inertia * inv_dt
    assert capped == (speed < 10.0)  # the cases cover both branches (the cap at |w_r| = 6 rad/s)


@pytest.mark.parametrize("mu_wall", [0.1, 0.3])
def test_a_wall_friction_of_its_own_sets_the_sliding_time_on_the_wall(mu_wall):
    """``wall_friction``: a sphere sliding on the floor reaches rolling at 5/7 v0 after 2 v0 / (7 mu_w g), the wall's
    coefficient, not the particles' (0.8 here; the particle-particle law is untouched: no pair exists)."""
    v0 = 0.5
    s = _sphere_on_floor(paper_contact(friction=0.8, rolling_friction=0.0, wall_friction=mu_wall), v0)
    slide_time = 2 * v0 / (7 * mu_wall * 9.81)
    s.step(int(0.5 * slide_time / s.dt))  # half-way: still sliding, decelerated at mu_w g
    assert by_id(s, "velocity")[0, 0] == pytest.approx(v0 - mu_wall * 9.81 * 0.5 * slide_time, rel=0.02)
    s.step(int(slide_time / s.dt))
    assert by_id(s, "velocity")[0, 0] == pytest.approx(5 / 7 * v0, rel=0.01)


def test_the_wall_coefficients_default_to_the_particles_and_a_wall_rolling_friction_decelerates():
    """Unset, the wall's coefficients are the particle-particle ones (the same kernel vector); a rolling sphere on
    the floor decelerates at 5/7 mu_rw g with ``wall_rolling_friction`` mu_rw (energy balance), and keeps rolling
    with mu_rw = 0 whatever the particles' mu_r."""
    from fvdem.dem.contact_law import FRICTION, ROLLING_FRICTION, WALL_FRICTION, WALL_ROLLING_FRICTION
    p = ContactModel(friction=0.4, rolling_friction=0.2).parameters(1e-5, 1e-4)
    assert p[WALL_FRICTION] == p[FRICTION] == 0.4 and p[WALL_ROLLING_FRICTION] == p[ROLLING_FRICTION] == 0.2
    v0, t = 0.3, 0.05
    ends = []
    for mu_rw in (0.05, 0.0):
        s = _sphere_on_floor(paper_contact(friction=0.5, rolling_friction=0.3, wall_rolling_friction=mu_rw), v0,
                             rolling=True)
        s.step(int(t / s.dt))
        ends.append(by_id(s, "velocity")[0, 0])
    assert ends[0] == pytest.approx(v0 - 5 / 7 * 0.05 * 9.81 * t, rel=0.02)
    assert ends[1] == pytest.approx(v0, rel=1e-3)


def test_one_set_of_contact_defaults_from_the_case_to_the_kernels():
    """The case's [contact] defaults, ContactModel's and ``contact_law.DEFAULTS`` are one set, key by key; the
    parameter vector the kernels take holds them at their named indices, and the constants the kernels read
    from it (``kernel_constants``, ``wall_constants``) are those entries under their names."""
    from dataclasses import fields

    from fvdem.case.schema import ContactConfig
    from fvdem.dem import contact_law as cl
    case, model = ContactConfig(), ContactModel()
    names = [f.name for f in fields(ContactModel)]
    assert sorted(names) == sorted(cl.DEFAULTS)
    for name in names:
        assert getattr(case, name) == getattr(model, name) == cl.DEFAULTS[name], name
    assert ContactModel(**{name: getattr(case, name) for name in names}) == model  # the case's keys build it
    mass, dt = DENSITY * math.pi / 6 * SPHERE_D ** 3, 5e-5
    p = model.parameters(dt, mass)
    assert p.shape == (cl.PARAMETER_COUNT,)
    k_n, defaults = cl.DEFAULTS["normal_stiffness"], cl.DEFAULTS
    expected = {cl.K_N: k_n, cl.K_T: defaults["tangential_stiffness_ratio"] * k_n,
                cl.ETA_T_OVER_ETA_N: defaults["tangential_damping_ratio"], cl.FRICTION: defaults["friction"],
                cl.ROLLING_FRICTION: defaults["rolling_friction"], cl.DT: dt, cl.WALL_FRICTION: defaults["friction"],
                cl.WALL_ROLLING_FRICTION: defaults["rolling_friction"],
                cl.ZETA_N: cl.calibrated_damping_ratio(defaults["restitution"], dt * math.sqrt(k_n / (0.5 * mass))),
                cl.ZETA_WALL: cl.calibrated_damping_ratio(defaults["restitution"], dt * math.sqrt(k_n / mass))}
    assert sorted(expected) == list(range(cl.PARAMETER_COUNT))  # every entry named once
    assert all(p[index] == value for index, value in expected.items())
    law = cl.kernel_constants(p)
    by_name = {cl.LAW_K_N: p[cl.K_N], cl.LAW_K_T: p[cl.K_T], cl.LAW_INV_K_T: 1.0 / p[cl.K_T],
               cl.LAW_ETA_T_RATIO: p[cl.ETA_T_OVER_ETA_N], cl.LAW_FRICTION: p[cl.FRICTION],
               cl.LAW_ROLLING_FRICTION: p[cl.ROLLING_FRICTION], cl.LAW_DT: dt, cl.LAW_INV_DT: 1.0 / dt}
    assert sorted(by_name) == list(range(len(law))) and all(law[i] == value for i, value in by_name.items())
    walls = ContactModel(wall_friction=0.1, wall_rolling_friction=0.2).parameters(dt, mass)
    wall = cl.wall_constants(cl.kernel_constants(walls), walls)
    assert (wall[cl.LAW_FRICTION], wall[cl.LAW_ROLLING_FRICTION]) == (0.1, 0.2)
    assert all(wall[i] == law[i] for i in by_name if i not in (cl.LAW_FRICTION, cl.LAW_ROLLING_FRICTION))
