"""Secondary motion through the Python API: mdc.Simulation (cpp/solve/reduced_dynamics.h)."""

import numpy as np
import pytest
from support.dynamics import (  # the benchmark's free-body measurement
    damped_oscillation,
    free_motion,
    released,
    swing,
)
from support.poses import rigid_transform as rigid

import modal_deform.core as mdc


@pytest.fixture(scope="module")
def bar():
    """A closed bar, baked small: a free body for the period and damping checks."""
    V, F = mdc.testing.bar(4, 4, 16, 1, 1, 4)
    return V, F, mdc.bake(V, F, modes=12, derivatives=20, ghost=300)


@pytest.fixture(scope="module")
def tube():
    """A tube of 1000 vertices held at its bottom ring, its top ring on a controller."""
    V, F = mdc.testing.cylinder(25, 40, radius=1.0, length=4.0)
    handles = [np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > 4 - 1e-9)]
    return V, F, handles, mdc.bake(V, F, modes=16, derivatives=30, ghost=400)


@pytest.mark.parametrize(
    "period, fps, substeps", [(12.0, 24.0, 2), (12.0, 24.0, 1), (6.0, 60.0, 3)]
)
def test_undamped_free_body_keeps_its_period_and_amplitude(bar, period, fps, substeps):
    *_, basis = bar
    frames = int(10 * period) + 1
    trace = released(basis, frames, period=period, damping=0.0, fps=fps, substeps=substeps)
    measured, decrement = damped_oscillation(trace)
    assert abs(measured - period) <= 0.02 * period
    # After 10 periods: at least 90% of the amplitude (the largest value over the last period).
    last_period = np.abs(trace[-int(np.ceil(period)) :]).max()
    assert last_period >= 0.9 * 0.01
    assert last_period <= 1.0001 * 0.01


@pytest.fixture(scope="module")
def long_bar():
    """The bar of issue 50's energy measurement: 15 modes and 52 derivatives."""
    V, F = mdc.testing.bar(4, 4, 16, 1, 1, 4)
    return mdc.bake(V, F, modes=15, derivatives=52)


@pytest.mark.parametrize("fraction", [0.05, 0.1])
def test_large_undamped_swings_keep_their_energy(long_bar, fraction):
    """Swings of 5% and 10% of the bar's length, where the midpoint rule alone drifts either way (a
    one-way check ended 10 periods at 0.92 and 0.77 of the energy): the energy correction keeps
    the total, working both ways."""
    period = 12.0
    trace, energies, removed, added = free_motion(
        long_bar, int(10 * period) + 1, swing(long_bar, fraction), period=period, damping=0.0
    )
    assert np.abs(energies / energies[0] - 1).max() <= 0.005
    assert removed > 0.01 * energies[0] and added > 0.01 * energies[0]
    # Still the lowest mode's swing: its period within the nonlinear bar's own shift (32 substeps
    # give 11.92 and 11.70 frames), and most of its amplitude after 10 periods.
    measured, _ = damped_oscillation(trace)
    assert abs(measured - period) <= 0.03 * period
    amplitude = swing(long_bar, fraction)
    assert 0.9 * amplitude <= np.abs(trace[-int(period) :]).max() <= 1.0001 * amplitude
    # Damped, the energy only decreases.
    _, energies, *_ = free_motion(long_bar, 48, amplitude, damping=0.05)
    assert (np.diff(energies) <= 0).all() and energies[-1] < 0.5 * energies[0]


@pytest.mark.parametrize("damping", [0.02, 0.05, 0.2, 0.5])
def test_damping_ratio_gives_the_logarithmic_decrement(bar, damping):
    *_, basis = bar
    trace = released(basis, 48, damping=damping)
    period, decrement = damped_oscillation(trace)
    expected = 2 * np.pi * damping / np.sqrt(1 - damping**2)
    assert abs(decrement - expected) <= 0.1 * expected
    assert abs(period - 12.0 / np.sqrt(1 - damping**2)) <= 0.02 * 12


@pytest.fixture(scope="module")
def tube_bases():
    """The tube baked as a whole, with a painted stiffness, on a proxy, and as a region (its upper
    half)."""
    V, F = mdc.testing.cylinder(25, 40, radius=1.0, length=4.0)
    sizes = dict(modes=16, derivatives=30, ghost=400)
    upper = np.flatnonzero(V[:, 2] > 2.0)
    bases = {
        "whole": mdc.bake(V, F, **sizes),
        "painted": mdc.bake(
            V, F, **sizes, stiffness_weights=np.clip(V[:, 2] / 4, 0, 1), max_stiffness=20.0
        ),
        "proxy": mdc.bake(V, F, **sizes, proxy=400, proxy_above=500),
        "region": mdc.bake(V, F, **sizes, region=upper),
    }
    return V, F, upper, bases


