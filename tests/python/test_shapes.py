"""ShapeSpace (issue 52): shape keys blended as shapes, against the exact half shapes of a bar."""

import numpy as np
import pytest

import modal_deform.core as mdc

LENGTH = 4.0  # mdc.testing.bar's length along z


def bend(V, angle):
    """The bar bent in the x-z plane into a circular arc of `angle` radians, its centre line
    (x = 0.5) keeping its length, its base (z = 0) in place."""
    if angle == 0:
        return V.copy()
    R = LENGTH / angle
    rho = R - (V[:, 0] - 0.5)
    phi = V[:, 2] / R
    X = V.copy()
    X[:, 0] = 0.5 + R - rho * np.cos(phi)
    X[:, 2] = rho * np.sin(phi)
    return X


def twist(V, angle):
    """The bar twisted about its axis (x = y = 0.5) by `angle` radians from base to tip."""
    a = angle * V[:, 2] / LENGTH
    x, y = V[:, 0] - 0.5, V[:, 1] - 0.5
    X = V.copy()
    X[:, 0] = 0.5 + np.cos(a) * x - np.sin(a) * y
    X[:, 1] = 0.5 + np.sin(a) * x + np.cos(a) * y
    return X


def aligned_error(X, Y):
    """The largest vertex distance from X to Y after the rigid motion that best aligns them (the
    blend is placed like the linear blend, the exact shapes with their base fixed)."""
    cx, cy = X.mean(0), Y.mean(0)
    U, _, Vt = np.linalg.svd((X - cx).T @ (Y - cy))
    d = np.sign(np.linalg.det(Vt.T @ U.T))
    R = Vt.T @ np.diag([1, 1, d]) @ U.T
    return np.linalg.norm((X - cx) @ R.T + cy - Y, axis=1).max()


@pytest.fixture(scope="module")
def bar():
    return mdc.testing.bar(4, 4, 16)


@pytest.fixture(scope="module")
def basis(bar):
    return mdc.bake(*bar)


@pytest.fixture(scope="module")
def bent(bar, basis):
    V, F = bar
    return mdc.ShapeSpace(V, F, [bend(V, np.pi / 2)], basis=basis)


@pytest.fixture(scope="module")
def twisted(bar, basis):
    V, F = bar
    return mdc.ShapeSpace(V, F, [twist(V, np.pi)], basis=basis)


@pytest.fixture(scope="module")
def two_keys(bar, basis):
    V, F = bar
    return mdc.ShapeSpace(V, F, [bend(V, np.pi / 2), twist(V, np.pi)], basis=basis)


def test_weights_zero_give_the_basis_and_one_the_key(bar, two_keys):
    V, _ = bar
    tolerance = 1e-4 * LENGTH  # the map's 16-bit vectors and float32
    assert np.abs(two_keys.blend([0, 0]) - V).max() < tolerance
    assert np.abs(two_keys.blend([1, 0]) - bend(V, np.pi / 2)).max() < tolerance
    assert np.abs(two_keys.blend([0, 1]) - twist(V, np.pi)).max() < tolerance
    assert two_keys.stats["converged"]


def test_bend_blends_as_a_bend(bar, bent):
    V, _ = bar
    half = bend(V, np.pi / 4)
    X = bent.blend([0.5]).astype(np.float64)
    assert bent.stats["converged"]
    linear = 0.5 * (V + bend(V, np.pi / 2))
    assert aligned_error(X, half) < 0.01 * LENGTH
    assert aligned_error(linear, half) > 0.05 * LENGTH
    # The centre line keeps its length (the linear blend's chord shortens it).
    line = np.flatnonzero((V[:, 0] == 0.5) & (V[:, 1] == 0))
    line = line[np.argsort(V[line, 2])]

    def length(Y):
        return np.linalg.norm(np.diff(Y[line], axis=0), axis=1).sum()

    assert abs(length(X) / LENGTH - 1) < 0.01
    assert length(linear) / LENGTH < 0.97


def test_twist_blends_as_a_twist(bar, twisted):
    V, _ = bar
    half = twist(V, np.pi / 2)
    X = twisted.blend([0.5]).astype(np.float64)
    assert twisted.stats["converged"]
    linear = 0.5 * (V + twist(V, np.pi))
    assert aligned_error(X, half) < 0.015 * LENGTH
    assert aligned_error(linear, half) > 0.1 * LENGTH
    # The cross-section at the tip keeps its size; the linear blend collapses it to a segment.
    tip = np.flatnonzero(V[:, 2] == LENGTH)

    def spread(Y):
        P = Y[tip, :2] - Y[tip, :2].mean(0)
        return np.linalg.svd(P, compute_uv=False)

    rest = spread(V)
    assert np.allclose(spread(X), rest, rtol=0.03)
    assert spread(linear)[1] < 0.05 * rest[1]


