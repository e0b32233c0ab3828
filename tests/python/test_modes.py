"""Vibration modes, rigid motions and the modal-derivative solves against dense scipy references,
with a spring network (edges and hinges: the shells pattern, rigid motions in its kernel) and a
graph Laplacian as stand-in stiffness matrices."""

import re

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
import scipy.sparse.csgraph
import scipy.sparse.linalg

import modal_deform.core as mdc


def edges_and_hinges(F):
    """Unique edges (a, b) and, for each edge with two faces, the two opposite vertices."""
    corners = np.concatenate([F[:, [0, 1, 2]], F[:, [1, 2, 0]], F[:, [2, 0, 1]]])
    keys = np.sort(corners[:, :2], axis=1)
    order = np.lexsort((keys[:, 1], keys[:, 0]))
    keys, opposite = keys[order], corners[order, 2]
    twin = np.all(keys[1:] == keys[:-1], axis=1)
    return np.unique(keys, axis=0), np.stack([opposite[:-1][twin], opposite[1:][twin]], axis=1)


def spring_stiffness(V, F):
    """Hessian at rest of sum 1/2 (l - l0)^2 / l0 over springs along edges and across hinges."""
    edges, hinges = edges_and_hinges(F)
    a, b = np.concatenate([edges, hinges]).T
    e = V[a] - V[b]
    block = e[:, :, None] * e[:, None, :] / np.linalg.norm(e, axis=1)[:, None, None] ** 3
    r, c = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    rows, cols, vals = [], [], []
    for p, q, sign in ((a, a, 1), (b, b, 1), (a, b, -1), (b, a, -1)):
        rows.append((3 * p[:, None, None] + r).ravel())
        cols.append((3 * q[:, None, None] + c).ravel())
        vals.append(sign * block.ravel())
    n = 3 * len(V)
    return scipy.sparse.csc_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), (n, n)
    )


def laplacian_stiffness(V, F):
    """Graph Laplacian of the edges (unit weights) ⊗ I3."""
    edges, _ = edges_and_hinges(F)
    A = scipy.sparse.coo_matrix((np.ones(len(edges)), tuple(edges.T)), (len(V), len(V)))
    L = scipy.sparse.csgraph.laplacian((A + A.T).tocsr())
    return scipy.sparse.kron(L, scipy.sparse.identity(3)).tocsc()


def jittered_bar(nx, ny, nz, seed):
    V, F = mdc.testing.bar(nx, ny, nz, 1.0, 1.0, 2.0)
    return V + np.random.default_rng(seed).uniform(-0.05, 0.05, V.shape), F


@pytest.fixture(scope="module")
def two_boxes():
    """Two rigid spring networks side by side: (V, F, K, mass, labels)."""
    V1, F1 = jittered_bar(2, 2, 3, 1)
    V2, F2 = jittered_bar(1, 2, 2, 2)
    V = np.vstack([V1, V2 + [3, 0, 0]])
    F = np.vstack([F1, F2 + len(V1)])
    labels = np.repeat([0, 1], [len(V1), len(V2)])
    return V, F, spring_stiffness(V, F), mdc.mass(V, F), labels


def test_modes_match_scipy_eigh(two_boxes):
    V, F, K, mass, _ = two_boxes
    m = np.repeat(mass, 3)
    for stiffness in (K, laplacian_stiffness(V, F)):
        reference = scipy.linalg.eigh(
            stiffness.toarray(), np.diag(m), eigvals_only=True, subset_by_index=[0, 19]
        )
        eigenvalues, modes = mdc.vibration_modes(stiffness, mass, 20)
        top = reference[-1]
        np.testing.assert_allclose(eigenvalues, reference, rtol=0, atol=1e-9 * top)
        residuals = stiffness @ modes - m[:, None] * modes * eigenvalues
        assert np.sqrt((residuals**2 / m[:, None]).sum(axis=0)).max() < 1e-8 * top
        np.testing.assert_allclose(modes.T @ (m[:, None] * modes), np.eye(20), atol=1e-10)


def test_zero_modes_six_per_component_for_springs_three_for_the_laplacian(two_boxes):
    V, F, K, mass, _ = two_boxes
    eigenvalues, _ = mdc.vibration_modes(K, mass, 16)
    assert np.sum(np.abs(eigenvalues) < 1e-8 * eigenvalues[12]) == 12
    eigenvalues, _ = mdc.vibration_modes(laplacian_stiffness(V, F), mass, 10)
    assert np.sum(np.abs(eigenvalues) < 1e-8 * eigenvalues[6]) == 6


def test_rigid_motions_are_the_kernel(two_boxes):
    V, F, K, mass, labels = two_boxes
    Z = mdc.rigid_motions(V, labels, mass)
    assert Z.shape == (3 * len(V), 12)
    np.testing.assert_allclose(Z.T @ (np.repeat(mass, 3)[:, None] * Z), np.eye(12), atol=1e-12)
    assert np.abs(K @ Z).max() < 1e-12 * np.abs(K).max() * np.abs(Z).max()
    # The kernel of K is exactly their span.
    eigenvalues, modes = mdc.vibration_modes(K, mass, 12)
    in_span = Z @ (Z.T @ (np.repeat(mass, 3)[:, None] * modes))
    np.testing.assert_allclose(in_span, modes, atol=1e-8 * np.abs(modes).max())


