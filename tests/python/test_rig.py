"""Secondary motion on a rig through the Python API: mdc.Simulation(..., rig=W), step(bones=B) and
mdc.skin (cpp/solve/rig_forces.h). A tube along z on a chain of three bones, weighted linearly
between the bones' centres, attached at its bottom."""

import os
import subprocess
import sys

import numpy as np
import pytest
import scipy.sparse

import modal_deform.core as mdc

LENGTH = 4.0
JOINTS = (LENGTH / 3, 2 * LENGTH / 3)


def chain_weights(z, bones, length=LENGTH):
    """(n, bones): a partition of unity along z, linear between the bones' centres."""
    centres = (np.arange(bones) + 0.5) * length / bones
    W = np.zeros((len(z), bones))
    for i, zi in enumerate(z):
        if zi <= centres[0]:
            W[i, 0] = 1
        elif zi >= centres[-1]:
            W[i, -1] = 1
        else:
            k = np.searchsorted(centres, zi) - 1
            t = (zi - centres[k]) / (centres[k + 1] - centres[k])
            W[i, k], W[i, k + 1] = 1 - t, t
    return W


def translation(d):
    T = np.eye(4)
    T[:3, 3] = d
    return T


def rotation_x(angle, centre=(0, 0, 0)):
    """A rotation by `angle` about the x axis through `centre`."""
    c, s = np.cos(angle), np.sin(angle)
    T = np.eye(4)
    T[1:3, 1:3] = [[c, -s], [s, c]]
    T[:3, 3] = np.asarray(centre, float) - T[:3, :3] @ centre
    return T


def chain(world=np.eye(4), bends=(0.0, 0.0)):
    """The three bones' skinning matrices: the whole chain moved by `world`, the second and third
    bones bent about x at the joints by bends[0], and bends[0] + bends[1]."""
    B0 = world
    B1 = B0 @ rotation_x(bends[0], (0, 0, JOINTS[0]))
    B2 = B1 @ rotation_x(bends[1], (0, 0, JOINTS[1]))
    return np.array([B0, B1, B2])