def test_continuous_and_bit_identical(two_keys):
    first = two_keys.blend([0.3, 0.4]).copy()
    two_keys.blend([0.9, 0.1])  # another blend between: no state carries over
    assert np.array_equal(two_keys.blend([0.3, 0.4]), first)
    nearby = two_keys.blend([0.3 + 1e-4, 0.4])
    assert np.abs(nearby - first).max() < 1e-3 * LENGTH
    previous = None
    for w in np.linspace(0, 1, 11):
        X = two_keys.blend([w, 0.0]).copy()
        if previous is not None:
            assert np.abs(X - previous).max() < 0.2 * LENGTH
        previous = X


def test_no_rigid_drift(bar, bent):
    V, _ = bar
    key = bend(V, np.pi / 2)
    X = bent.blend([0.5])
    linear = 0.5 * (V + key)
    m = bent.basis.mass[:, None]
    centre = (m * X).sum(0) / m.sum()
    assert np.linalg.norm(centre - (m * linear).sum(0) / m.sum()) < 1e-3 * LENGTH


def test_out_and_stats(bar, bent):
    V, _ = bar
    out = np.zeros((len(V), 3), np.float32)
    assert bent.blend([0.25], out=out) is out
    stats = bent.stats
    assert set(stats) >= {"iterations", "converged", "ms", "solve_ms", "map_ms"}
    assert stats["ms"] > 0 and 0 < stats["map_ms"] <= stats["ms"]


def test_weights_outside_zero_one(bar, bent):
    V, _ = bar
    for w in (-0.5, 1.5):
        X = bent.blend([w])
        assert np.isfinite(X).all()
        assert "converged" in bent.stats


def test_storage_round_trip(bar, two_keys):
    arrays = two_keys.to_arrays()
    again = mdc.ShapeSpace.from_arrays(arrays)
    assert np.array_equal(again.blend([0.3, 0.4]), two_keys.blend([0.3, 0.4]))
    broken = dict(arrays)
    broken["key_coordinates"] = arrays["key_coordinates"][:-1]
    with pytest.raises(ValueError, match="coordinates"):
        mdc.ShapeSpace.from_arrays(broken)
    broken = dict(arrays)
    broken["key_coordinates"] = arrays["key_coordinates"].copy()
    broken["key_coordinates"][0, 0] = np.nan
    with pytest.raises(ValueError, match="coordinates"):
        mdc.ShapeSpace.from_arrays(broken)
    broken = dict(arrays)
    del broken["key_residuals"]
    with pytest.raises(ValueError, match="key_residuals"):
        mdc.ShapeSpace.from_arrays(broken)
    with pytest.raises(ValueError, match="base_dimension"):
        mdc.ShapeSpace.from_arrays({**arrays, "base_dimension": np.array(10**6, np.int32)})


def test_bad_input(bar, basis, bent):
    V, F = bar
    with pytest.raises(ValueError, match=r"shapes\[1\].*vertices"):
        mdc.ShapeSpace(V, F, [V, V[:-1]], basis=basis)
    with pytest.raises(ValueError, match="at least one"):
        mdc.ShapeSpace(V, F, [], basis=basis)
    nan_key = V.copy()
    nan_key[3, 1] = np.nan
    with pytest.raises(ValueError, match=r"shapes\[0\]"):
        mdc.ShapeSpace(V, F, [nan_key], basis=basis)
    with pytest.raises(ValueError, match="another mesh"):
        mdc.ShapeSpace(V * 2, F, [V], basis=basis)
    with pytest.raises(ValueError, match=r"weights\[0\]"):
        bent.blend([np.nan])
    with pytest.raises(ValueError, match="one per key"):
        bent.blend([0.5, 0.5])
    with pytest.raises(ValueError, match=r"weights\[0\]"):
        bent.blend([1e6])


def test_key_that_collapses_the_mesh(bar, basis):
    """A key flattened onto a plane (triangles of no area) or onto a point: the space takes it (a
    zero-size element of a key adds nothing to its term's blend), the key is reproduced and the
    blend toward it is finite, its stats saying whether it converged."""
    V, F = bar
    flat = V.copy()
    flat[:, 0] = 0
    for key in (flat, np.full_like(V, 0.5)):
        space = mdc.ShapeSpace(V, F, [key], basis=basis)
        assert np.abs(space.blend([1.0]) - key).max() < 1e-4 * LENGTH
        assert np.isfinite(space.blend([0.5])).all()
        assert isinstance(space.stats["converged"], bool)


