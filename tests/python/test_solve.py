"""Posing through the Python API: mdc.solve_full and mdc.ReducedSolver."""
import numpy as np
import pytest

import modal_deform.core as mdc


def rigid(axis, angle, centre, translation):
    """4x4: rotation by ``angle`` about ``axis`` through ``centre``, then a translation."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    R = np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.asarray(centre) + np.asarray(translation) - R @ centre
    return T


@pytest.fixture(scope="module")
def tube():
    """A tube along z held at its bottom ring, its top ring turned and pushed."""
    V, F = mdc.cylinder(8, 6, radius=1.0, length=3.0)
    handles = [np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > 3 - 1e-9)]
    transforms = [np.eye(4), rigid([1, 0, 1], 0.8, [0, 0, 3], [0.8, 0, -0.3])]
    return V, F, handles, transforms


def objective_gradient(V, F, handles, transforms, X, stiffness, energy):
    """∇F in the normalised frame, assembled independently from mdc's energies and masses."""
    s = 10.0 / np.ptp(V, axis=0).max()
    E = mdc.DiscreteShells(s * V, F) if energy == "shells" else mdc.Arap(s * V, F)
    g = E.gradient(s * X).reshape(-1, 3)
    m = mdc.mass(V, F)
    for idx, T in zip(handles, transforms):
        target = V[idx] @ T[:3, :3].T + T[:3, 3]
        g[idx] += 2 * stiffness * s**2 * m[idx, None] * s * (X[idx] - target)
    return g.ravel()


@pytest.mark.parametrize("energy", ["shells", "arap"])
def test_solve_full_finds_a_stationary_point(tube, energy):
    V, F, handles, transforms = tube
    X, stats = mdc.solve_full(V, F, handles, transforms, stiffness=100.0, energy=energy, tolerance=1e-10,
                              return_stats=True)
    assert X.shape == V.shape and X.dtype == np.float64
    assert stats["converged"] and stats["iterations"] > 0
    assert stats["gradient_norm"] <= 1e-10 * stats["gradient_scale"]
    g = objective_gradient(V, F, handles, transforms, X, 100.0, energy)
    g0 = objective_gradient(V, F, handles, transforms, V, 100.0, energy)
    assert np.linalg.norm(g) <= 1e-8 * np.linalg.norm(g0)
    # Without stats: the positions alone.
    assert np.array_equal(mdc.solve_full(V, F, handles, transforms, stiffness=100.0, energy=energy, tolerance=1e-10), X)


def test_solve_full_refuses_bad_input(tube):
    V, F, handles, transforms = tube
    scaled = transforms[1].copy()
    scaled[:3, :3] *= 1.1
    with pytest.raises(ValueError, match=r"transforms\[1\]"):
        mdc.solve_full(V, F, handles, [np.eye(4), scaled])
    mirrored = np.diag([1.0, 1.0, -1.0, 1.0])
    with pytest.raises(ValueError, match=r"transforms\[0\].*reflection"):
        mdc.solve_full(V, F, handles, [mirrored, np.eye(4)])
    with pytest.raises(ValueError, match=r"transforms\[1\]: expected a 4x4"):
        mdc.solve_full(V, F, handles, [np.eye(4), np.eye(3)])
    with pytest.raises(ValueError, match="expected 2"):
        mdc.solve_full(V, F, handles, [np.eye(4)])
    with pytest.raises(ValueError, match=r"handles\[1\]\[0\] = 999"):
        mdc.solve_full(V, F, [handles[0], [999]], transforms)
    with pytest.raises(ValueError, match=r"handles\[0\] lists vertex 3 twice"):
        mdc.solve_full(V, F, [[3, 4, 3]], [np.eye(4)])
    with pytest.raises(ValueError, match=r"handles\[1\]: expected a non-empty"):
        mdc.solve_full(V, F, [handles[0], []], transforms)
    with pytest.raises(ValueError, match="a single index array"):
        mdc.solve_full(V, F, handles[0], [np.eye(4)])
    with pytest.raises(ValueError, match="no handle"):
        mdc.solve_full(V, F, [], [])
    with pytest.raises(ValueError, match="energy"):
        mdc.solve_full(V, F, handles, transforms, energy="neo-hookean")
    with pytest.raises(ValueError, match="stiffness"):
        mdc.solve_full(V, F, handles, transforms, stiffness=-1.0)
    with pytest.raises(ValueError, match=r"weights"):
        mdc.solve_full(V, F, handles, transforms, weights=[1.0, -2.0])