@pytest.mark.parametrize("kind", ["whole", "painted", "proxy", "region"])
def test_every_kind_of_basis_keeps_the_period_and_follows_a_controller(tube_bases, kind):
    V, F, upper, bases = tube_bases
    basis = bases[kind]
    assert basis.on_proxy == (kind == "proxy")
    period, _ = damped_oscillation(released(basis, 25, damping=0.0))
    assert abs(period - 12.0) <= 0.02 * 12.0
    top = np.flatnonzero(V[:, 2] > 4 - 1e-9)
    sim = mdc.Simulation(basis, [top], pull=100.0)
    for frame in range(1, 13):
        X = sim.step([rigid([1, 0, 0], np.radians(5 * frame), V[top].mean(axis=0))])
        assert np.isfinite(X).all() and X.shape == V.shape
    assert np.abs(X[top] - V[top]).max() > 0.1  # it followed
    if kind == "region":
        outside = np.setdiff1d(np.arange(len(V)), upper)
        assert np.array_equal(X[outside], V[outside].astype(np.float32))


def random_controller(rng, centre):
    """A random rigid move of the controller: turns up to 150° about a random axis, jumps up to about
    a bar's length."""
    return rigid(
        rng.normal(size=3), rng.uniform(0, np.radians(150)), centre, rng.normal(scale=1.5, size=3)
    )


def test_fast_random_controllers_then_settling_to_the_pose(tube):
    V, F, handles, basis = tube
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    sim = mdc.Simulation(basis, handles, pull=100.0, damping=0.3)
    rng = np.random.default_rng(7)
    top_centre = V[handles[1]].mean(axis=0)
    for _ in range(60):
        T = random_controller(rng, top_centre)
        X = sim.step([np.eye(4), T])
        assert np.isfinite(X).all() and np.isfinite(sim.energy())
        # No blow-up: the mesh stays within a few diagonals of its controllers.
        assert np.abs(X - V.mean(axis=0)).max() <= 5 * diagonal
    # The controllers stop in a moderate pose (a strong one has several equilibria, and where the
    # motion ends up among them is its own business): no more work is done on the mesh, and its
    # energy never grows.
    T = rigid([1, 0, 0], np.radians(60), top_centre, [0.5, 0, -0.5])
    sim.step([np.eye(4), T])
    energies = [sim.energy()]
    for _ in range(240):
        X = sim.step([np.eye(4), T])
        energies.append(sim.energy())
    energies = np.array(energies)
    assert (np.diff(energies) <= 1e-12 * energies[0]).all()
    assert energies[-1] < energies[0]
    # It settles where the quasi-static solver poses it.
    solver = mdc.ReducedSolver(basis, handles, pull=100.0)
    solver.set_transforms([np.eye(4), T])
    assert solver.solve(max_iterations=500, tolerance=1e-12)["converged"]
    assert np.abs(X - solver.positions()).max() <= 1e-4 * diagonal


