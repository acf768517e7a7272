"""The compiled closures (each registered law of ``fvdem.coupling.laws`` through the loops ``law_loops`` writes
from the registry) against the same law run in plain Python, and against the values fvdem 0.2.0's
separately written numpy and numba closures gave (``tests/data/law_values_0.2.0.npz``), to 1e-12; and the
bridge's exchange kernels against numpy."""
import json
import math
import warnings
from pathlib import Path

import numba
import numpy as np
import pytest

from fvdem.coupling import closures, kernels
from fvdem.coupling.bridge import particle_response
from fvdem.coupling.interpolation import scatter
from fvdem.coupling.laws import D_P, DRAG, MU, RHO, reynolds, slip_speed

from paths import DATA

AIR = (1.2, 1.8e-5)
WATER = (1000.0, 1.0e-3)
PARTICLES = {  # cylinder diameter, total length, fluid
    "sphere-air": (5.3e-3, 5.3e-3, AIR),
    "rod4-air": (3.2e-3, 12.8e-3, AIR),
    "rod2-water": (2.0e-3, 4.0e-3, WATER),
}


def inputs(n=600, seed=3):
    """Slips over seven decades (zero, axis-parallel and axis-perpendicular ones included), voidages
    0.4-1 (1 exactly too) and random orientations."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1)[:, None]
    direction = rng.normal(size=(n, 3))
    direction /= np.linalg.norm(direction, axis=1)[:, None]
    slip = direction * 10.0 ** rng.uniform(-6, 1.3, n)[:, None]
    slip[0] = 0.0
    slip[1] = 2.0 * axis[1]  # parallel: no lift or torque
    perpendicular = np.cross(axis[2], [0.0, 0.0, 1.0])
    slip[2] = 1.5 * perpendicular / np.linalg.norm(perpendicular)
    voidage = rng.uniform(0.4, 1.0, n)
    voidage[3] = 1.0
    return slip, voidage, axis


def assert_close(actual, expected):
    expected = np.asarray(expected, float)
    scale = np.abs(expected).max() if expected.size else 0.0
    np.testing.assert_allclose(actual, expected, rtol=1e-12, atol=1e-12 * scale)


ALL_LAWS = [(kind, name) for kind in ("drag", "lift", "torque") for name in closures.LAWS[kind]]
RECORDED = DATA / "law_values_0.2.0.npz"


def test_every_seed_law_is_registered():
    for kind, name in (("drag", "hoelzer-sommerfeld"), ("drag", "sanjeevi-padding"), ("drag", "gidaspow"),
                       ("drag", "beetstra"), ("drag", "tenneti"), ("drag", "tang"), ("lift", "zastawny"),
                       ("lift", "sanjeevi-padding"), ("torque", "zastawny"), ("torque", "sanjeevi-padding")):
        assert (kind, name) in ALL_LAWS


@pytest.mark.parametrize("kind,name", ALL_LAWS)
@pytest.mark.parametrize("particle_name", list(PARTICLES))
def test_compiled_law_equals_the_same_law_in_python_and_fvdem_0_2_0(kind, name, particle_name):
    law = closures.law(kind, name)
    d, length, (rho, mu) = PARTICLES[particle_name]
    shape = "sphere" if length <= d else "spherocylinder"
    if shape not in law.shapes:
        pytest.skip(f"{name} is not a {shape} law")
    particle = closures.ParticleShape(d, length, rho, mu)
    slip, voidage, axis = inputs()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # range warnings of the dense laws
        expected = law.reference_values(particle, slip, voidage, axis)
        actual = law.evaluate(particle, slip, voidage, axis)
    if law.none and kind != "drag":
        assert actual is None and expected is None
        return
    assert actual.shape == expected.shape
    assert np.all(np.isfinite(actual))
    assert_close(actual, expected)
    if name != "none":
        if kind == "drag":
            assert np.all(actual > 0)
        else:  # no lift or torque along the axis
            assert np.all(actual[[0, 1]] == 0.0)
    # the values of 0.2.0's closures (96 of the same kind of inputs)
    with np.load(RECORDED) as recorded, warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        assert_close(law.evaluate(particle, recorded["slip"], recorded["voidage"], recorded["axis"]),
                     recorded[f"{kind}/{name}/{particle_name}"])


def test_kernel_path_warns_outside_the_fitted_range():
    closures.reset_range_warnings()
    particle = closures.ParticleShape(5.3e-3, 5.3e-3, *AIR)
    slip = np.array([[0.0, 0.0, 3.0]])
    with pytest.warns(RuntimeWarning, match="tenneti.*Re .* above its fitted range 0-300"):
        closures.law("drag", "tenneti").evaluate(particle, slip, np.array([0.45]), np.array([[0.0, 0.0, 1.0]]))
    closures.reset_range_warnings()


def test_a_law_is_registered_only_compiled_for_its_kinds_signature():
    """A law is a compiled scalar function of one particle with its kind's signature (``laws.DRAG``,
    ``laws.FORCE``; registered so it runs, ``test_a_law_registered_in_a_test_runs_inlined_in_the_fast_loop``);
    a plain Python function, or one compiled for another signature, is refused at registration with the
    decorator to use."""
    from fvdem.coupling import laws

    for wrong in (lambda particle, slip, voidage, axis: np.ones(len(slip)), laws.zastawny_lift):
        with pytest.raises(TypeError, match=r"njit\(fvdem.coupling.laws.DRAG, cache=True\)"):
            closures.register("drag", "wrong-test")(wrong)
    assert "wrong-test" not in closures.LAWS["drag"]


@numba.njit(DRAG, cache=True, inline="always")
def toy_drag(sx, sy, sz, eps, ax, ay, az, shape):
    """A drag law as one adds it (``laws.py``'s form and shared pieces): Stokes drag with a Schiller-Naumann
    factor and a voidage power [kg/s]."""
    re = reynolds(slip_speed(sx, sy, sz), eps, shape[D_P], shape[RHO], shape[MU])
    return 3.0 * math.pi * shape[MU] * shape[D_P] * eps ** -1.65 * (1.0 + 0.15 * re ** 0.687)


def test_a_law_registered_in_a_test_runs_inlined_in_the_fast_loop():
    """Registering a law is all it takes: the next evaluation writes the loops for the new registry (another
    fingerprint, so another numba cache), the law runs there by its index, its values are its Python
    reference's, and the registry without it finds its own loops again."""
    before = closures.fast_loops()
    closures.register("drag", "toy-test", summary="a test's law")(toy_drag)
    try:
        particle = closures.ParticleShape(3.2e-3, 12.8e-3, *AIR)
        slip, voidage, axis = inputs()
        law = closures.law("drag", "toy-test")
        values = law.evaluate(particle, slip, voidage, axis)
        loops = closures.fast_loops()
        assert loops is not before and loops.FINGERPRINT != before.FINGERPRINT
        k = loops.INDEX["drag"]["toy-test"]
        assert getattr(loops, f"drag_{k}") is toy_drag and f"return drag_{k}(" in Path(loops.__file__).read_text()
        assert loops.drag_loop.signatures  # the fast path ran it
        assert_close(values, law.reference_values(particle, slip, voidage, axis))
        assert np.all(values > 0)
        assert list(loops.INDEX["drag"]) == list(closures.LAWS["drag"])
    finally:
        closures.LAWS["drag"].pop("toy-test", None)
    assert closures.fast_loops() is before


def test_the_fingerprint_follows_the_registry_and_the_laws_source_files(tmp_path, monkeypatch):
    """The loops' module name (so numba's cache) changes with the registry's names and order and with an edit
    of a law's source file or of a module of its package it imports, and with nothing else; it is the same in
    another process (else every run would compile again)."""
    import subprocess
    import sys

    from fvdem.coupling import law_loops
    package = tmp_path / "toylaws"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "constants.py").write_text("SCALE = 2.0\n")
    (package / "law.py").write_text("from numba import njit\nfrom fvdem.coupling.laws import DRAG\n"
                                    "from .constants import SCALE\n\n\n@njit(DRAG)\n"
                                    "def law(sx, sy, sz, eps, ax, ay, az, shape):\n    return SCALE * eps\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import toylaws.law
    registry = {"drag": (("a", toylaws.law.law), ("b", closures.LAWS["drag"]["none"].scalar)), "lift": (),
                "torque": (), "set": ()}
    first = law_loops.fingerprint(registry)
    assert law_loops.fingerprint(dict(registry)) == first
    assert law_loops.fingerprint({**registry, "drag": registry["drag"][::-1]}) != first
    assert law_loops.fingerprint({**registry, "drag": (("c", toylaws.law.law), registry["drag"][1])}) != first
    (package / "constants.py").write_text("SCALE = 3.0\n")
    assert law_loops.fingerprint(registry) != first
    (package / "constants.py").write_text("SCALE = 2.0\n")
    assert law_loops.fingerprint(registry) == first
    here = closures.fast_loops().FINGERPRINT
    there = subprocess.run([sys.executable, "-c", "from fvdem.coupling import closures; "
                            "print(closures.fast_loops().FINGERPRINT)"], capture_output=True, text=True, check=True)
    assert there.stdout.strip() == here


def test_generated_loops_unused_for_a_while_are_removed_with_their_caches(tmp_path):
    """When a module is written, those not used (touched) for ``STALE_DAYS`` go, with numba's and Python's caches
    of them; the one in use and recently used ones stay."""
    import os
    import time

    from fvdem.coupling import law_loops
    (tmp_path / "__pycache__").mkdir()
    names = {age: f"{law_loops.PREFIX}{age:016d}" for age in (0, 2, law_loops.STALE_DAYS + 1)}
    for age, name in names.items():
        for path in (tmp_path / f"{name}.py", tmp_path / "__pycache__" / f"{name}.drag_loop-46.py311.nbi"):
            path.write_text("")
            os.utime(path, (time.time() - age * 86400,) * 2)
    law_loops._remove_stale(tmp_path, names[0])
    left = {p.name.split(".")[0] for p in tmp_path.rglob("*") if p.is_file()}
    assert left == {names[0], names[2]}


@pytest.mark.parametrize("kind", ["drag", "lift", "torque"])
def test_the_fast_loops_run_every_registered_law_by_its_index_and_list_what_fvdem_laws_lists(kind, capsys):
    """The loops' index is the registry's order, which ``fvdem laws KIND`` lists; index k runs the law
    registered under that name (its values are its Python reference's)."""
    from fvdem.cli import main
    assert main(["laws", kind, "--json"]) == 0
    listed = list(json.loads(capsys.readouterr().out)[kind])
    loops = closures.fast_loops()
    assert list(loops.INDEX[kind]) == listed == list(closures.LAWS[kind])
    particle = closures.ParticleShape(3.2e-3, 12.8e-3, *AIR)
    slip, voidage, axis = closures.kernel_inputs(*inputs(n=200))
    shape = particle.kernel_args
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # range warnings of the dense laws
        for name, k in loops.INDEX[kind].items():
            law = closures.LAWS[kind][name]
            assert getattr(loops, f"{kind}_{k}") is law.scalar
            out = np.empty(len(slip)) if kind == "drag" else np.empty((len(slip), 3))
            getattr(loops, f"{kind}_loop")(k, slip, voidage, axis, shape, out)
            expected = law.reference_values(particle, slip, voidage, axis)
            assert_close(out, np.zeros_like(out) if expected is None else expected)


def grid_weights(n, cells, width, seed=5):
    rng = np.random.default_rng(seed)
    index = rng.integers(0, cells, (n, width)).astype(np.int64)
    weights = rng.uniform(0, 1, (n, width))
    weights[rng.uniform(size=(n, width)) < 0.2] = 0.0
    return index, weights


def reference_scatter(values, cells, weights, count, counts=None):
    """The deposition of row i's first ``counts[i]`` entries (all when ``counts`` is None)."""
    out = np.zeros((count, values.shape[1]))
    for k in range(cells.shape[1]):
        used = weights[:, k] if counts is None else np.where(k < counts, weights[:, k], 0.0)
        np.add.at(out, cells[:, k], used[:, None] * values)
    return out


def on_each_thread_count(run):
    """``run()`` on 1 and on all threads; the results (the numba default restored afterwards)."""
    before = numba.get_num_threads()
    try:
        results = []
        for threads in sorted({1, numba.config.NUMBA_NUM_THREADS}):
            numba.set_num_threads(threads)
            results.append(run())
        return results
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("n", [3, 1000])
def test_parallel_scatter_equals_serial_sum_and_is_thread_count_independent(n):
    cells, weights = grid_weights(n, 50, 8)
    counts = np.random.default_rng(2).integers(0, 9, n).astype(np.int32)  # rows of any length up to the width
    values = np.random.default_rng(1).normal(size=(n, 3))
    expected = reference_scatter(values, cells, weights, 50, counts)
    results = on_each_thread_count(lambda: scatter(values, cells, weights, counts, np.zeros((50, 3))))
    assert_close(results[0], expected)
    for other in results[1:]:
        assert np.array_equal(other, results[0])  # bit for bit whatever the threads


def test_exchange_terms_equal_numpy_response_and_deposition():
    rng = np.random.default_rng(7)
    n, count = 2000, 60
    cells, weights = grid_weights(n, count, 8)
    weights /= weights.sum(axis=1)[:, None]
    mass = rng.uniform(1e-5, 1e-4, n)
    c = 10.0 ** rng.uniform(-6, -2, n)
    c[0] = 0.0  # no drag: k = 0
    velocity = rng.normal(size=(n, 3))
    force = rng.normal(size=(n, 3)) * 1e-3
    gravity = np.array([0.0, 0.0, -9.81])
    lift = rng.normal(size=(n, 3)) * 1e-5
    h, substeps, dt = 5e-5, 10, 5e-4
    one_minus_r, k = particle_response(mass, c, h, substeps)
    coefficient = mass * one_minus_r / dt
    exchanged = coefficient[:, None] * velocity - (mass * k)[:, None] * (force / mass[:, None] + gravity) - lift
    beta_expected = reference_scatter(coefficient[:, None], cells, weights, count)[:, 0]
    source_expected = reference_scatter(exchanged, cells, weights, count)
    for lift_in, source_ref in ((lift, source_expected),
                                (np.zeros((0, 3)), reference_scatter(exchanged + lift, cells, weights, count))):
        beta, source = kernels.exchange_terms(mass, c, velocity, force, gravity, lift_in, h, substeps, dt, cells,
                                              weights, np.full(n, 8, np.int32), np.zeros(count), np.zeros((count, 3)))
        assert_close(beta, beta_expected)
        assert_close(source, source_ref)


@pytest.mark.parametrize("laws", [("sanjeevi-padding", "sanjeevi-padding", "sanjeevi-padding"),
                                  ("hoelzer-sommerfeld", "zastawny", "zastawny"), ("gidaspow", "none", "none")])
def test_a_set_in_one_pass_equals_its_laws_one_by_one(laws):
    drag, lift, torque = laws
    particle = closures.ParticleShape(3.2e-3, 12.8e-3, *AIR)
    slip, voidage, axis = inputs()
    voidage = np.maximum(voidage, 0.65)  # within the fitted solids fractions
    together = closures.evaluate_set(particle, drag, lift, torque, slip, voidage, axis)
    for kind, name, value in zip(("drag", "lift", "torque"), laws, together):
        alone = closures.law(kind, name).evaluate(particle, slip, voidage, axis)
        assert (value is None and alone is None) or np.array_equal(value, alone)


@pytest.mark.parametrize("fixed", [False, True])
def test_slip_at_particles_equals_clip_and_difference(fixed):
    rng = np.random.default_rng(3)
    n = 500
    at = np.column_stack([rng.uniform(0.0, 1.2, n), rng.normal(size=(n, 3))])
    velocity = rng.normal(size=(n, 3))
    voidage, slip = kernels.slip_at_particles(at, velocity, 0.3, fixed, np.empty(n), np.empty((n, 3)))
    assert np.array_equal(voidage, np.clip(at[:, 0], 0.3, 1.0))
    assert np.array_equal(slip, at[:, 1:] - (0.0 if fixed else velocity))


@pytest.mark.parametrize("n", [5, 3000])
@pytest.mark.parametrize("gradient, lift, explicit", [(True, True, False), (False, False, True), (True, False, False)])
def test_particle_forces_equal_the_numpy_sum_on_any_thread_count(n, gradient, lift, explicit):
    """The gas's forces held on the particles: ``-V_p grad p + V_p G (+ lift) (+ explicit drag)`` and the
    fluid velocity, written in place; the pressure part's total equal to numpy's to round-off and bit
    for bit the same on any number of threads."""
    rng = np.random.default_rng(11)
    at = rng.normal(size=(n, 6)) * np.array([1.0, 1.0, 1.0, 1e4, 1e4, 1e4])
    radius = rng.uniform(1e-3, 3e-3, n)
    half_length = np.where(rng.uniform(size=n) < 0.5, 0.0, rng.uniform(0.0, 5e-3, n))
    mean = np.array([0.0, 0.0, 1.2e4])
    lift_in = rng.normal(size=(n, 3)) * 1e-4 if lift else np.zeros((0, 3))
    drag_in = rng.normal(size=(n, 3)) * 1e-3 if explicit else np.zeros((0, 3))
    volume = (np.pi * radius ** 2 * 2.0 * half_length + 4.0 / 3.0 * np.pi * radius ** 3)[:, None]
    pressure_part = (-volume * at[:, 3:] if gradient else np.zeros((n, 3))) + volume * mean
    expected = pressure_part + (lift_in if lift else 0.0) + (drag_in if explicit else 0.0)

    def run():
        fluid, external = np.empty((n, 3)), np.empty((n, 3))
        total = kernels.particle_forces(at, gradient, radius, half_length, mean, lift_in, drag_in, fluid, external)
        return fluid, external, total

    results = on_each_thread_count(run)
    fluid, external, total = results[0]
    assert np.array_equal(fluid, at[:, :3])
    np.testing.assert_allclose(external, expected, rtol=1e-12, atol=1e-15 * np.abs(expected).max())
    np.testing.assert_allclose(total, pressure_part.sum(axis=0), rtol=1e-12, atol=1e-12 * np.abs(pressure_part).sum())
    for other in results[1:]:
        assert all(np.array_equal(a, b) for a, b in zip(other, results[0]))


@pytest.mark.parametrize("n", [3, 5000])
def test_column_sums_equal_numpy_on_any_thread_count(n):
    values = np.random.default_rng(5).normal(size=(n, 3))
    results = on_each_thread_count(lambda: kernels.column_sums(values))
    np.testing.assert_allclose(results[0], values.sum(axis=0), rtol=0, atol=1e-12 * np.abs(values).sum())
    for other in results[1:]:
        assert np.array_equal(other, results[0])
