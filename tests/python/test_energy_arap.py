"""mdc.Arap through the Python API: shapes, derivatives, rigid invariance, errors."""

import numpy as np
import pytest
import scipy.sparse

import modal_deform.core as mdc


@pytest.fixture(scope="module")
def bunny(shared_mesh):
    V, F = shared_mesh("bunny.obj.gz")
    return V * (10.0 / np.ptp(V, axis=0).max()), F


def test_rest_and_rigid_motions_cost_nothing(bunny):
    V, F = bunny
    E = mdc.Arap(V, F)
    c, s = np.cos(1.0), np.sin(1.0)
    moved = V @ np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]).T + [1.0, 2.0, 3.0]
    for X in (V, moved):
        assert abs(E.value(X)) < 1e-20
        assert np.abs(E.gradient(X)).max() < 1e-11
    assert E.num_vertices == len(V)


def test_derivatives_match_centred_differences(bunny):
    V, F = bunny
    E = mdc.Arap(V, F)
    rng = np.random.default_rng(3)
    X = V * [1.3, 1.0, 0.8] + 0.05 * rng.standard_normal(V.shape)
    d = rng.standard_normal(V.size)
    h = 1e-4
    g = E.gradient(X)
    assert g.shape == (V.size,) and g.dtype == np.float64
    slope = (E.value(X.ravel() + h * d) - E.value(X.ravel() - h * d)) / (2 * h)
    assert slope == pytest.approx(g @ d, rel=1e-6)
    H = E.hessian(X)
    assert isinstance(H, scipy.sparse.csc_matrix) and H.shape == (V.size, V.size)
    assert abs(H - H.T).max() < 1e-12 * abs(H).max()
    change = (E.gradient(X.ravel() + h * d) - E.gradient(X.ravel() - h * d)) / (2 * h)
    assert np.linalg.norm(change - H @ d) < 1e-6 * np.linalg.norm(H @ d)


def test_mirror_image_is_not_free(bunny):
    V, F = bunny
    E = mdc.Arap(V, F)
    assert E.value(V * [-1.0, 1.0, 1.0]) > E.value(V * [1.3, 1.0, 1.0]) > 1.0


def test_third_derivative_is_refused_with_the_reason():
    V, F = mdc.testing.cylinder(8, 3)
    E = mdc.Arap(V, F)
    with pytest.raises(ValueError, match="shells"):
        E.third(V, V, V)


def test_bad_input_is_named():
    V, F = mdc.testing.cylinder(8, 3)
    with pytest.raises(ValueError, match=r"F\[0\]"):
        mdc.Arap(V, F + 1000)
    E = mdc.Arap(V, F)
    with pytest.raises(ValueError, match="X: expected shape"):
        E.value(V[:-1])
    X = V.copy()
    X[4, 2] = np.nan
    with pytest.raises(ValueError, match=r"X\[4\]"):
        E.gradient(X)