def test_a_run_is_deterministic_and_its_state_reloads_bit_identical(tube):
    V, F, handles, basis = tube
    rng = np.random.default_rng(3)
    centre = V[handles[1]].mean(axis=0)
    moves = [[np.eye(4), random_controller(rng, centre)] for _ in range(16)]

    def run(sim, transforms):
        return [sim.step(T).copy() for T in transforms]

    first, second = (
        mdc.Simulation(basis, handles, pull=100.0),
        mdc.Simulation(basis, handles, pull=100.0),
    )
    a, b = run(first, moves), run(second, moves)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    assert all(np.array_equal(x, y) for x, y in zip(first.state, second.state))
    # A cache: the state after frame 8 (the end of a block of BFGS's memory: memory_frames frames
    # from the start), reloaded into a fresh simulation, continues bit-identical.
    assert first.memory_frames == mdc.SIMULATION_OPTIONS["memory_frames"].default == 8
    cached = mdc.Simulation(basis, handles, pull=100.0)
    run(cached, moves[:8])
    q, v = cached.state
    reloaded = mdc.Simulation(basis, handles, pull=100.0)
    reloaded.set_state(q, v, moves[7])
    assert all(np.array_equal(x, y) for x, y in zip(reloaded.state, (q, v)))
    assert reloaded.energy() == cached.energy()
    assert np.array_equal(reloaded.positions(), cached.positions())
    assert all(np.array_equal(x, y) for x, y in zip(run(reloaded, moves[8:]), a[8:]))
    # A cached frame shown by positions_of: the positions set_state would map, the state untouched.
    state, energy = reloaded.state, reloaded.energy()
    assert np.array_equal(reloaded.positions_of(q), cached.positions())
    assert (
        all(np.array_equal(x, y) for x, y in zip(reloaded.state, state))
        and reloaded.energy() == energy
    )
    with pytest.raises(ValueError, match="q"):
        reloaded.positions_of(q[:-1])
    # Its displacement alone (a rig's display shows it): U q, the positions less the rest up to
    # float rounding, exactly zero at q = 0.
    rest = basis.rest.astype(np.float32)
    size = np.ptp(basis.rest, axis=0).max()
    assert np.abs(reloaded.displacement_of(q) - (cached.positions() - rest)).max() < 1e-6 * size
    assert not reloaded.displacement_of(np.zeros_like(q)).any()
    with pytest.raises(ValueError, match="q"):
        reloaded.displacement_of(q[:-1])
    # Its own state set again, as playback does before each step, continues the same.
    energy = cached.energy()
    cached.set_state(q, v, moves[7])
    assert cached.energy() == energy
    assert all(np.array_equal(x, y) for x, y in zip(run(cached, moves[8:]), a[8:]))


def test_bfgs_memory_spans_blocks_of_frames_and_a_frame_inside_one_is_reached_again(tube):
    V, F, handles, basis = tube
    centre = V[handles[1]].mean(axis=0)
    moves = [[np.eye(4), rigid([1, 0, 0], np.radians(5) * k, centre)] for k in range(1, 13)]
    played = mdc.Simulation(basis, handles, memory_frames=4, pull=100.0)
    states, evaluations = [(played.state, [np.eye(4)] * 2)], 0
    for k, T in enumerate(moves):
        played.advance(T)
        evaluations += played.stats["evaluations"]
        assert played.remembered_frames == k % 4 + 1 and played.stats["converged"]
        states.append((played.state, T))
    # Frame 7 from the cached state of frame 6 in a simulation that does not remember frames 5 and 6
    # (a set_state of a state not its own forgets): a different minimisation, the same motion
    # within the solver's tolerance.
    jumped = mdc.Simulation(basis, handles, memory_frames=4, pull=100.0)
    jumped.set_state(*states[6][0], states[6][1])
    assert jumped.remembered_frames == 0
    jumped.advance(moves[6])
    assert jumped.stats["converged"] and not np.array_equal(jumped.state[0], states[7][0][0])
    assert np.abs(jumped.state[0] - states[7][0][0]).max() < 1e-4 * np.abs(states[7][0][0]).max()
    # From the block's first state (frame 4), with the memory forgotten, frames 5 and 6 stepped again:
    # frame 7 is the same bits as played.
    jumped.set_state(*states[4][0], states[4][1])
    jumped.forget()
    for T in moves[4:6]:
        jumped.advance(T)
    assert all(np.array_equal(x, y) for x, y in zip(jumped.state, states[6][0]))
    jumped.set_state(*states[6][0], states[6][1])  # its own state: the memory is kept
    assert jumped.remembered_frames == 2
    jumped.advance(moves[6])
    assert all(np.array_equal(x, y) for x, y in zip(jumped.state, states[7][0]))
    # memory_frames=1: each frame from the rest Hessian, a function of the state it starts from
    # alone, at more evaluations.
    fresh = mdc.Simulation(basis, handles, memory_frames=1, pull=100.0)
    fresh_states, fresh_evaluations = [], 0
    for T in moves:
        fresh.advance(T)
        fresh_evaluations += fresh.stats["evaluations"]
        assert fresh.remembered_frames == 1
        fresh_states.append(fresh.state)
    alone = mdc.Simulation(basis, handles, memory_frames=1, pull=100.0)
    alone.set_state(*fresh_states[5], moves[5])
    alone.advance(moves[6])
    assert all(np.array_equal(x, y) for x, y in zip(alone.state, fresh_states[6]))
    assert evaluations < fresh_evaluations
    with pytest.raises(ValueError, match="memory_frames"):
        mdc.Simulation(basis, handles, memory_frames=0)


