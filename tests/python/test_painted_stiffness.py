"""Stiffness painted per vertex (issue 24): stiff parts keep their shape, soft ones bend."""

import numpy as np
import pytest

import modal_deform.core as mdc


def turn_about_x(angle, centre, translation=(0.0, 0.0, 0.0)):
    """4x4: rotation by ``angle`` about the x axis through ``centre``, then a translation."""
    c, s = np.cos(angle), np.sin(angle)
    T = np.eye(4)
    T[:3, :3] = [[1, 0, 0], [0, c, -s], [0, s, c]]
    T[:3, 3] = np.asarray(centre) + np.asarray(translation) - T[:3, :3] @ centre
    return T


def pose(V, F, handles, transforms, **bake_options):
    basis = mdc.bake(V, F, modes=16, derivatives=40, ghost=2000, **bake_options)
    solver = mdc.ReducedSolver(basis, handles, pull=1e3)
    solver.set_transforms(transforms)
    solver.solve(max_iterations=400, tolerance=1e-9)
    return solver.positions().astype(np.float64)


def rigid_deviation(rest, posed):
    """RMS distance of ``posed`` from the rigid motion of ``rest`` that fits it best (Kabsch)."""
    a, b = rest - rest.mean(axis=0), posed - posed.mean(axis=0)
    U, _, Wt = np.linalg.svd(a.T @ b)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Wt))])
    return np.sqrt(np.mean(np.sum((a @ U @ D @ Wt - b) ** 2, axis=1)))


def ring_turning(V, posed):
    """(z of each ring but the ends, angle the tube's axis turns there): the axis is the chain of
    the rings' centroids."""
    z = np.unique(np.round(V[:, 2], 9))
    centres = np.array([posed[np.isclose(V[:, 2], level)].mean(axis=0) for level in z])
    tangents = np.diff(centres, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1)[:, None]
    return z[1:-1], np.arccos(np.clip(np.sum(tangents[1:] * tangents[:-1], axis=1), -1, 1))


@pytest.fixture(scope="module")
def bar():
    """A tube along z, 6 long, its end rings turned by ±40° about x: bent into an arc."""
    V, F = mdc.testing.cylinder(10, 30, radius=0.5, length=6.0)
    ends = [np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > 6 - 1e-9)]
    transforms = [
        turn_about_x(-0.7, [0, 0, 0], [0, 0, 0.4]),
        turn_about_x(0.7, [0, 0, 6], [0, 0, -0.4]),
    ]
    return V, F, ends, transforms


def test_zero_weights_give_the_plain_bake(bar):
    V, F, _, _ = bar
    plain = mdc.bake(V, F, modes=14, derivatives=10, ghost=100)
    zero = mdc.bake(
        V,
        F,
        modes=14,
        derivatives=10,
        ghost=100,
        stiffness_weights=np.zeros(len(V)),
        max_stiffness=1e4,
    )
    for name in ("vectors", "eigenvalues", "ghost_vectors"):
        np.testing.assert_array_equal(getattr(zero, name), getattr(plain, name), err_msg=name)
    assert zero.max_stiffness == 1e4 and zero.stiffness_weights.shape == (len(V),)
    assert plain.stiffness_weights.shape == (0,)


def test_a_stiff_middle_third_stays_nearly_rigid(bar):
    """Bent into an arc by its ends, the middle third of a bar painted 100 times stiffer there
    deviates from a rigid motion by less than a fifth of the uniform bar's middle."""
    V, F, ends, transforms = bar
    middle = (V[:, 2] > 2) & (V[:, 2] < 4)
    weights = middle.astype(float)
    uniform = pose(V, F, ends, transforms)
    painted = pose(V, F, ends, transforms, stiffness_weights=weights, max_stiffness=100.0)
    bent, stiff = (
        rigid_deviation(V[middle], uniform[middle]),
        rigid_deviation(V[middle], painted[middle]),
    )
    assert bent > 0.01
    assert stiff < 0.2 * bent, (stiff, bent)
    # The full solve agrees: the painted objective is the same one.
    full, _ = mdc.solve_full(
        V, F, ends, transforms, pull=1e3, stiffness_weights=weights, max_stiffness=100.0
    )
    assert rigid_deviation(V[middle], full[middle]) < 0.2 * bent


def test_a_finger_bends_at_its_knuckles():
    """A tube of three stiff phalanges and two soft knuckles, its tip ring curled by 120°: nearly
    all of the turning happens at the knuckles, where the uniform tube turns along its length."""
    V, F = mdc.testing.cylinder(10, 40, radius=0.4, length=5.0)
    knuckles = ((V[:, 2] > 1.5) & (V[:, 2] < 2.0)) | ((V[:, 2] > 3.25) & (V[:, 2] < 3.75))
    base, tip = np.flatnonzero(V[:, 2] < 1e-9), np.flatnonzero(V[:, 2] > 5 - 1e-9)
    # The tip ring where a finger curled by 60° at each knuckle would put it.
    curl = turn_about_x(-1.05, [0, 0, 1.75]) @ turn_about_x(-1.05, [0, 0, 3.5])
    transforms = [np.eye(4), curl]

    def share_at_knuckles(posed):
        z, turning = ring_turning(V, posed)
        at_knuckles = ((z > 1.5) & (z < 2.0)) | ((z > 3.25) & (z < 3.75))
        return turning[at_knuckles].sum() / turning.sum()

    uniform = pose(V, F, [base, tip], transforms)
    finger = pose(
        V,
        F,
        [base, tip],
        transforms,
        stiffness_weights=np.where(knuckles, 0.0, 1.0),
        max_stiffness=100.0,
    )
    assert share_at_knuckles(uniform) < 0.4
    assert share_at_knuckles(finger) > 0.75, share_at_knuckles(finger)


