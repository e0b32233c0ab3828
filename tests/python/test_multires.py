"""The multiresolution bake (issue 15): dense meshes baked on a proxy and carried to every vertex."""

import numpy as np
import pytest
from support import subdivision  # midpoint_subdivide: the project's own
from support.poses import end_pull  # the benchmark's handles and pose

import modal_deform.core as mdc


@pytest.fixture(scope="module")
def plane_on_proxy():
    V, F = mdc.testing.bumpy_plane(100)  # 10,201 vertices
    return V, F, mdc.bake(V, F, modes=12, derivatives=10, ghost=200, proxy=2000, proxy_above=5000)


def test_a_dense_mesh_keeps_the_proxy_basis_and_the_prolongation(plane_on_proxy):
    V, F, basis = plane_on_proxy
    n, r = len(V), basis.dimension
    assert basis.on_proxy and basis.num_vertices == n
    p = basis.num_basis_vertices
    assert 1800 <= p <= 2200 and basis.vectors.shape == (3 * p, r)
    assert basis.prolongation_vertices.shape == (n, 3) and basis.prolongation_weights.shape == (
        n,
        3,
    )
    assert basis.ghost_map.shape == (n,) and np.array_equal(basis.rest, V)
    assert {"proxy", "prolongation"} <= set(basis.timings)
    # Stored per fine vertex: rest (24 bytes), mass (8), ghost map (4) and prolongation (24), not
    # the 12 r bytes of a dense basis; the rest is the proxy's and the ghost's.
    arrays = basis.to_arrays()
    per_proxy = sum(
        arrays[name].nbytes
        for name in ("vectors", "ghost_vectors", "ghost_vertices", "ghost_faces")
    )
    assert sum(a.nbytes for a in arrays.values()) - per_proxy <= 60 * n + 1000
    assert "proxy 2" in repr(basis)


def test_positions_are_the_prolongated_basis(plane_on_proxy):
    V, F, basis = plane_on_proxy
    U = basis.fine_vectors()
    assert U.shape == (3 * len(V), basis.dimension)
    solver = mdc.ReducedSolver(basis, [np.flatnonzero(V[:, 0] < -4), np.flatnonzero(V[:, 0] > 4)])
    lift = np.eye(4)
    lift[2, 3] = 1.5
    solver.set_transforms([np.eye(4), lift])
    solver.solve(max_iterations=30)
    X = solver.positions()
    # positions() reads 16-bit vectors: within 1e-4 of the diagonal (FinePositions::kTolerance, 3e-5)
    assert np.abs(X.ravel() - (V.ravel() + U @ solver.q)).max() < 1e-4 * np.linalg.norm(
        np.ptp(V, axis=0)
    )
    assert X[V[:, 0] > 4, 2].mean() > 1.0  # the lifted end moved


def test_round_trip_and_damaged_prolongation(plane_on_proxy):
    _, _, basis = plane_on_proxy
    arrays = basis.to_arrays()
    again = mdc.Basis.from_arrays(arrays)
    assert again.on_proxy and again.num_basis_vertices == basis.num_basis_vertices
    for name, a in again.to_arrays().items():
        assert a.tobytes() == arrays[name].tobytes(), name

    def damaged(**replacements):
        return {**arrays, **replacements}

    vertices, weights = (
        arrays["prolongation_vertices"].copy(),
        arrays["prolongation_weights"].copy(),
    )
    vertices[11, 2] = basis.num_basis_vertices
    weights[5] = (0.9, 0.9, -0.8)
    nan = arrays["prolongation_weights"].copy()
    nan[0, 0] = np.nan
    for name, corrupted in (
        ("prolongation vertices", damaged(prolongation_vertices=vertices)),
        ("prolongation weights", damaged(prolongation_weights=weights)),
        ("prolongation weights", damaged(prolongation_weights=nan)),
        ("prolongation_weights", damaged(prolongation_weights=weights.astype(np.float64))),
        ("prolongation_vertices", damaged(prolongation_vertices=vertices[:, :2])),
        ("prolongation has", damaged(prolongation_vertices=vertices[:-1])),
        ("vectors has", damaged(vectors=arrays["vectors"][:-1])),
    ):
        with pytest.raises(ValueError, match=name):
            mdc.Basis.from_arrays(corrupted)


