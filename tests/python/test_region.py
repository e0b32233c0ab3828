"""Region bakes (issue 24): only the region moves, every other vertex stays exactly at rest."""

import numpy as np
import pytest

import modal_deform.core as mdc


@pytest.fixture(scope="module")
def tube():
    V, F = mdc.testing.cylinder(10, 30, radius=0.5, length=6.0)
    return V, F, np.flatnonzero(V[:, 2] > 3.0 - 1e-9)


def test_outside_the_region_nothing_moves_and_the_inside_follows_its_handle(tube):
    V, F, region = tube
    basis = mdc.bake(V, F, modes=12, derivatives=30, ghost=100, region=region[::-1])
    assert basis.num_rigid == 0 and basis.num_floppy == 0 and basis.dimension == 42
    np.testing.assert_array_equal(basis.region, region)
    outside = np.setdiff1d(np.arange(len(V)), region)
    assert not basis.vectors.reshape(len(V), 3, -1)[outside].any()
    # The ghost is spent where the mesh moves: the region and the two rings of faces around it.
    assert (
        len(basis.ghost_vertices) <= 100 and basis.ghost_vertices[:, 2].min() > 3.0 - 3 * 6.0 / 30
    )
    top = np.flatnonzero(V[:, 2] > 6 - 1e-9)
    T = np.eye(4)
    T[:3, 3] = [0.6, 0.0, -0.3]
    solver = mdc.ReducedSolver(basis, [top], pull=1e3)
    solver.set_transforms([T])
    stats = solver.solve(max_iterations=200, tolerance=1e-8)
    X = solver.positions()
    assert X[outside].tobytes() == V[outside].astype(np.float32).tobytes()
    assert np.abs(X[top] - (V[top] + T[:3, 3])).max() < 0.05 * 0.6, stats
    # The boundary holds: the ring next to the clamped half barely moves, the middle of the region does.
    moved = np.linalg.norm(X - V, axis=1)
    assert moved[np.isclose(V[:, 2], 3.2)].max() < 0.4 * moved[np.isclose(V[:, 2], 4.6)].min()


def test_a_region_bake_matches_the_full_solve_with_the_outside_held(tube):
    """The region's reduced pose approaches the full solve that pins every vertex outside."""
    V, F, region = tube
    basis = mdc.bake(V, F, modes=16, derivatives=50, ghost=1000, region=region)
    top = np.flatnonzero(V[:, 2] > 6 - 1e-9)
    outside = np.setdiff1d(np.arange(len(V)), region)
    T = np.eye(4)
    T[:3, 3] = [0.5, 0.0, 0.0]
    solver = mdc.ReducedSolver(basis, [top], pull=1e3)
    solver.set_transforms([T])
    solver.solve(max_iterations=300, tolerance=1e-9)
    full, _ = mdc.solve_full(V, F, [top, outside], [T, np.eye(4)], pull=1e3, weights=[1.0, 1e3])
    error = np.abs(solver.positions()[region] - full[region]).max()
    assert error < 0.05 * 0.5, error


def test_a_dense_region_is_baked_on_a_proxy_of_its_own_faces():
    """A region of more free vertices than proxy_above is baked on a proxy of the region and the
    faces around it: the outside is held exactly by zero prolongation weights, and the pose agrees
    with the region's dense bake."""
    V, F = mdc.testing.cylinder(40, 120, radius=0.5, length=6.0)
    region = np.flatnonzero(V[:, 2] > 3.0 - 1e-9)
    outside = np.setdiff1d(np.arange(len(V)), region)
    top = np.flatnonzero(V[:, 2] > 6 - 1e-9)
    T = np.eye(4)
    T[:3, 3] = [0.6, 0.0, -0.3]
    sizes = dict(modes=12, derivatives=30, ghost=300, region=region)
    dense = mdc.bake(V, F, proxy=None, **sizes)
    basis = mdc.bake(V, F, proxy=600, proxy_above=1000, **sizes)
    assert basis.on_proxy and basis.num_basis_vertices <= 650 and basis.num_rigid == 0
    np.testing.assert_array_equal(basis.region, region)
    assert not basis.prolongation_weights[outside].any()
    np.testing.assert_allclose(basis.prolongation_weights[region].sum(axis=1), 1.0, atol=1e-6)
    poses = []
    for b in (dense, basis, mdc.Basis.from_arrays(basis.to_arrays())):
        solver = mdc.ReducedSolver(b, [top], pull=1e3)
        solver.set_transforms([T])
        assert solver.solve(max_iterations=300, tolerance=1e-8)["converged"]
        poses.append(solver.positions())
    X = poses[1]
    assert X[outside].tobytes() == V[outside].astype(np.float32).tobytes()
    assert np.abs(X[top] - (V[top] + T[:3, 3])).max() < 0.05 * 0.6
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    assert np.sqrt(np.mean(np.sum((X - poses[0]) ** 2, axis=1))) < 0.005 * diagonal
    assert poses[2].tobytes() == X.tobytes()
    arrays = basis.to_arrays()
    weights = arrays["prolongation_weights"].copy()
    weights[outside[0]] = [1.0, 0.0, 0.0]
    with pytest.raises(
        ValueError, match=rf"prolongation weights\[{outside[0]}\]: vertex {outside[0]} lies outside"
    ):
        mdc.Basis.from_arrays({**arrays, "prolongation_weights": weights})


