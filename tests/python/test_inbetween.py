"""Physics in-betweens through the Python API: mdc.Inbetween (cpp/solve/inbetween.h)."""

import warnings

import numpy as np
import pytest
from support.inbetween import free_motion_keys
from support.poses import translation

import modal_deform.core as mdc


@pytest.fixture(scope="module")
def bar():
    """A closed bar held at both ends by handles (the 8% of its length at each end)."""
    V, F = mdc.testing.bar(4, 4, 16, 1, 1, 4)
    handles = [np.flatnonzero(V[:, 2] < 0.3), np.flatnonzero(V[:, 2] > 3.7)]
    return V, F, handles, mdc.bake(V, F, modes=12, derivatives=20, ghost=300)


def diagonal(V):
    return float(np.linalg.norm(np.ptp(V, axis=0)))


def two_keys(amplitude=0.05):
    """The far end moved sideways by `amplitude` at frame 6, back at 12; the near end held."""
    return [
        (0, [np.eye(4), np.eye(4)]),
        (6, [np.eye(4), translation([amplitude, 0, 0])]),
        (12, [np.eye(4), np.eye(4)]),
    ]


def test_free_motion_is_reproduced(bar):
    """Keys taken from a motion Simulation produces freely, from rest in the first key's static
    pose: the in-betweens follow it (it needs no control), frame by frame."""
    V, _, handles, basis = bar
    start = [np.eye(4), translation([0.02, 0, 0])]
    positions, keys = free_motion_keys(basis, handles, start, 24, [0, 8, 16, 24])
    ib = mdc.Inbetween(basis, handles, keys)
    stats = ib.solve()
    assert stats["converged"]
    error = max(np.abs(ib.positions(f) - positions[f]).max() for f in range(25))
    # The motion's largest excursion from rest, for scale.
    excursion = np.abs(positions - V).max()
    # What differs is the start: posing's minimum at the first key's fits, not at `start`.
    assert error <= 1e-2 * excursion
    assert error <= 1e-4 * diagonal(V)
    assert stats["control"] <= 1e-6 * stats["initial_control"]


def key_error(V, handle, X, T):
    """How far the rigid fit of the handle's vertices at X takes them from where T puts them."""
    fit = mdc.rigid_fit(V[handle], X[handle])
    return np.linalg.norm(V[handle] @ (fit - T)[:3, :3].T + (fit - T)[:3, 3], axis=1).max()


def test_keys_are_hit_as_precisely_as_posing(bar):
    """Each keyed handle's rigid fit reaches its key at least as closely as posing's reaches the
    same transform."""
    V, _, handles, basis = bar
    keys = two_keys(0.2)
    keys[1][1][0] = translation([0, 0.1, 0])
    ib = mdc.Inbetween(basis, handles, keys)
    assert ib.solve()["converged"]
    for frame, transforms in keys:
        pose = mdc.ReducedSolver(basis, handles)
        pose.set_transforms(transforms)
        pose.solve(max_iterations=1000, tolerance=1e-8)
        for h, T in zip(handles, transforms):
            inbetween = key_error(V, h, ib.positions(frame), T)
            posing = key_error(V, h, pose.positions(), T)
            assert inbetween <= posing + 1e-5 * diagonal(V)
            assert inbetween <= 0.01 * diagonal(V)


def test_the_motion_moves_between_keys_and_holds_before_the_first(bar):
    V, _, handles, basis = bar
    keys = [(f + 5, T) for f, T in two_keys(0.1)]
    ib = mdc.Inbetween(basis, handles, keys)
    ib.solve()
    assert (ib.first_frame, ib.last_frame) == (5, 17)
    np.testing.assert_array_equal(ib.positions(0), ib.positions(5))
    q, v = ib.state(2)
    assert not v.any()
    # The far end goes out to the key and comes back: farthest near frame 11.
    far = [ib.positions(f)[handles[1], 0].mean() - V[handles[1], 0].mean() for f in range(5, 18)]
    assert abs(far[6] - 0.1) <= 1e-3
    assert 0 < far[3] < 0.1 and 0 < far[9] < 0.1