def test_deflated_modes_are_the_flexible_ones(two_boxes):
    V, F, K, mass, labels = two_boxes
    Z = mdc.rigid_motions(V, labels, mass)
    all_eigenvalues, _ = mdc.vibration_modes(K, mass, 18)
    eigenvalues, modes = mdc.vibration_modes(K, mass, 6, kernel=Z)
    np.testing.assert_allclose(eigenvalues, all_eigenvalues[12:], rtol=1e-9)
    assert np.abs(Z.T @ (np.repeat(mass, 3)[:, None] * modes)).max() < 1e-10


def test_solve_in_range_is_the_limit_of_k_plus_eps_m(two_boxes):
    V, F, K, mass, labels = two_boxes
    m = np.repeat(mass, 3)
    Z = mdc.rigid_motions(V, labels, mass)
    B = np.random.default_rng(3).standard_normal((K.shape[0], 4))
    PB = B - Z @ np.linalg.solve(Z.T @ Z, Z.T @ B)
    Psi = mdc.solve_in_range(K, mass, Z, B)
    assert Psi.shape == B.shape
    # Dense pseudo-inverse in the M-orthonormal eigenbasis: Σ over λ > 0 of φ φᵀ P B / λ.
    lam, phi = scipy.linalg.eigh(K.toarray(), np.diag(m))
    flexible = lam > 1e-8 * lam[-1]
    assert np.count_nonzero(~flexible) == 12
    reference = phi[:, flexible] @ ((phi[:, flexible].T @ PB) / lam[flexible, None])
    np.testing.assert_allclose(Psi, reference, rtol=0, atol=1e-9 * np.abs(reference).max())
    # (K + εM)⁻¹ P B tends to Ψ as ε → 0, with an error of about ε / λ₁.
    for eps in (1e-4 * lam[flexible][0], 1e-6 * lam[flexible][0]):
        shifted = scipy.sparse.linalg.spsolve((K + eps * scipy.sparse.diags(m)).tocsc(), PB)
        assert np.abs(shifted - Psi).max() < 10 * eps / lam[flexible][0] * np.abs(Psi).max()
    # One vector works too, and K does not need to be csc.
    np.testing.assert_allclose(
        mdc.solve_in_range(K.tocoo(), mass, Z, B[:, 0])[:, 0], Psi[:, 0], atol=1e-12
    )


def test_unsorted_duplicate_entries_are_summed(two_boxes):
    V, F, K, mass, _ = two_boxes
    # Each column twice, the second copy reversed, each copy with half the values.
    indices, data = [], []
    for j in range(K.shape[1]):
        rows, values = (
            K.indices[K.indptr[j] : K.indptr[j + 1]],
            K.data[K.indptr[j] : K.indptr[j + 1]],
        )
        indices += [rows, rows[::-1]]
        data += [values / 2, values[::-1] / 2]
    doubled = scipy.sparse.csc_matrix(
        (np.concatenate(data), np.concatenate(indices), 2 * K.indptr), K.shape
    )
    assert not doubled.has_canonical_format
    before = doubled.indices.copy(), doubled.data.copy()
    np.testing.assert_allclose(
        mdc.vibration_modes(doubled, mass, 14)[0],
        mdc.vibration_modes(K, mass, 14)[0],
        rtol=1e-10,
        atol=1e-12,
    )
    # The caller's matrix is left as it was.
    np.testing.assert_array_equal(doubled.indices, before[0])
    np.testing.assert_array_equal(doubled.data, before[1])


@pytest.mark.parametrize(
    "call, error, needle",
    [
        (
            lambda K, m, Z: mdc.vibration_modes(K.toarray(), m, 4),
            ValueError,
            "K: expected a scipy.sparse matrix",
        ),
        (lambda K, m, Z: mdc.vibration_modes(K, m[:-1], 4), ValueError, "K: expected"),
        (lambda K, m, Z: mdc.vibration_modes(K, m, 0), ValueError, "count: expected 1 to"),
        (lambda K, m, Z: mdc.vibration_modes(K, -m, 4), ValueError, "mass[0]"),
        (
            lambda K, m, Z: mdc.vibration_modes(
                K - 0.01 * scipy.sparse.diags(np.repeat(m, 3)), m, 4
            ),
            RuntimeError,
            "not positive definite",
        ),
        (
            lambda K, m, Z: mdc.vibration_modes(K, m, 4, kernel=Z[:, :5] + 1),
            ValueError,
            "M-orthonormal",
        ),
        (
            lambda K, m, Z: mdc.solve_in_range(K, m, Z[:-3], np.ones(K.shape[0])),
            ValueError,
            "Z: expected shape",
        ),
        (
            lambda K, m, Z: mdc.solve_in_range(K, m, 2 * Z, np.ones(K.shape[0])),
            ValueError,
            "M-orthonormal",
        ),
        (
            lambda K, m, Z: mdc.solve_in_range(K, m, Z[:, :3], np.ones(K.shape[0])),
            RuntimeError,
            "whole kernel",
        ),
        (
            lambda K, m, Z: mdc.rigid_motions(np.zeros((len(m), 3)), np.zeros(len(m), int), m),
            ValueError,
            "line",
        ),
        (
            lambda K, m, Z: mdc.rigid_motions(np.zeros((len(m), 3)), np.zeros(len(m)), m),
            ValueError,
            "labels: expected integers",
        ),
    ],
)
def test_bad_input_raises_naming_it(two_boxes, call, error, needle):
    V, F, K, mass, labels = two_boxes
    Z = mdc.rigid_motions(V, labels, mass)
    with pytest.raises(error, match=re.escape(needle)):
        call(K, mass, Z)