def test_the_solver_minimises_the_painted_energy(bar):
    """With the mesh as its own ghost, the solver's objective is the painted energy of the posed
    mesh plus the handle term, which is linear in the handle stiffness μ: E = 2 f(μ=1) − f(μ=2)."""
    V, F, _, _ = bar
    weights = np.linspace(0, 1, len(V))
    basis = mdc.bake(
        V, F, modes=14, derivatives=10, ghost=len(V), stiffness_weights=weights, max_stiffness=30.0
    )
    q = np.random.default_rng(1).normal(scale=0.05, size=basis.dimension)
    f1, f2 = (mdc.ReducedSolver(basis, [[0]], pull=mu).objective(q)[0] for mu in (1.0, 2.0))
    s = basis.scale
    X = s * (V.reshape(-1) + basis.vectors.astype(np.float64) @ q)
    painted = mdc.DiscreteShells(s * V, F, stiffness_weights=weights, max_stiffness=30.0)
    assert 2 * f1 - f2 == pytest.approx(painted.value(X), rel=1e-6)
    assert painted.value(X) > 1.5 * mdc.DiscreteShells(s * V, F).value(X)


def test_bad_paint_is_refused_naming_it(bar):
    V, F, _, _ = bar
    n = len(V)
    bad = [
        (np.full(n - 1, 0.5), {}, r"stiffness_weights: expected \(%d,\)" % n),
        (np.where(np.arange(n) == 7, np.nan, 0.0), {}, r"stiffness_weights\[7\] = nan"),
        (np.where(np.arange(n) == 3, -0.1, 0.0), {}, r"stiffness_weights\[3\] = -0.1"),
        (np.where(np.arange(n) == 5, 1.5, 0.0), {}, r"stiffness_weights\[5\] = 1.5"),
        (
            np.zeros(n),
            {"max_stiffness": 0.5},
            r"max_stiffness: expected a value in \[1, 10000\], got 0.5",
        ),
        (np.zeros(n), {"max_stiffness": 2e4}, "max_stiffness"),
        (np.zeros(n), {"max_stiffness": np.nan}, "max_stiffness"),
        (np.zeros(n), {"energy": "arap", "derivatives": 0}, "stiffness_weights: the ARAP energy"),
    ]
    for weights, options, message in bad:
        with pytest.raises(ValueError, match=message):
            mdc.bake(
                V,
                F,
                modes=14,
                derivatives=options.pop("derivatives", 10),
                ghost=100,
                stiffness_weights=weights,
                **options,
            )
    with pytest.raises(ValueError, match=r"stiffness_weights\[7\]"):
        mdc.DiscreteShells(
            V, F, stiffness_weights=np.where(np.arange(n) == 7, 2.0, 0.0), max_stiffness=10
        )
    with pytest.raises(ValueError, match="stiffness_weights: the ARAP energy"):
        mdc.solve_full(
            V, F, [[0]], [np.eye(4)], energy="arap", stiffness_weights=np.ones(n), max_stiffness=10
        )


def test_the_paint_is_stored_and_checked(bar):
    V, F, _, _ = bar
    basis = mdc.bake(
        V,
        F,
        modes=14,
        derivatives=4,
        ghost=100,
        stiffness_weights=np.linspace(0, 1, len(V)),
        max_stiffness=10.0,
    )
    arrays = basis.to_arrays()
    again = mdc.Basis.from_arrays(arrays)
    np.testing.assert_array_equal(again.stiffness_weights, basis.stiffness_weights)
    assert again.max_stiffness == 10.0
    for name, value in [
        ("stiffness_weights", arrays["stiffness_weights"][:-1]),
        ("stiffness_weights", arrays["stiffness_weights"] * 2),
        ("max_stiffness", np.array(0.0)),
    ]:
        with pytest.raises(ValueError, match=name):
            mdc.Basis.from_arrays({**arrays, name: value})
    # A basis stored before painting (format 2) has none.
    old = {
        name: a
        for name, a in arrays.items()
        if name not in ("stiffness_weights", "max_stiffness", "region", "ghost_stiffness_weights")
    }
    old["format_version"] = np.array(2, dtype=np.int32)
    assert mdc.Basis.from_arrays(old).stiffness_weights.shape == (0,)


def test_a_proxy_bake_carries_the_paint(bar):
    """A mesh baked on a proxy: the proxy's elements and the ghost's take the fine weights' means,
    and the basis keeps the fine weights; the stiff middle still holds."""
    V, F, ends, transforms = bar
    middle = (V[:, 2] > 2) & (V[:, 2] < 4)
    basis = mdc.bake(
        V,
        F,
        modes=16,
        derivatives=40,
        ghost=150,
        proxy=200,
        proxy_above=250,
        stiffness_weights=middle.astype(float),
        max_stiffness=100.0,
    )
    assert basis.on_proxy and basis.num_basis_vertices < len(V)
    np.testing.assert_array_equal(basis.stiffness_weights, middle.astype(float))
    ghost_weights = basis.ghost_stiffness_weights
    assert ghost_weights.shape == (len(basis.ghost_vertices),) and 0 < ghost_weights.mean() < 1
    solver = mdc.ReducedSolver(basis, ends, pull=1e3)
    solver.set_transforms(transforms)
    solver.solve(max_iterations=400, tolerance=1e-9)
    uniform = pose(V, F, ends, transforms)
    posed = solver.positions().astype(np.float64)
    assert rigid_deviation(V[middle], posed[middle]) < 0.2 * rigid_deviation(
        V[middle], uniform[middle]
    )