def smooth(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


@pytest.fixture(scope="module")
def tube():
    V, F = mdc.testing.cylinder(25, 40, radius=1.0, length=LENGTH)
    basis = mdc.bake(V, F, modes=16, derivatives=30, ghost=400)
    W = chain_weights(V[:, 2], 3)
    attach = np.flatnonzero(V[:, 2] < 0.3)
    top = np.flatnonzero(V[:, 2] > LENGTH - 1e-9)
    return V, basis, W, attach, top


def tip_displacement(X, V, top):
    """The mean displacement of the top ring in rest space."""
    return (X[top] - V[top]).mean(axis=0)


def run(sim, V, top, frames):
    """Steps `sim` through `frames` (bones per frame): the tip's rest-space displacement a frame."""
    return np.array([tip_displacement(sim.step([np.eye(4)], bones=B), V, top) for B in frames])


def sign_changes(trace):
    s = np.sign(trace[np.abs(trace) > 1e-3 * np.abs(trace).max()])
    return int(np.count_nonzero(s[1:] != s[:-1]))


def test_still_rig_shows_the_skinned_rest_and_settles_back_to_it(tube):
    """Posed from the first frame: no kick, the displacement is exactly zero; after a jump and a
    stop, it settles back to within 1e-6 of the diagonal (damping 0.05)."""
    V, basis, W, attach, top = tube
    sim = mdc.Simulation(basis, [attach], rig=W, damping=0.05)
    posed = chain(rotation_x(0.4) @ translation([1, 2, 3]), bends=(0.5, -0.3))
    for _ in range(5):
        X = sim.step([np.eye(4)], bones=posed)
    q, v = sim.state
    assert not q.any() and not v.any()
    np.testing.assert_array_equal(mdc.skin(X, W, posed), mdc.skin(V.astype(np.float32), W, posed))
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    for f in range(20):
        world = translation([2 * smooth(f / 10), 0, 0]) @ rotation_x(0.4) @ translation([1, 2, 3])
        X = sim.step([np.eye(4)], bones=chain(world, (0.5, -0.3)))
    assert np.abs(X - V).max() > 0.05 * diagonal
    for _ in range(600):
        X = sim.step([np.eye(4)], bones=chain(world, (0.5, -0.3)))
    assert np.abs(X - V).max() <= 1e-6 * diagonal


def test_a_jump_makes_the_free_end_lag_overshoot_and_settle(tube):
    V, basis, W, attach, top = tube
    sim = mdc.Simulation(basis, [attach], rig=W)
    frames = [chain(translation([2 * smooth((f - 5) / 10), 0, 0])) for f in range(200)]
    trace = run(sim, V, top, frames)[:, 0]
    assert np.abs(trace[:5]).max() < 1e-6  # still before the jump (float32 positions)
    assert trace[5:10].min() < -0.1 and trace[5:10].max() <= 0  # lags while it speeds up
    assert trace[12:20].max() > 0.3  # overshoots as it stops
    assert sign_changes(trace[15:]) >= 6  # oscillates
    assert np.abs(trace[-12:]).max() < 0.2 * np.abs(trace).max()  # and settles


def test_a_turn_makes_the_free_end_lag_and_overshoot(tube):
    """The whole rig swung by 45 degrees about x through the base: the tip moves along −y in rest
    space, so it lags along +y, then overshoots along −y."""
    V, basis, W, attach, top = tube
    sim = mdc.Simulation(basis, [attach], rig=W)
    frames = [chain(rotation_x(np.pi / 4 * smooth((f - 2) / 8))) for f in range(60)]
    trace = run(sim, V, top, frames)[:, 1]
    assert trace[2:6].max() > 0.05 and trace[2:6].min() >= 0
    assert trace[8:16].min() < -0.1
    assert sign_changes(trace[8:]) >= 3


def test_a_chain_bent_fast_gives_its_free_end_follow_through(tube):
    """The upper two bones bent by 60 degrees in 4 frames, then held: the tip moves along −y in its
    bone's frame; it lags behind (+y) while the bend speeds up, follows through (−y) after the
    bend stops, and settles."""
    V, basis, W, attach, top = tube
    sim = mdc.Simulation(basis, [attach], rig=W)
    bend = [np.radians(60) * smooth((f - 2) / 4) for f in range(300)]
    trace = run(sim, V, top, [chain(bends=(a, 0.0)) for a in bend])[:, 1]
    assert trace[2:4].max() > 0 and trace[2:4].min() >= 0
    assert trace[6:14].min() < -0.1
    assert np.abs(trace[-12:]).max() < 0.1 * np.abs(trace).max()


def test_identity_bones_are_the_simulation_without_a_rig(tube):
    """A free body released from a deformed state: with identity bones (or any still pose) the same
    frames, bit for bit, as without a rig; with handles, a still posed rig as identity bones."""
    V, basis, W, attach, top = tube
    plain = mdc.Simulation(basis, [])
    rigged = mdc.Simulation(basis, [], rig=W)
    assert rigged.mass_scale == plain.mass_scale  # no handles: the same lowest mode
    start = 0.05 * plain.lowest_mode
    for sim in (plain, rigged):
        sim.set_state(start, np.zeros_like(start))
    identity = np.array([np.eye(4)] * 3)
    for _ in range(20):
        np.testing.assert_array_equal(plain.step([]), rigged.step([], bones=identity))
    np.testing.assert_array_equal(plain.state[0], rigged.state[0])

    held = mdc.Simulation(basis, [attach, top], rig=W)
    posed = mdc.Simulation(basis, [attach, top], rig=W)
    pose = chain(rotation_x(0.3), (0.2, 0.4))
    for f in range(15):
        T = [np.eye(4), translation([0.05 * f, 0, 0])]
        np.testing.assert_array_equal(held.step(T, bones=identity), posed.step(T, bones=pose))


def test_frames_are_the_same_bits_however_reached(tube):
    """Stepping through, or restoring a cached state (with its rig_state) mid-way and stepping on."""
    V, basis, W, attach, top = tube
    frames = [
        chain(translation([smooth((f - 3) / 6), 0, 0]), (np.radians(40) * smooth((f - 8) / 5), 0))
        for f in range(30)
    ]
    through = mdc.Simulation(basis, [attach], rig=W, memory_frames=1)
    assert through.rig_state is None
    results, cached = [], {}
    for f, B in enumerate(frames):
        results.append(through.step([np.eye(4)], bones=B).copy())
        cached[f] = (*through.state, through.rig_state)
    np.testing.assert_array_equal(cached[10][2], np.array([frames[9], frames[10]]))
    restored = mdc.Simulation(basis, [attach], rig=W, memory_frames=1)
    q, v, rig_state = cached[10]
    restored.set_state(q, v, [np.eye(4)], bones=rig_state)
    for f in range(11, 30):
        np.testing.assert_array_equal(restored.step([np.eye(4)], bones=frames[f]), results[f])
    # A posed first frame given by set_state: the rig was still there before.
    first = mdc.Simulation(basis, [attach], rig=W)
    first.set_state(np.zeros(first.dimension), np.zeros(first.dimension), bones=frames[12])
    np.testing.assert_array_equal(first.rig_state, np.array([frames[12], frames[12]]))
    first.step([np.eye(4)], bones=frames[12])
    assert not first.state[0].any()


def test_a_state_set_without_bones_has_no_rig_history(tube):
    """set_state(q, v) without bones on a rig: the next step takes the rig as still in the pose it
    is given (as a fresh simulation's first), whatever the simulation stepped before, so the
    frames from there are the same bits however the simulation got there; with the cached
    rig_state, the original run's."""
    V, basis, W, attach, top = tube
    frames = [chain(translation([0.05 * f * f, 0, 0]), (0.04 * f, 0)) for f in range(16)]
    run = mdc.Simulation(basis, [attach], rig=W, memory_frames=1)
    results, cached = [], {}
    for f, B in enumerate(frames):
        results.append(run.step([np.eye(4)], bones=B).copy())
        cached[f] = (*run.state, run.rig_state)
    q, v, rig_state = cached[8]
    fresh = mdc.Simulation(basis, [attach], rig=W, memory_frames=1)
    histories = []
    for sim in (run, fresh):
        sim.set_state(q, v, [np.eye(4)])
        histories.append(sim.rig_state)
    for B in frames[9:]:
        np.testing.assert_array_equal(
            run.step([np.eye(4)], bones=B), fresh.step([np.eye(4)], bones=B)
        )
    assert histories == [None, None]
    assert not np.array_equal(fresh.state[0], cached[15][0])  # the rig's motion was dropped
    run.set_state(q, v, [np.eye(4)], bones=rig_state)
    for f in range(9, 16):
        np.testing.assert_array_equal(run.step([np.eye(4)], bones=frames[f]), results[f])


def test_the_period_is_the_lowest_mode_as_attached(tube):
    V, basis, W, attach, top = tube
    period = 12.0
    sim = mdc.Simulation(basis, [attach], rig=W, period=period, damping=0.0)
    plain = mdc.Simulation(basis, [attach], period=period, damping=0.0)
    assert not np.isclose(sim.mass_scale, plain.mass_scale)
    mode = sim.lowest_mode
    sim.set_state(1e-3 * mode, np.zeros_like(mode))
    still = chain()
    trace = np.array(
        [sim.step([np.eye(4)], bones=still) is not None and sim.state[0] @ mode for _ in range(61)]
    )
    crossings = np.flatnonzero(np.sign(trace[1:]) != np.sign(trace[:-1]))
    # Linear interpolation of the zero crossings: half periods.
    times = crossings + trace[crossings] / (trace[crossings] - trace[crossings + 1])
    assert abs(2 * np.diff(times).mean() - period) < 0.03 * period


def test_skin_is_linear_blend_skinning_with_affine_bones(tube):
    V, basis, W, attach, top = tube
    rng = np.random.default_rng(3)
    B = np.array([np.eye(4)] * 3)
    B[:, :3, :] = rng.normal(size=(3, 3, 4)) + 2 * np.eye(3, 4)  # scaled and sheared
    X = V + 0.01 * rng.normal(size=V.shape)
    expected = np.zeros_like(V)
    for i in range(len(V)):
        for b in range(3):
            expected[i] += W[i, b] * (B[b, :3, :3] @ X[i] + B[b, :3, 3])
    np.testing.assert_allclose(mdc.skin(X, W, B), expected, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(mdc.skin(X, scipy.sparse.csc_matrix(W), B), expected, atol=1e-12)


def test_a_scaled_or_sheared_object_moves_its_rest_space_the_same(tube):
    """The pull-back by L⁻¹: a world matrix S (scale and shear) applied to every bone scales the
    world motion and its acceleration alike, so the displacement in rest space is the same (with
    Lᵀ it would scale by S's square)."""
    V, basis, W, attach, top = tube
    S = np.diag([2.0, 0.5, 1.5, 1.0])
    S[0, 1] = 0.3
    sims = [mdc.Simulation(basis, [attach], rig=W) for _ in range(2)]
    for f in range(12):
        B = chain(translation([smooth(f / 8), 0, 0]), (np.radians(30) * smooth(f / 6), 0))
        X = [sims[0].step([np.eye(4)], bones=B), sims[1].step([np.eye(4)], bones=S @ B)]
        np.testing.assert_allclose(
            sims[1].rig_acceleration,
            sims[0].rig_acceleration,
            rtol=1e-9,
            atol=1e-9 * np.abs(sims[0].rig_acceleration).max(),
        )
        np.testing.assert_allclose(X[1], X[0], atol=1e-5)


def test_many_bones_and_bones_without_vertices(tube):
    V, basis, W, attach, top = tube
    W200 = np.hstack([chain_weights(V[:, 2], 199), np.zeros((len(V), 1))])  # the last: no vertex
    sim = mdc.Simulation(basis, [attach], rig=scipy.sparse.csr_matrix(W200))
    assert sim.num_bones == 200
    for f in range(6):
        B = np.array([translation([0.2 * f * f, 0, 0])] * 200)
        X = sim.step([np.eye(4)], bones=B)
    assert np.isfinite(X).all() and np.abs(X - V).max() > 0


def test_bad_rigs_are_refused_with_a_message(tube):
    V, basis, W, attach, top = tube
    n = len(V)

    def refused(rig, match):
        with pytest.raises(ValueError, match=match):
            mdc.Simulation(basis, [attach], rig=rig)

    refused(W[:-1], "rows|vertices|one row per vertex")
    refused(W[:, 0], "matrix|shape")
    refused(np.zeros((n, 0)), "bone")
    refused(W * 1.01, "sum to")
    negative = W.copy()
    negative[0, :2] = [1.5, -0.5]
    refused(negative, "negative")
    unweighted = W.copy()
    unweighted[7] = 0
    refused(unweighted, "vertex 7 is weighted to no bone")
    nan = W.copy()
    nan[3, 0] = np.nan
    refused(nan, "not finite")
    with pytest.raises(ValueError, match="sum to"):
        mdc.skin(V, W * 0.5, chain())

    sim = mdc.Simulation(basis, [attach], rig=W)
    bad = chain()
    with pytest.raises(ValueError, match="required"):
        sim.step([np.eye(4)])
    with pytest.raises(ValueError, match="one per bone"):
        sim.step([np.eye(4)], bones=bad[:2])
    with pytest.raises(ValueError, match="one per bone"):
        sim.step([np.eye(4)], bones=bad[:, :3, :])
    nonfinite = bad.copy()
    nonfinite[1, 0, 3] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        sim.step([np.eye(4)], bones=nonfinite)
    singular = bad.copy()
    singular[2, :3, 2] = 0
    with pytest.raises(ValueError, match="singular"):
        sim.step([np.eye(4)], bones=singular)
    projective = bad.copy()
    projective[0, 3, 0] = 0.1
    with pytest.raises(ValueError, match="affine"):
        sim.step([np.eye(4)], bones=projective)
    with pytest.raises(ValueError, match="singular"):
        mdc.skin(V, W, singular)
    assert sim.rig_state is None  # nothing taken from a refused frame
    with pytest.raises(ValueError, match="without a rig"):
        mdc.Simulation(basis, [attach]).step([np.eye(4)], bones=bad)


def test_a_refused_frame_leaves_the_simulation_as_it_was(tube):
    """Bones non-finite, not affine or beyond the coordinates the core takes (kMaxCoordinate, 1e15:
    their second difference times fps² would overflow the rig's acceleration) are refused naming
    the bone, before the state changes: the next frame is the same bits as without the refused
    one."""
    V, basis, W, attach, top = tube
    frames = [chain(translation([0.1 * f * f, 0, 0]), (0.05 * f, 0)) for f in range(6)]
    sims = [mdc.Simulation(basis, [attach], rig=W) for _ in range(2)]
    for sim in sims:
        for B in frames[:4]:
            sim.step([np.eye(4)], bones=B)
    for entry, value, match in [
        ((1, 0, 3), np.nan, "non-finite"),
        ((1, 3, 2), 0.5, "affine"),
        ((1, 0, 3), 2e15, "beyond"),
        ((1, 2, 1), -1e300, "beyond"),
        ((1, 0, 0), 1e200, "beyond"),
    ]:
        bad = frames[4].copy()
        bad[entry] = value
        with pytest.raises(ValueError, match=rf"bones\[1\].*{match}"):
            sims[1].step([np.eye(4)], bones=bad)
    for B in frames[4:]:
        np.testing.assert_array_equal(
            sims[1].step([np.eye(4)], bones=B), sims[0].step([np.eye(4)], bones=B)
        )
    for a, b in zip(sims[0].state, sims[1].state):
        np.testing.assert_array_equal(a, b)
    np.testing.assert_array_equal(sims[0].rig_acceleration, sims[1].rig_acceleration)


def test_sparse_weights_naming_no_column_are_refused(tube):
    V, basis, W, attach, top = tube
    n = len(V)
    rows = np.arange(n + 1, dtype=np.int32)
    for column in (5_000_000, -7):
        built = scipy.sparse.csr_matrix(
            (np.ones(n), np.full(n, column, np.int32), rows), shape=(n, 3)
        )
        with pytest.raises(ValueError, match="rig"):
            mdc.Simulation(basis, [attach], rig=built)
        with pytest.raises(ValueError, match="rig"):
            mdc.skin(V, built, chain())


def test_the_rig_needs_no_scipy():
    # Blender's Python has NumPy but no SciPy: the core must import and run a rig without it.
    code = (
        "import sys; sys.modules['scipy'] = None\n"
        "import numpy as np, modal_deform.core as mdc\n"
        "V, F = mdc.testing.cylinder(8, 10, radius=1.0, length=4.0)\n"
        "W = np.c_[1 - V[:, 2] / 4, V[:, 2] / 4]\n"
        "sim = mdc.Simulation(mdc.bake(V, F, modes=10, derivatives=4, ghost=60), [[0, 1, 2]], rig=W)\n"
        "B = np.repeat(np.eye(4)[None], 2, axis=0)\n"
        "X = sim.step([np.eye(4)], bones=B)\n"
        "assert np.allclose(mdc.skin(X, W, B), X)\n"
    )
    subprocess.run([sys.executable, "-c", code], check=True, env=dict(os.environ))
