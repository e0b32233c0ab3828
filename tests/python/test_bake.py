"""mdc.bake against dense scipy references, the Basis arrays and their storage round trip, and
progress, cancel and errors from the callback."""

import warnings

import numpy as np
import pytest
import scipy.linalg

import modal_deform.core as mdc


def side_by_side(first, second, offset):
    (V1, F1), (V2, F2) = first, second
    return np.vstack([V1, V2 + offset]), np.vstack([F1, F2 + len(V1)])


@pytest.fixture(scope="module")
def two_tubes():
    tube = mdc.testing.cylinder(14, 6, 0.5, 2.0)
    return side_by_side(tube, tube, [3.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def tubes_basis(two_tubes):
    return mdc.bake(*two_tubes, modes=18, derivatives=10, ghost=60)


def normalised_pencil(V, F):
    """K = ∇²E(x̄) and the diagonal of M in the normalised frame, dense."""
    s = 10.0 / np.ptp(V, axis=0).max()
    K = mdc.DiscreteShells(s * V, F).hessian(s * V).toarray()
    return K, np.repeat(s * s * mdc.mass(V, F), 3), s


def test_eigenvalues_and_residuals_match_scipy_eigh(two_tubes, tubes_basis):
    V, F = two_tubes
    K, m, s = normalised_pencil(V, F)
    reference = scipy.linalg.eigh(K, np.diag(m), eigvals_only=True)
    basis = tubes_basis
    assert basis.num_rigid == 12 and basis.num_floppy == 0
    # Exactly 6 near-zero eigenvalues per component, in the dense reference too.
    assert np.sum(np.abs(reference) < 1e-8 * reference[12]) == 12
    np.testing.assert_array_equal(basis.eigenvalues[:12], 0.0)
    np.testing.assert_allclose(basis.eigenvalues[12:], reference[12:18], rtol=1e-8)
    phi = s * basis.modes[:, 12:].astype(np.float64)
    residual = K @ phi - m[:, None] * phi * basis.eigenvalues[12:]
    # Single-precision vectors: the residual scales with float32 rounding times the spectrum's top.
    assert np.sqrt((residual**2 / m[:, None]).sum(axis=0)).max() < 1e-6 * reference[-1]


def test_zero_modes_beside_the_flexible_ones_are_deflated_and_solved_again():
    """Two cones joined at their apex: their relative rotation gives 3 zero modes, whose
    transformed eigenvalue swamps the others' in one Lanczos run (once a residual failure)."""
    V, F = [[0.0, 0.0, 0.0]], []
    for side in (1.0, -1.0):
        ring = len(V)
        V += [[np.cos(a), np.sin(a), side] for a in np.linspace(0, 2 * np.pi, 5, endpoint=False)]
        F += [[0, ring + k, ring + (k + 1) % 5] for k in range(5)]
    V, F = np.array(V), np.array(F)
    with pytest.warns(UserWarning, match="3 zero modes") as record:
        basis = mdc.bake(V, F, modes=10, derivatives=5, ghost=11)
    assert "on top of the 10 modes" in str(record[0].message)
    K, m, _ = normalised_pencil(V, F)
    reference = scipy.linalg.eigh(K, np.diag(m), eigvals_only=True)
    assert basis.num_rigid == 6 and basis.num_floppy == 3
    np.testing.assert_allclose(basis.eigenvalues[9:], reference[9:13], rtol=1e-8)


def test_basis_is_m_orthonormal_with_the_rigid_motions_first(two_tubes, tubes_basis):
    V, F = two_tubes
    basis = tubes_basis
    U = basis.scale * basis.vectors.astype(np.float64)
    m = np.repeat(basis.scale**2 * basis.mass, 3)
    np.testing.assert_allclose(U.T @ (m[:, None] * U), np.eye(basis.dimension), atol=1e-5)
    half = len(V) // 2
    for j in range(12):
        u = basis.vectors[:, j].astype(np.float64).reshape(-1, 3)
        moving, resting = (
            (slice(0, half), slice(half, None)) if j < 6 else (slice(half, None), slice(0, half))
        )
        assert np.all(u[resting] == 0)
        # u = ω × x + t on the moving tube: its displacement gradient is skew.
        X = np.c_[V[moving], np.ones(half)]
        gradient = np.linalg.lstsq(X, u[moving], rcond=None)[0][:3].T
        assert (
            np.abs(X @ np.linalg.lstsq(X, u[moving], rcond=None)[0] - u[moving]).max()
            < 1e-5 * np.abs(u).max()
        )
        assert np.abs(gradient + gradient.T).max() < 1e-5 * np.abs(gradient).max() + 1e-7


def test_arrays_are_read_only_views(tubes_basis):
    basis = tubes_basis
    assert basis.vectors.dtype == np.float32 and basis.vectors.shape == (
        3 * basis.num_vertices,
        basis.dimension,
    )
    assert basis.modes.shape == (3 * basis.num_vertices, basis.num_modes)
    assert np.shares_memory(basis.modes, basis.vectors)
    for name in (
        "rest",
        "mass",
        "vectors",
        "eigenvalues",
        "ghost_vertices",
        "ghost_faces",
        "ghost_map",
        "ghost_vectors",
    ):
        array = getattr(basis, name)
        assert not array.flags.writeable, name
        with pytest.raises(ValueError):
            array[...] = 0
    assert basis.ghost_faces.dtype == np.int32 and basis.ghost_map.dtype == np.int32
    assert basis.ghost_map.shape == (basis.num_vertices,) and basis.ghost_map.max() < len(
        basis.ghost_vertices
    )
    assert basis.ghost_vectors.shape == (3 * len(basis.ghost_vertices), basis.dimension)
    assert set(basis.timings) >= {
        "hessian",
        "factorisation",
        "modes",
        "third derivatives",
        "derivative solves",
        "orthonormalisation",
        "ghost",
    }
    assert "rigid" in repr(basis)


def test_views_keep_the_basis_alive(two_tubes):
    vectors = mdc.bake(*two_tubes, modes=14, derivatives=0, ghost=60).vectors
    expected = vectors.copy()
    mdc.bake(*two_tubes, modes=14, derivatives=3, ghost=60)  # allocate over anything freed
    np.testing.assert_array_equal(vectors, expected)


def test_to_arrays_round_trips_bit_exactly(tubes_basis):
    arrays = tubes_basis.to_arrays()
    assert int(arrays["format_version"]) == 3
    again = mdc.Basis.from_arrays(arrays).to_arrays()
    assert set(again) == set(arrays)
    for name, a in arrays.items():
        assert a.dtype == again[name].dtype and a.shape == again[name].shape, name
        assert a.tobytes() == again[name].tobytes(), name


def corruptions(arrays):
    """(name the error must mention, corrupted copy) pairs."""
    n, g = len(arrays["rest"]), len(arrays["ghost_vertices"])

    def changed(**replacements):
        copy = dict(arrays)
        copy.update(replacements)
        return copy

    missing = dict(arrays)
    del missing["ghost_map"]
    yield "ghost_map", missing
    yield "vectors", changed(vectors=arrays["vectors"].astype(np.float64))
    yield "ghost_faces", changed(ghost_faces=arrays["ghost_faces"].astype(np.int64))
    yield "vectors", changed(vectors=arrays["vectors"][:-3])
    yield "vectors", changed(vectors=arrays["vectors"][:, :-1])
    yield "rest", changed(rest=arrays["rest"][:, :2])
    yield "mass", changed(mass=np.append(arrays["mass"], 1.0))
    yield "ghost_vectors", changed(ghost_vectors=arrays["ghost_vectors"][:-1])
    yield "eigenvalues", changed(eigenvalues=arrays["eigenvalues"][:-1])
    yield "num_modes", changed(num_modes=np.array(arrays["vectors"].shape[1] + 1, dtype=np.int32))
    yield "num_floppy", changed(num_floppy=np.array(-1, dtype=np.int32))
    yield "num_dropped", changed(num_dropped=np.array(-2, dtype=np.int32))
    yield "num_rigid", changed(num_rigid=np.array([6], dtype=np.int32))
    vectors = arrays["vectors"].copy()
    vectors[7, 3] = np.nan
    yield "vectors", changed(vectors=vectors)
    ghost_vectors = arrays["ghost_vectors"].copy()
    ghost_vectors[0, 0] = np.inf
    yield "ghost_vectors", changed(ghost_vectors=ghost_vectors)
    # Not the restriction of vectors: larger than every entry of their column.
    yield "ghost_vectors", changed(ghost_vectors=arrays["ghost_vectors"] * 10)
    yield "mass", changed(mass=-arrays["mass"])
    yield "scale", changed(scale=np.array(0.0))
    yield "scale", changed(scale=np.array(np.nan))
    yield "bending", changed(bending=np.array(-1.0))
    yield "membrane", changed(membrane=np.array(np.inf))
    yield "rest", changed(rest=arrays["rest"] * 1e-200)
    for bad in (-1, g, 2**31 - 1):
        ghost_map = arrays["ghost_map"].copy()
        ghost_map[n // 2] = bad
        yield "ghost_map", changed(ghost_map=ghost_map)
    ghost_faces = arrays["ghost_faces"].copy()
    ghost_faces[-1, 2] = g
    yield "ghost_faces", changed(ghost_faces=ghost_faces)
    yield "ghost_faces", changed(ghost_faces=arrays["ghost_faces"][:0])
    yield "ghost_vertices", changed(ghost_vertices=arrays["ghost_vertices"][:0])
    yield "format_version", changed(format_version=np.array(4, dtype=np.int32))
    yield "format_version", changed(format_version=np.array(1, dtype=np.int64))
    yield "rest", changed(rest=arrays["rest"][:0])


def test_from_arrays_refuses_every_corruption_naming_the_array(tubes_basis):
    arrays = tubes_basis.to_arrays()
    for name, corrupted in corruptions(arrays):
        with pytest.raises(ValueError, match=name):
            mdc.Basis.from_arrays(corrupted)
    with pytest.raises(ValueError, match="arrays"):
        mdc.Basis.from_arrays([1, 2, 3])
    mdc.Basis.from_arrays(arrays)  # the original still loads


def test_the_papers_pairs_give_its_67_dimensions(two_tubes):
    """All modes but the translations pair (paper §4): with 15 modes, 3 rotations and 9 flexible
    modes give 78 pairs, so 52 derivatives make its 67-dimensional basis; pairs of flexible modes
    only (rotation_pairs=False, the rule before) are 45. Rotations of two components do not pair
    (their derivative is zero), so two tubes drop no column."""
    tube = mdc.testing.cylinder(14, 6, 0.5, 2.0)
    basis = mdc.bake(*tube, modes=15, derivatives=52, ghost=60)
    assert (basis.dimension, basis.num_dropped) == (67, 0)
    with pytest.raises(
        ValueError, match="derivatives: 52 asked for, but the 9 modes .* only 45 pairs"
    ):
        mdc.bake(*tube, modes=15, derivatives=52, ghost=60, rotation_pairs=False)
    assert mdc.bake(*tube, modes=21, derivatives=52, ghost=60, rotation_pairs=False).dimension == 73
    with pytest.raises(ValueError, match="rotation_pairs: expected True or False"):
        mdc.bake(*tube, rotation_pairs="yes")
    assert mdc.bake(*two_tubes, modes=18, derivatives=20, ghost=60).num_dropped == 0


def test_bad_options_raise_value_error_naming_them(two_tubes):
    V, F = two_tubes
    for kwargs, name in [
        ({"modes": 12}, "modes"),
        ({"derivatives": 500}, "derivatives"),
        ({"energy": "arap"}, "derivatives"),
        ({"energy": "springs"}, "energy"),
        ({"ghost": 3}, "ghost"),
        ({"modes": 2.5}, "modes"),
        ({"membrane": -1.0}, "membrane"),
        ({"progress": 3}, "progress"),
    ]:
        with pytest.raises(ValueError, match=name):
            mdc.bake(V, F, **kwargs)
    with pytest.raises(ValueError, match="F"):
        mdc.bake(V, F + len(V))
    basis = mdc.bake(V, F, modes=14, derivatives=0, energy="arap", ghost=60)
    assert basis.dimension == 14


@pytest.fixture(scope="module")
def scan_dragon(shared_mesh):
    return shared_mesh("dragon_vrip_res4.ply.gz")


def test_progress_is_frequent_and_a_scans_debris_makes_no_zero_modes(scan_dragon):
    """The 5k dragon's doubled triangles and the blobs hanging from it by a vertex are attached
    (they made 9 zero modes and a warning before): nothing on top of the modes asked for."""
    calls = []
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        basis = mdc.bake(
            *scan_dragon,
            modes=20,
            derivatives=15,
            progress=lambda stage, fraction: calls.append((stage, fraction)),
        )
    assert (
        basis.num_floppy == 0
        and basis.num_modes == 20
        and basis.dimension + basis.num_dropped == 35
    )
    # (That the eigensolve reports between its ends is tested natively, with no minimum interval
    # between reports: here reports are at most every 0.1 s, so their count depends on the machine.)
    stages = [stage for stage, _ in calls]
    for stage in (
        "hessian",
        "modes",
        "third derivatives",
        "derivative solves",
        "orthonormalisation",
        "ghost",
    ):
        assert stage in stages
    assert all(0.0 <= fraction <= 1.0 for _, fraction in calls)


@pytest.mark.parametrize("on_proxy", [False, True])
def test_one_bar_runs_forward_through_the_stages(on_proxy):
    """The stages come in the order of BAKE_STAGES (the native core's list), so the bar made of
    them only moves forward, to the end: on a dense mesh it fell back to 0 during the prolongation,
    and jumped to the ghost and back while the ordering waited for it."""
    V, F = mdc.testing.bumpy_plane(40)
    calls = []
    basis = mdc.bake(
        V,
        F,
        modes=10,
        derivatives=4,
        ghost=100,
        proxy=400 if on_proxy else None,
        proxy_above=1000,
        progress=lambda stage, fraction: calls.append((stage, fraction)),
    )
    assert basis.on_proxy == on_proxy
    order = [stage for i, (stage, _) in enumerate(calls) if i == 0 or calls[i - 1][0] != stage]
    expected = mdc.BAKE_STAGES if on_proxy else mdc.BAKE_STAGES[1:-1]
    assert order == [stage for stage in expected if stage in order], order
    assert (
        {"proxy", "prolongation"} <= set(order)
        if on_proxy
        else not {"proxy", "prolongation"} & set(order)
    )
    bar = [mdc.bake_fraction(stage, fraction, on_proxy) for stage, fraction in calls]
    assert all(a <= b for a, b in zip(bar, bar[1:])), bar
    assert bar[-1] == 1.0


def test_cancel_stops_at_once(scan_dragon):
    # The first report after the callback says stop ends the bake: nothing is reported after it.
    for stop_at in ("modes", "derivative solves", "ghost"):
        calls = []

        def progress(stage, fraction):
            calls.append(stage)
            return stage != stop_at

        with pytest.raises(mdc.Cancelled):
            mdc.bake(*scan_dragon, modes=20, derivatives=15, progress=progress)
        assert calls.index(stop_at) == len(calls) - 1, (stop_at, calls[-5:])


def test_an_exception_in_the_callback_propagates_as_itself(two_tubes):
    class Interrupted(Exception):
        pass

    def progress(stage, fraction):
        if stage == "modes":
            raise Interrupted(stage)

    with pytest.raises(Interrupted, match="modes"):
        mdc.bake(*two_tubes, modes=14, derivatives=5, ghost=60, progress=progress)