def test_refine_keeps_the_outside_exactly_where_it_was(tube):
    """Refine of a region bake holds every vertex outside the region where the reduced pose left it
    (at rest), and reaches the full solve's minimum with the outside held."""
    V, F, region = tube
    basis = mdc.bake(V, F, modes=12, derivatives=30, ghost=100, region=region)
    outside = np.setdiff1d(np.arange(len(V)), region)
    top = np.flatnonzero(V[:, 2] > 6 - 1e-9)
    T = np.eye(4)
    T[:3, 3] = [0.6, 0.0, -0.3]
    solver = mdc.ReducedSolver(basis, [top], pull=1e3)
    solver.set_transforms([T])
    solver.solve(max_iterations=200, tolerance=1e-8)
    start = solver.positions().astype(np.float64)
    X, stats = solver.refine(F)
    assert stats["converged"], stats
    assert X[outside].tobytes() == start[outside].tobytes()
    held, held_stats = mdc.solve_full(V, F, [top], [T], pull=1e3, held=outside)
    assert held_stats["converged"] and np.array_equal(held[outside], V[outside])
    assert np.abs(X - held).max() < 1e-4 * np.linalg.norm(np.ptp(V, axis=0))
    with pytest.raises(ValueError, match=rf"held\[1\] = {len(V)} is not a vertex"):
        mdc.solve_full(V, F, [top], [T], held=[0, len(V)])


def test_handles_outside_the_region_are_refused(tube):
    V, F, region = tube
    basis = mdc.bake(V, F, modes=8, derivatives=0, ghost=100, region=region)
    with pytest.raises(ValueError, match=r"handles\[1\]: vertex 0 lies outside the basis's region"):
        mdc.ReducedSolver(basis, [region[-10:], [0, 1]])


def test_a_free_part_of_the_region_keeps_its_rigid_motions_as_zero_modes(tube):
    V, F, _ = tube
    W = V + [3.0, 0.0, 0.0]
    V2, F2 = np.vstack([V, W]), np.vstack([F, F + len(V)])
    basis = mdc.bake(
        V2, F2, modes=12, derivatives=10, ghost=200, region=np.arange(len(V), 2 * len(V))
    )
    assert basis.num_rigid == 0 and basis.num_floppy == 6
    assert not basis.vectors[: 3 * len(V)].any()


def test_bad_regions_are_refused_naming_them(tube):
    V, F, region = tube
    n = len(V)
    for bad, message in [
        ([], "region: it has no vertices"),
        ([0, n], rf"region\[1\] = {n} is not a vertex"),
        ([3, 4, 3], r"region\[2\] = 3 is there twice"),
        (np.arange(n), "region: it holds every vertex"),
        ([[1, 2]], "region: expected a 1-d array"),
        ([0.5], "region: expected a 1-d array of vertex indices"),
    ]:
        with pytest.raises(ValueError, match=message):
            mdc.bake(V, F, modes=8, derivatives=0, ghost=100, region=bad)
    # A region vertex without a face has no mass: nothing is left free.
    V2 = np.vstack([V, [[9.0, 9.0, 9.0]]])
    with pytest.raises(ValueError, match="region: no vertex of it is left free"):
        mdc.bake(V2, F, modes=8, derivatives=0, ghost=100, region=[n])
    arrays = mdc.bake(V, F, modes=8, derivatives=0, ghost=100, region=region).to_arrays()
    for value, message in [
        (arrays["region"][::-1].copy(), r"region\[1\]"),
        (arrays["region"][1:], "vectors: vertex %d lies outside the region" % region[0]),
    ]:
        with pytest.raises(ValueError, match=message):
            mdc.Basis.from_arrays({**arrays, "region": value})


def test_the_solver_minimises_the_whole_mesh_energy_with_the_outside_held(tube):
    """The region's ghost (its submesh, here whole) holds every term that moves, the bending terms
    across its boundary ring included: its energy at any q is the whole mesh's."""
    V, F, region = tube
    basis = mdc.bake(V, F, modes=12, derivatives=20, ghost=1000, region=region)
    q = np.random.default_rng(2).normal(scale=0.02, size=basis.dimension)
    f1, f2 = (
        mdc.ReducedSolver(basis, [region[-10:]], pull=mu).objective(q)[0] for mu in (1.0, 2.0)
    )
    s = basis.scale
    X = s * (V.reshape(-1) + basis.vectors.astype(np.float64) @ q)
    assert 2 * f1 - f2 == pytest.approx(mdc.DiscreteShells(s * V, F).value(X), rel=1e-6)