@pytest.mark.parametrize(
    "options",
    [
        {"fps": 1e-300},
        {"fps": 1e-157, "substeps": 64},
        {"fps": 1e-150, "period": 1e6, "damping": 1.0, "substeps": 64},
    ],
)
def test_options_beyond_double_precision_together_are_refused(bar, options):
    """Each option within its range, together they make the mass scale, the damping or the
    substep overflow (ρ grows as fps⁻², h² as fps⁻²): refused naming them, for Simulation and
    Inbetween alike, not a simulation of infinities."""
    V, F, basis = bar
    with pytest.raises(ValueError, match=r"fps = .*period = .*substeps = .*beyond double"):
        mdc.Simulation(basis, [], **options)
    handles = [np.flatnonzero(V[:, 2] < 0.3)]
    with pytest.raises(ValueError, match=r"fps = .*period = .*substeps = .*beyond double"):
        mdc.Inbetween(basis, handles, [(0, [np.eye(4)]), (3, [np.eye(4)])], **options)
    fine = mdc.Simulation(basis, [], **{**options, "fps": 1e-100})
    assert np.isfinite(fine.mass_scale) and fine.mass_scale > 0


def test_parameters_are_defined_once_and_checked(bar):
    V, F, basis = bar
    assert (
        mdc.SIMULATION_OPTIONS["period"].default == 12.0
        and mdc.SIMULATION_OPTIONS["substeps"].default == 2
    )
    sim = mdc.Simulation(basis, [])
    assert sim.dimension == basis.vectors.shape[1] and sim.num_handles == 0
    X = sim.step([])
    assert X.shape == V.shape and X.dtype == np.float32
    assert np.array_equal(X, sim.positions())
    for name, value in [
        ("period", 2.0),
        ("damping", -0.1),
        ("damping", 1.5),
        ("fps", 0.0),
        ("pull", -1.0),
        ("period", float("nan")),
    ]:
        with pytest.raises(ValueError, match=name):
            mdc.Simulation(basis, [], **{name: value})
    with pytest.raises(ValueError, match="substeps"):
        mdc.Simulation(basis, [], substeps=0)
    with pytest.raises(ValueError, match="basis"):
        mdc.Simulation(V, [])
    with pytest.raises(ValueError, match=r"handles\[0\]"):
        mdc.Simulation(basis, [[len(V)]])
    held = mdc.Simulation(basis, [[0, 1, 2]], pull=100.0)
    with pytest.raises(ValueError, match="transforms"):
        held.step([])
    sheared = np.eye(4)
    sheared[0, 1] = 0.5
    with pytest.raises(ValueError, match=r"transforms\[0\]"):
        held.step([sheared])
    r = sim.dimension
    with pytest.raises(ValueError, match="q"):
        sim.set_state(np.zeros(r + 1), np.zeros(r))
    with pytest.raises(ValueError, match="v"):
        sim.set_state(np.zeros(r), np.full(r, np.nan))
    with pytest.raises(ValueError, match="q"):
        sim.set_state(np.full(r, 1e300), np.zeros(r))


def test_an_unconverged_step_says_so_and_stays_finite(tube):
    V, F, handles, basis = tube
    sim = mdc.Simulation(basis, handles, max_iterations=1, pull=100.0)
    rng = np.random.default_rng(5)
    centre = V[handles[1]].mean(axis=0)
    stats = []
    for _ in range(10):
        X = sim.step([np.eye(4), random_controller(rng, centre)])
        assert np.isfinite(X).all() and np.isfinite(sim.energy())
        stats.append(sim.stats)
    assert not all(s["converged"] for s in stats)
    assert all(
        s["substeps"] == 2 and s["iterations"] <= 2 * (1 + s["implicit_euler"]) for s in stats
    )
    # Unconverged steps cannot create energy either: with the controllers still it never grows.
    still = [np.eye(4), random_controller(rng, centre)]
    sim.step(still)
    energies = [sim.energy()]
    for _ in range(40):
        sim.step(still)
        energies.append(sim.energy())
    assert (np.diff(energies) <= 1e-12 * energies[0]).all() and energies[-1] < energies[0]


def test_the_motion_in_frames_does_not_depend_on_the_frame_rate(bar):
    """Period and damping are in frames: at another fps the frames are the same (velocities, per
    second, scale with it)."""
    *_, basis = bar
    traces = [released(basis, 30, fps=fps) for fps in (24.0, 30.0)]
    assert np.allclose(traces[0], traces[1], rtol=0, atol=1e-9 * np.abs(traces[0]).max())
