"""mdc.DiscreteShells through the bindings: the paper's formula, shapes, errors.

The derivatives are checked in depth by tests/cpp/test_discrete_shells.cpp.
"""

import numpy as np
import pytest
import scipy.sparse

import modal_deform.core as mdc


def normalized(V):
    return V * (10.0 / np.ptp(V, axis=0).max())


def deformed(V, seed=0):
    """Half of the mesh turned by 90 degrees, the rest stretched by 30%, plus noise."""
    rng = np.random.default_rng(seed)
    X = V.copy()
    top = V[:, 2] > np.median(V[:, 2])
    c, s = np.cos(np.pi / 2), np.sin(np.pi / 2)
    R = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    pivot = np.array([V[:, 0].mean(), V[:, 1].mean(), np.median(V[:, 2])])
    X[top] = (V[top] - pivot) @ R.T + pivot
    X[~top, 0] *= 1.3
    return X + 0.02 * rng.uniform(-1, 1, X.shape)


def paper_energy(V, F, X, bending, membrane):
    """E = α E_F + β (E_L + E_A) of a closed manifold mesh, written out plainly: dihedral angles by
    atan2, θ − θ̄ wrapped into [−π, π)."""
    ends = np.stack([F, np.roll(F, -1, axis=1)], axis=2).reshape(-1, 2)  # half-edge a -> b
    opposite = np.roll(F, -2, axis=1).reshape(-1)
    key = np.sort(ends, axis=1) @ [len(V), 1]
    order = np.argsort(key, kind="stable")
    assert np.all(key[order[0::2]] == key[order[1::2]])  # every edge has exactly two faces
    first, second = order[0::2], order[1::2]
    v0, v1 = ends[first, 0], ends[first, 1]
    v2, v3 = opposite[first], opposite[second]
    face_area = lambda P: (
        0.5 * np.linalg.norm(np.cross(P[F[:, 1]] - P[F[:, 0]], P[F[:, 2]] - P[F[:, 0]]), axis=1)
    )

    def theta(P):
        e = P[v1] - P[v0]
        n1 = np.cross(e, P[v2] - P[v0])
        n2 = np.cross(P[v3] - P[v0], e)
        unit = e / np.linalg.norm(e, axis=1)[:, None]
        return np.arctan2(
            np.einsum("ij,ij->i", np.cross(n1, n2), unit), np.einsum("ij,ij->i", n1, n2)
        )

    rest_area = face_area(V)
    combined = rest_area[first // 3] + rest_area[second // 3]
    rest_length = np.linalg.norm(V[v1] - V[v0], axis=1)
    delta = np.mod(theta(X) - theta(V) + np.pi, 2 * np.pi) - np.pi
    E_F = 0.5 * np.sum(3 * rest_length**2 / combined * (2 * np.sin(delta / 2)) ** 2)
    length = np.linalg.norm(X[v1] - X[v0], axis=1)
    E_L = 0.5 * np.sum((length - rest_length) ** 2 / rest_length)
    E_A = 0.5 * np.sum((face_area(X) - rest_area) ** 2 / rest_area)
    return bending * E_F + membrane * (E_L + E_A)


@pytest.fixture(scope="module")
def bunny(shared_mesh):
    V, F = shared_mesh("bunny.obj.gz")
    return normalized(V), F


def test_value_is_the_papers_formula(bunny):
    V, F = bunny
    E = mdc.DiscreteShells(V, F, bending=1.3, membrane=0.7)
    for seed in range(3):
        X = deformed(V, seed)
        assert E.value(X) == pytest.approx(paper_energy(V, F, X, 1.3, 0.7), rel=1e-12)
    assert E.value(V) == 0.0


def test_shapes_types_and_layouts(bunny):
    V, F = bunny
    n = len(V)
    E = mdc.DiscreteShells(V, F)
    assert E.num_vertices == n
    assert E.term_counts == {"edges": 5511, "triangles": 3674, "hinges": 5511}
    X = deformed(V)
    g = E.gradient(X)
    assert g.shape == (3 * n,) and g.dtype == np.float64
    np.testing.assert_array_equal(E.gradient(X.reshape(-1)), g)
    H = E.hessian(X)
    assert isinstance(H, scipy.sparse.csc_matrix) and H.shape == (3 * n, 3 * n)
    assert abs(H - H.T).max() == 0.0
    rng = np.random.default_rng(1)
    U, W = rng.standard_normal((2, 3 * n))
    t = E.third(X, U, W)
    assert t.shape == (3 * n,)
    B = E.third_batch(X, np.stack([U, W], axis=1), [(0, 1), (1, 1)])
    assert B.shape == (3 * n, 2)
    np.testing.assert_allclose(B[:, 0], t, rtol=0, atol=1e-12 * np.abs(t).max())
    np.testing.assert_allclose(
        B[:, 1], E.third(X, W, W), rtol=0, atol=1e-12 * np.abs(B[:, 1]).max()
    )
    assert E.third_batch(X, np.stack([U, W], axis=1), np.zeros((0, 2), dtype=int)).shape == (
        3 * n,
        0,
    )


def test_hessian_is_the_derivative_of_the_gradient(bunny):
    V, F = bunny
    E = mdc.DiscreteShells(V, F)
    X = deformed(V).reshape(-1)
    d = np.random.default_rng(2).uniform(-1, 1, X.shape)
    h = 1e-5
    difference = (E.gradient(X + h * d) - E.gradient(X - h * d)) / (2 * h)
    exact = E.hessian(X) @ d
    assert np.linalg.norm(difference - exact) < 1e-7 * np.linalg.norm(exact)


@pytest.mark.parametrize(
    "call, needle",
    [
        (lambda V, F, E: mdc.DiscreteShells(V, F, bending=-1), "bending"),
        (lambda V, F, E: mdc.DiscreteShells(V, F, membrane=np.inf), "membrane"),
        (lambda V, F, E: mdc.DiscreteShells(V[:, :2], F), "V: expected an (n, 3)"),
        (lambda V, F, E: E.value(V[:-1]), "X: expected shape"),
        (
            lambda V, F, E: E.value(np.where(np.arange(V.size).reshape(V.shape) == 7, np.nan, V)),
            "X[2]: vertex 2",
        ),
        (lambda V, F, E: E.third(V, V, np.full(V.shape, np.inf)), "W[0]"),
        (lambda V, F, E: E.third_batch(V, np.ones((V.size, 2)), [(0, 2)]), "pairs[0]"),
        (
            lambda V, F, E: E.third_batch(V, np.ones((V.size, 2)), [0, 1]),
            "pairs: expected a (p, 2)",
        ),
        (
            lambda V, F, E: E.third_batch(V, np.ones((V.size - 1, 2)), [(0, 1)]),
            "Phi: expected shape",
        ),
    ],
)
def test_bad_input_raises_value_error_naming_it(call, needle):
    V, F = mdc.testing.cylinder(6, 2)
    E = mdc.DiscreteShells(V, F)
    with pytest.raises(ValueError) as error:
        call(V, F, E)
    assert needle in str(error.value)