def test_a_version_1_basis_still_loads():
    V, F = mdc.testing.bumpy_plane(20)
    arrays = mdc.bake(V, F, modes=10, derivatives=4, ghost=100).to_arrays()
    old = {name: a for name, a in arrays.items() if not name.startswith("prolongation")}
    old["format_version"] = np.array(1, dtype=np.int32)
    basis = mdc.Basis.from_arrays(old)
    assert not basis.on_proxy and basis.prolongation_vertices.shape == (0, 3)


def test_proxy_options_and_progress():
    V, F = mdc.testing.bumpy_plane(40)
    stages = []
    basis = mdc.bake(
        V,
        F,
        modes=10,
        derivatives=4,
        ghost=100,
        proxy=400,
        proxy_above=1000,
        progress=lambda stage, fraction: stages.append(stage),
    )
    assert basis.on_proxy and stages[0] == "proxy" and stages[-1] == "prolongation"
    assert not mdc.bake(V, F, modes=10, derivatives=4, ghost=100, proxy=None).on_proxy
    assert not mdc.bake(
        V, F, modes=10, derivatives=4, ghost=100, proxy=400, proxy_above=len(V)
    ).on_proxy
    assert not mdc.bake(
        V, F, modes=10, derivatives=4, ghost=100, proxy=400, proxy_above=0
    ).on_proxy  # 0: never
    for options, name in (
        ({"proxy": 3, "proxy_above": 1000}, "proxy"),
        ({"proxy": 1500, "proxy_above": 1000}, "proxy"),
        ({"proxy_above": -1}, "proxy_above"),
        ({"proxy": "many"}, "proxy"),
    ):
        with pytest.raises(ValueError, match=name):
            mdc.bake(V, F, modes=10, derivatives=4, ghost=100, **options)


def test_the_subdivided_dragon_on_a_proxy_poses_like_the_dragon(shared_mesh):
    """The dragon (100k) subdivided once (400k) and baked on the default proxy poses within 1% RMS
    (of the bounding-box diagonal) of the dragon's own bake under the same handles, on the
    vertices the two share; its stored basis is a fraction of a dense one."""
    V, F = shared_mesh("dragon_vrip_res2.ply.gz")
    V_fine, F_fine = subdivision.midpoint_subdivide(V, F)

    def posed(basis, V):
        handles, poses = end_pull(V)
        solver = mdc.ReducedSolver(basis, handles)
        solver.set_transforms(poses[0].at(1.0))
        solver.solve(max_iterations=300, tolerance=1e-9)
        return solver.positions()

    fine = mdc.bake(V_fine, F_fine, modes=20, derivatives=47, ghost=1000)
    assert fine.on_proxy and fine.num_basis_vertices <= 1.1 * mdc.BAKE_OPTIONS["proxy"].default
    stored = sum(a.nbytes for a in fine.to_arrays().values())
    assert stored < 0.25 * 12 * fine.dimension * len(V_fine)
    own = mdc.bake(V, F, modes=20, derivatives=47, ghost=1000)
    assert not own.on_proxy
    X, X_own = posed(fine, V_fine)[: len(V)], posed(own, V)
    diagonal = np.linalg.norm(np.ptp(V, axis=0))
    rms = np.sqrt(np.mean(np.sum((X.astype(np.float64) - X_own) ** 2, axis=1))) / diagonal
    moved = np.sqrt(np.mean(np.sum((X_own - V) ** 2, axis=1))) / diagonal
    print(
        f"RMS against the dragon's own bake: {100 * rms:.3f}% of the diagonal (the pose moves {100 * moved:.1f}%)"
    )
    assert moved > 0.05
    assert rms < 0.01