def test_key_equal_to_the_basis_and_repeated_keys(bar, basis):
    V, F = bar
    key = bend(V, np.pi / 2)
    space = mdc.ShapeSpace(V, F, [V, key, key], basis=basis)
    assert space.dimension == basis.dimension + 1  # the basis and the repeat add nothing
    assert np.abs(space.blend([1, 0, 0]) - V).max() < 1e-4 * LENGTH
    both = space.blend([0, 0.25, 0.25]).copy()
    assert np.abs(both - space.blend([0, 0.5, 0])).max() < 1e-3 * LENGTH


def test_key_folded_through_itself(bar, basis):
    """A key that mirrors the mesh through a plane (every triangle turned over): a valid rest, and
    a blend toward it does not crash (what it converges to is the energy's business)."""
    V, F = bar
    mirrored = V.copy()
    mirrored[:, 0] = 1.0 - mirrored[:, 0]
    space = mdc.ShapeSpace(V, F, [mirrored], basis=basis)
    assert np.abs(space.blend([1.0]) - mirrored).max() < 1e-4 * LENGTH
    X = space.blend([0.5])
    assert np.isfinite(X).all()
    assert isinstance(space.stats["converged"], bool)


def test_many_keys(bar, basis):
    V, F = bar
    rng = np.random.default_rng(3)
    keys = [bend(V, a) if i % 2 else twist(V, a) for i, a in enumerate(rng.uniform(-2, 2, 200))]
    space = mdc.ShapeSpace(V, F, keys, basis=basis)
    w = np.zeros(200)
    w[[3, 50, 199]] = 0.3
    X = space.blend(w)
    assert np.isfinite(X).all()
    with pytest.raises(ValueError, match="up to"):
        mdc.ShapeSpace(V, F, [V] * (mdc.shapes.MAX_KEYS + 1), basis=basis)


def test_weights_with_no_minimum_give_the_linear_blend_and_say_so(bar, basis):
    V, F = bar
    stretched = V.copy()
    stretched[:, 2] *= 2.0
    also = stretched.copy()
    also[:, 0] += 0.05 * (V[:, 2] / 4) ** 2
    space = mdc.ShapeSpace(V, F, [stretched, also], basis=basis)
    for weights in ([1.0, 1.0], [1.0, 0.999]):
        X = space.blend(weights)
        linear = V + sum(w * (k - V) for w, k in zip(weights, (stretched, also)))
        assert np.ptp(X[:, 2]) < 2 * np.ptp(linear[:, 2])
        if space.stats["diverged"]:
            assert not space.stats["converged"]
            assert np.abs(X - linear).max() < 1e-4 * np.ptp(V)
    assert space.blend([0.5, 0.0]) is not None and not space.stats["diverged"]


def test_on_a_proxy_keys_keep_their_detail(bar):
    """On a proxy each key is P U q_i plus its residual, the detail the proxy cannot hold: weight 1
    gives the key to the map's precision, the weighted residuals being summed over the keys."""
    V, F = bar
    basis = mdc.bake(V, F, proxy=100, proxy_above=200)
    assert basis.num_basis_vertices < len(V)
    rng = np.random.default_rng(5)
    keys = [bend(V, np.pi / 2) + 0.01 * rng.normal(size=V.shape), twist(V, np.pi)]
    space = mdc.ShapeSpace(V, F, keys, basis=basis)
    assert np.abs(space.to_arrays()["key_residuals"]).max() > 0.01  # the noise, beyond the proxy
    for i, key in enumerate(keys):
        w = np.zeros(2)
        w[i] = 1
        assert np.abs(space.blend(w) - key).max() < 1e-4 * LENGTH
    both = space.blend([0.3, 0.4]).copy()
    assert np.isfinite(both).all()
    assert np.array_equal(space.blend([0.3, 0.4]), both)


def test_a_space_with_only_rigid_coordinates_blends_linearly(bar):
    V, F = bar
    arrays = mdc.bake(V, F, modes=7, derivatives=0).to_arrays()
    arrays["vectors"] = np.ascontiguousarray(arrays["vectors"][:, :6])
    arrays["ghost_vectors"] = np.ascontiguousarray(arrays["ghost_vectors"][:, :6])
    arrays["num_modes"] = np.array(6, dtype=np.int32)
    arrays["eigenvalues"] = arrays["eigenvalues"][:6].copy()
    space = mdc.ShapeSpace(V, F, [V.copy()], basis=mdc.Basis.from_arrays(arrays))
    X = space.blend([0.5])
    assert np.abs(X - V).max() < 1e-4 * np.ptp(V) and space.stats["converged"]