def test_after_the_last_key_it_is_simulation_from_there(bar):
    V, _, handles, basis = bar
    keys = two_keys()
    keys[-1] = (12, [None, translation([0.03, 0, 0])])  # the near end free at the last key
    ib = mdc.Inbetween(basis, handles, keys, damping=0.1)
    ib.solve()
    sim = mdc.Simulation(basis, handles, damping=0.1)
    q, v = ib.state(12)
    last = [np.eye(4), translation([0.03, 0, 0])]  # the near end's last key is frame 6's
    sim.set_state(q, v, last)
    for frame in range(13, 30):
        np.testing.assert_array_equal(sim.step(last), ib.positions(frame))
        np.testing.assert_array_equal(sim.state[0], ib.state(frame)[0])


def test_frames_are_the_same_bits_however_reached(bar):
    V, _, handles, basis = bar
    one = mdc.Inbetween(basis, handles, two_keys())
    two = mdc.Inbetween(basis, handles, two_keys())
    assert one.solve() is not None
    frames = [40, 3, 12, 25, 0, 7]
    first = {f: one.positions(f).copy() for f in frames}
    second = {f: two.positions(f).copy() for f in reversed(frames)}  # solves on demand
    for f in frames:
        np.testing.assert_array_equal(first[f], second[f])
    stats = one.solve()
    np.testing.assert_array_equal(one.positions(40), first[40])
    assert set(stats) >= {"converged", "iterations", "ms", "evaluations"}


def test_options_are_simulations(bar):
    for name, option in mdc.SIMULATION_OPTIONS.items():
        assert mdc.INBETWEEN_OPTIONS[name] == option
    V, _, handles, basis = bar
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ib = mdc.Inbetween(basis, handles, two_keys(), stiffness=500.0)
    assert any(issubclass(w.category, DeprecationWarning) for w in caught)
    assert ib.mass_scale == mdc.Simulation(basis, handles).mass_scale


def bent(T):
    T = T.copy()
    T[0, 0] = 1.5
    return T


@pytest.mark.parametrize(
    "keys, match",
    [
        ([], "at least one key"),
        (None, "at least one key"),
        ([(3, [np.eye(4), np.eye(4)]), (3, [np.eye(4), None])], "two keys at frame 3"),
        ([(-1, [np.eye(4), np.eye(4)])], "frame >= 0"),
        ([(1.5, [np.eye(4), np.eye(4)])], "integer frame"),
        ([(f, [np.eye(4), np.eye(4)]) for f in range(1000)], "at most"),
        ([(0, [np.eye(4), np.eye(4)]), (20000, [np.eye(4), None])], "spans more than"),
        ([(0, [np.eye(4)])], "expected 2 transforms"),
        ([(0, [np.eye(4), np.eye(3)])], "4x4"),
        ([(0, [np.eye(4), bent(np.eye(4))])], "handle 1: the 3 by 3 block is not a rotation"),
        ([(0, [np.eye(4), np.full((4, 4), np.nan)])], "handle 1 has non-finite entries"),
        ([(0, [None, None])], "keys no handle"),
        ([(0, "ab")], "expected real numbers"),
        (5, "expected a list"),
    ],
)
def test_bad_keys_are_refused(bar, keys, match):
    _, _, handles, basis = bar
    with pytest.raises(ValueError, match=match):
        mdc.Inbetween(basis, handles, keys)


def test_bad_frames_and_options_are_refused(bar):
    _, _, handles, basis = bar
    ib = mdc.Inbetween(basis, handles, two_keys())
    for frame in [-1, 2.0, None, True]:
        with pytest.raises(ValueError, match="frame"):
            ib.positions(frame)
    with pytest.raises(ValueError, match="frame"):
        ib.state(10**7)
    with pytest.raises(ValueError, match="period"):
        mdc.Inbetween(basis, handles, two_keys(), period=1.0)
    with pytest.raises(ValueError, match="handles"):
        mdc.Inbetween(basis, [], two_keys())


def test_rigid_fit_recovers_a_rigid_motion():
    rng = np.random.default_rng(3)
    points = rng.normal(size=(20, 3))
    T = translation([0.3, -0.2, 1.0])
    T[:3, :3] = np.linalg.qr(rng.normal(size=(3, 3)))[0] * np.sign(
        np.linalg.det(np.linalg.qr(rng.normal(size=(3, 3)))[0])
    )
    moved = points @ T[:3, :3].T + T[:3, 3]
    fitted = mdc.rigid_fit(points, moved)
    np.testing.assert_allclose(points @ fitted[:3, :3].T + fitted[:3, 3], moved, atol=1e-12)
