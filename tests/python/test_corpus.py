"""The corpus of bad and awkward inputs, each run through every entry point it applies to.

Every case states its outcome per entry point: it works, with finite results, or it raises an
error whose message names the problem and where (the argument, and the first offending vertex,
face or handle). docs/robustness.md lists the cases; tests/cpp/test_corpus.cpp runs the same
meshes through the native entry points without the Python layer's checks.
"""

import warnings

import numpy as np
import pytest

import modal_deform.core as mdc


class Refused:
    """The outcome of a case that must raise ValueError with a message matching `pattern`."""

    def __init__(self, pattern):
        self.pattern = pattern

    def __repr__(self):
        return f"ValueError({self.pattern!r})"


WORKS = None


def finite(*arrays):
    for a in arrays:
        a = a.data if hasattr(a, "tocsc") else np.asarray(a)
        assert np.isfinite(a).all(), "non-finite output"


# --- Meshes ------------------------------------------------------------------------------------


def grid():
    return mdc.testing.grid(3, 3)


def with_vertices(V, F, extra):
    return np.vstack([V, extra]), F


def with_faces(V, F, extra):
    return V, np.vstack([F, extra])


def two_fans_at_a_vertex():
    """Two triangle fans (cones) that touch at their common apex only: a non-manifold vertex."""
    V, F = [[0.0, 0.0, 0.0]], []
    for side in (1.0, -1.0):
        ring = len(V)
        for k in range(5):
            angle = 2 * np.pi * k / 5
            V.append([np.cos(angle), np.sin(angle), side])
        F += [[0, ring + k, ring + (k + 1) % 5] for k in range(5)]
    return np.array(V), np.array(F)


def fin():
    """A grid with a fin standing on an interior edge: a non-manifold edge with three faces."""
    V, F = grid()
    a, b = F[4, 0], F[4, 1]
    top = (V[a] + V[b]) / 2 + [0.0, 0.0, 0.3]
    return np.vstack([V, top]), np.vstack([F, [[a, b, len(V)]]])


def debris():
    """A grid with 20 small triangles floating beside it, as scans have."""
    V, F = grid()
    rng = np.random.default_rng(3)
    Vs, Fs = [V], [F]
    for k in range(20):
        base = np.array([1.0 + 0.1 * k, 0.3 * rng.standard_normal(), 0.2])
        Vs.append(base + 0.01 * rng.standard_normal((3, 3)))
        Fs.append(np.arange(3)[None, :] + sum(len(v) for v in Vs[:-1]))
    return np.vstack(Vs), np.vstack(Fs)


def duplicate_vertex():
    """A seam: vertex 5's position repeated as a new vertex that half of its faces use."""
    V, F = grid()
    F = F.copy()
    F[F[:, 0] == 5, 0] = len(V)
    return np.vstack([V, V[5]]), F


def needle():
    """A face whose third vertex sits 1e-9 off its longest edge."""
    V, F = grid()
    a, b = V[0], V[1]
    return np.vstack([V, (a + b) / 2 + [0.0, 1e-9, 0.0]]), np.vstack([F, [[0, 1, len(V)]]])


def sliver_flap(height):
    """A triangle on the grid's first boundary edge whose apex sits `height` off it: a sliver that
    alone carries a vertex."""
    V, F = grid()
    apex = (V[0] + V[1]) / 2 + [0.0, -height, 0.0]
    return np.vstack([V, apex]), np.vstack([F, [[1, 0, len(V)]]])


def inner_sliver(height):
    """A wavy 6x6 grid whose face 30 has its third vertex `height` above its first edge's middle."""
    V, F = mdc.testing.grid(6, 6, 2.0, 2.0)
    V = V.copy()
    V[:, 2] = 0.1 * np.sin(3 * V[:, 0]) * np.cos(2 * V[:, 1])
    p, q, r = F[30]
    middle = (V[p] + V[q]) / 2
    V[r] = middle + height * (V[r] - middle) / np.linalg.norm(V[r] - middle)
    return V, F


def tiny_component(size):
    """The grid with a triangle `size` across floating above it."""
    V, F = grid()
    triangle = np.array([[0, 0, 0.5], [size, 0, 0.5], [0, size, 0.5]])
    return np.vstack([V, triangle]), np.vstack([F, [[len(V), len(V) + 1, len(V) + 2]]])


def scaled(factor):
    return lambda: (factor * grid()[0], grid()[1])


def with_entry(array, row, column, value):
    """The grid with one entry of V (array 0) or F (array 1) replaced."""

    def make():
        arrays = [a.copy() for a in grid()]
        arrays[array][row, column] = value
        return tuple(arrays)

    return make


def with_value(row, column, value):
    return with_entry(0, row, column, value)


def with_index(row, column, value):
    return with_entry(1, row, column, value)


def flipped(every):
    def make():
        V, F = grid()
        F = F.copy()
        F[::every] = F[::every, ::-1]
        return V, F

    return make


ONE_TRIANGLE = (np.eye(3), np.array([[0, 1, 2]]))
COLLINEAR = (np.c_[np.arange(4.0), np.zeros(4), np.zeros(4)], np.array([[0, 1, 2], [1, 2, 3]]))
NO_AREA = Refused(r"F: every face is degenerate or a sliver")
NO_EXTENT = Refused(r"V: the mesh's extent")

# name: (make (V, F), default outcome, {entry point: outcome} where it differs)
MESHES = {
    "empty mesh": (
        lambda: (np.zeros((0, 3)), np.zeros((0, 3), np.int32)),
        Refused(r"V: the mesh has no vertices"),
        {},
    ),
    "vertices, no faces": (
        lambda: (grid()[0], np.zeros((0, 3), np.int32)),
        Refused(r"F: the mesh has no faces"),
        {},
    ),
    "lone vertex": (
        lambda: (np.zeros((1, 3)), np.zeros((0, 3), np.int32)),
        Refused(r"F: the mesh has no faces"),
        {},
    ),
    "lone vertex in a face": (
        lambda: (np.zeros((1, 3)), np.zeros((1, 3), np.int32)),
        NO_EXTENT,
        {},
    ),
    "one triangle": (lambda: ONE_TRIANGLE, WORKS, {}),
    "collinear faces": (lambda: COLLINEAR, WORKS, {"bake": NO_AREA, "pose": NO_AREA}),
    "unreferenced vertices": (
        lambda: with_vertices(*grid(), [[5.0, 5.0, 5.0], [0.1, 0.1, 0.0]]),
        WORKS,
        {},
    ),
    "duplicate vertices": (duplicate_vertex, WORKS, {}),
    "zero-area face": (lambda: with_faces(*grid(), [[0, 1, 2]]), WORKS, {}),
    "face with a repeated index": (lambda: with_faces(*grid(), [[0, 5, 5]]), WORKS, {}),
    "needle face": (needle, WORKS, {}),
    "sliver flap (ratio 6e-9)": (lambda: sliver_flap(1e-9), WORKS, {}),
    "inner sliver (ratio 6e-6)": (lambda: inner_sliver(1e-6), WORKS, {}),
    "a component 1e-20 the size of the mesh": (lambda: tiny_component(1e-20), WORKS, {}),
    "duplicate face": (lambda: with_faces(*grid(), [grid()[1][3]]), WORKS, {}),
    "double sheet (a face and its flip)": (
        lambda: with_faces(*grid(), [grid()[1][3][::-1]]),
        WORKS,
        {},
    ),
    "non-manifold edge": (fin, WORKS, {}),
    # Three zero modes from the cones' relative rotation: the bake deflates them and solves again.
    "non-manifold vertex": (two_fans_at_a_vertex, WORKS, {}),
    "open boundary": (grid, WORKS, {}),
    "closed surface": (lambda: mdc.testing.bar(1, 1, 2), WORKS, {}),
    "many components (debris)": (debris, WORKS, {}),
    "inverted faces": (flipped(1), WORKS, {}),
    "inconsistently oriented faces": (flipped(2), WORKS, {}),
    "NaN coordinate": (
        with_value(7, 1, np.nan),
        Refused(r"V\[7\]: vertex 7 has a non-finite coordinate"),
        {},
    ),
    "infinite coordinate": (
        with_value(3, 2, -np.inf),
        Refused(r"V\[3\]: vertex 3 has a non-finite coordinate"),
        {},
    ),
    "tiny scale (1e-6)": (scaled(1e-6), WORKS, {}),
    "huge scale (1e6)": (scaled(1e6), WORKS, {}),
    "coordinate too large (1e200)": (
        with_value(2, 0, 1e200),
        Refused(r"V\[2\]: vertex 2 has a coordinate too large"),
        {},
    ),
    "extent too small (1e-200)": (scaled(1e-200), NO_EXTENT, {}),
    "index out of range": (
        with_index(4, 2, 16),
        Refused(r"F\[4\]: face 4 refers to vertex 16, outside \[0, 16\)"),
        {},
    ),
    "negative index": (with_index(2, 0, -1), Refused(r"F\[2\]: face 2 refers to vertex -1"), {}),
}

MESH_ENTRY_POINTS = ("check", "mass", "shells", "arap", "ghost", "bake", "pose", "full")


def rotation_about_z(angle, translation):
    T = np.eye(4)
    T[:2, :2] = [[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]]
    T[:3, 3] = translation
    return T


def small_bake(V, F):
    """8 modes (one simulated component: the debris is attached), 3 derivatives, a ghost of 8."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # floppy meshes warn
        return mdc.bake(V, F, modes=8, derivatives=3, ghost=8)


def pose_handle(V, F):
    """Vertex 0, moved by a small turn and a push of a tenth of the mesh's extent."""
    extent = np.ptp(V[np.isfinite(V).all(axis=1)], axis=0).max() if len(V) > 1 else 1.0
    return [[0]], [rotation_about_z(0.2, [0.1 * extent, 0.0, 0.0])]


def run_mesh_entry_point(entry, V, F):
    n = len(V)
    if entry == "check":
        report = mdc.check(V, F)
        assert report["vertices"] == n and report["faces"] == len(F)
    elif entry == "mass":
        m = mdc.mass(V, F)
        finite(m)
        assert m.shape == (n,) and (m >= 0).all()
    elif entry in ("shells", "arap"):
        E = mdc.DiscreteShells(V, F) if entry == "shells" else mdc.Arap(V, F)
        rng = np.random.default_rng(1)
        X = V + 0.05 * np.ptp(V, axis=0).max() * rng.standard_normal(V.shape)
        for x in (V, X):
            finite(E.value(x), E.gradient(x), E.hessian(x))
            if entry == "shells":
                finite(E.third(x, rng.standard_normal(3 * n), rng.standard_normal(3 * n)))
    elif entry == "ghost":
        Vg, Fg, ghost_map = mdc.ghost_mesh(V, F, 4)
        finite(Vg)
        assert ghost_map.shape == (n,) and 0 <= ghost_map.min() and ghost_map.max() < len(Vg)
        assert len(Fg) == 0 or (0 <= Fg.min() and Fg.max() < len(Vg))
    elif entry == "bake":
        basis = small_bake(V, F)
        finite(basis.vectors, basis.ghost_vectors, basis.eigenvalues)
    elif entry == "pose":
        basis = small_bake(V, F)
        handles, transforms = pose_handle(V, F)
        solver = mdc.ReducedSolver(basis, handles)
        solver.set_transforms(transforms)
        stats = solver.solve(max_iterations=10)
        finite(stats["energy"], solver.positions())
    elif entry == "full":
        handles, transforms = pose_handle(V, F)
        finite(mdc.solve_full(V, F, handles, transforms, max_iterations=10, tolerance=1e-6)[0])


def expect(outcome, call):
    if outcome is WORKS:
        call()
    else:
        with pytest.raises(ValueError, match=outcome.pattern):
            call()


@pytest.mark.parametrize("case", MESHES)
@pytest.mark.parametrize("entry", MESH_ENTRY_POINTS)
def test_mesh_case(case, entry):
    make, default, overrides = MESHES[case]
    V, F = make()
    expect(overrides.get(entry, default), lambda: run_mesh_entry_point(entry, V, F))


# --- Arrays of the wrong type or shape -----------------------------------------------------------

ARRAYS = {
    "V of shape (n, 2)": (lambda V, F: (V[:, :2], F), r"V: expected an \(n, 3\) array"),
    "V flat": (lambda V, F: (V.reshape(-1), F), r"V: expected an \(n, 3\) array"),
    "V of strings": (
        lambda V, F: (V.astype(str).astype(object) + "x", F),
        r"V: expected real numbers",
    ),
    "V complex": (lambda V, F: (V + 1j, F), r"V: expected real numbers"),
    "V as None": (lambda V, F: (None, F), r"V: expected"),
    "F of shape (m, 4)": (lambda V, F: (V, np.c_[F, F[:, :1]]), r"F: expected an \(m, 3\) array"),
    "F of floats": (lambda V, F: (V, F.astype(float)), r"F: expected integer indices"),
    "F beyond int32": (
        lambda V, F: (V, F.astype(np.int64) + 2**40),
        r"F: an index does not fit in 32 bits",
    ),
}


@pytest.mark.parametrize("case", ARRAYS)
@pytest.mark.parametrize("entry", ["check", "mass", "shells", "arap", "ghost", "bake", "full"])
def test_wrong_arrays_name_the_argument(case, entry):
    change, pattern = ARRAYS[case]
    V, F = change(*grid())
    calls = {
        "check": lambda: mdc.check(V, F),
        "mass": lambda: mdc.mass(V, F),
        "shells": lambda: mdc.DiscreteShells(V, F),
        "arap": lambda: mdc.Arap(V, F),
        "ghost": lambda: mdc.ghost_mesh(V, F, 4),
        "bake": lambda: mdc.bake(V, F, modes=8, derivatives=0),
        "full": lambda: mdc.solve_full(V, F, [[0]], [np.eye(4)]),
    }
    with pytest.raises(ValueError, match=pattern):
        calls[entry]()


def test_non_contiguous_and_read_only_arrays_work():
    V, F = grid()
    V2 = np.asfortranarray(np.hstack([V, V])[:, ::2])
    F2 = F[::-1][::-1].astype(np.uint16)
    V2.flags.writeable = False
    assert mdc.check(V2, F2)["faces"] == len(F)
    np.testing.assert_array_equal(mdc.mass(V2, F2), mdc.mass(V, F))


@pytest.mark.parametrize(
    "X, pattern",
    [
        (
            lambda V: np.where(np.arange(V.size).reshape(V.shape) == 13, np.nan, V),
            r"X\[4\]: vertex 4 has a non-finite",
        ),
        (lambda V: V[:-1], r"X: expected shape"),
        (lambda V: V * 1e200, r"X\[\d+\]: .*too large"),
    ],
)
@pytest.mark.parametrize("energy", [mdc.DiscreteShells, mdc.Arap])
def test_energies_refuse_bad_positions(energy, X, pattern):
    V, F = grid()
    E = energy(V, F)
    for method in (E.value, E.gradient, E.hessian):
        with pytest.raises(ValueError, match=pattern):
            method(X(V))


def test_third_derivative_refuses_bad_directions():
    V, F = grid()
    E = mdc.DiscreteShells(V, F)
    u = np.ones(V.size)
    bad = u.copy()
    bad[5] = np.inf
    with pytest.raises(ValueError, match=r"U\[1\]"):
        E.third(V, bad, u)
    with pytest.raises(ValueError, match=r"W\[1\]"):
        E.third(V, u, bad)


# --- Bake options --------------------------------------------------------------------------------

OPTIONS = {
    "more modes than degrees of freedom": (
        ONE_TRIANGLE,
        {"modes": 9},
        Refused(r"modes: .*ask for fewer than 9"),
    ),
    "modes not above the rigid motions": (
        (grid()),
        {"modes": 6},
        Refused(r"modes: 6 modes are not more than the 6"),
    ),
    "derivatives beyond the pairs": (
        grid(),
        {"modes": 8, "derivatives": 16},
        Refused(r"derivatives: 16 asked for"),
    ),
    "ghost larger than the mesh": (grid(), {"modes": 8, "ghost": 10**6}, WORKS),
    "ghost below 4": (grid(), {"ghost": 3}, Refused(r"ghost: expected at least 4")),
    "NaN bending": (
        grid(),
        {"bending": np.nan},
        Refused(r"bending: expected a value in \[0, 1e\+12\], got nan"),
    ),
    "negative membrane": (
        grid(),
        {"membrane": -1.0},
        Refused(r"membrane: expected a value in \[0, 1e\+12\], got -1"),
    ),
    "bending above 1e12": (
        grid(),
        {"bending": 1e300},
        Refused(r"bending: expected a value in \[0, 1e\+12\], got 1e\+300"),
    ),
    "bending not a number": (grid(), {"bending": "stiff"}, Refused(r"bending: expected a number")),
    "unknown energy": (
        grid(),
        {"energy": "springs"},
        Refused(r"energy: expected \"shells\" or \"arap\""),
    ),
    "ARAP with derivatives": (
        grid(),
        {"energy": "arap"},
        Refused(r"derivatives: the ARAP energy has no third"),
    ),
    "modes not an integer": (grid(), {"modes": 8.5}, Refused(r"modes: expected an integer")),
    "progress not callable": (
        grid(),
        {"progress": "yes"},
        Refused(r"progress: expected a callable"),
    ),
}


@pytest.mark.parametrize("case", OPTIONS)
def test_bake_option_case(case):
    (V, F), options, outcome = OPTIONS[case]
    options = {"modes": 10, "derivatives": 3, "ghost": 8, **options}
    expect(outcome, lambda: finite(mdc.bake(V, F, **options).vectors))


# --- Handles and transforms ----------------------------------------------------------------------


@pytest.fixture(scope="module")
def tube():
    V, F = mdc.testing.cylinder(8, 4, radius=0.5, length=2.0)
    return V, F, mdc.bake(V, F, modes=12, derivatives=8, ghost=20)


def turn(angle=0.3, shift=0.2):
    return rotation_about_z(angle, [shift, 0.0, 0.0])


def scaled_transform():
    T = turn()
    T[:3, :3] *= 1.5
    return T


def mirror():
    T = np.eye(4)
    T[0, 0] = -1
    return T


def nan_transform():
    T = turn()
    T[1, 3] = np.nan
    return T


# name: (handles (n) -> list, transforms, weights, stiffness, outcome)
HANDLES = {
    "no handles": (lambda n: [], [], None, 100.0, Refused(r"handles: no handle given")),
    "an empty handle": (
        lambda n: [[0, 1], []],
        [turn(), turn()],
        None,
        100.0,
        Refused(r"handles\[1\]"),
    ),
    "a handle covering every vertex": (lambda n: [np.arange(n)], [turn()], None, 100.0, WORKS),
    "overlapping handles": (lambda n: [[0, 1, 2], [2, 3]], [turn(), np.eye(4)], None, 100.0, WORKS),
    "index out of range": (
        lambda n: [[0, n]],
        [turn()],
        None,
        100.0,
        Refused(r"handles\[0\]\[1\] = \d+ is outside"),
    ),
    "negative index": (
        lambda n: [[-1]],
        [turn()],
        None,
        100.0,
        Refused(r"handles\[0\]\[0\] = -1 is outside"),
    ),
    "vertex listed twice": (
        lambda n: [[3, 3]],
        [turn()],
        None,
        100.0,
        Refused(r"handles\[0\] lists vertex 3 twice"),
    ),
    "a single index array": (
        lambda n: np.arange(3),
        [turn()],
        None,
        100.0,
        Refused(r"handles: .*single index array"),
    ),
    "float indices": (
        lambda n: [[0.0, 1.0]],
        [turn()],
        None,
        100.0,
        Refused(r"handles\[0\]: expected integer"),
    ),
    "too few transforms": (
        lambda n: [[0], [1]],
        [turn()],
        None,
        100.0,
        Refused(r"transforms: expected 2"),
    ),
    "scaled transform": (
        lambda n: [[0]],
        [scaled_transform()],
        None,
        100.0,
        Refused(r"transforms\[0\]: .*not a rotation"),
    ),
    "mirroring transform": (
        lambda n: [[0]],
        [mirror()],
        None,
        100.0,
        Refused(r"transforms\[0\]: .*reflection"),
    ),
    "NaN in a transform": (
        lambda n: [[0]],
        [nan_transform()],
        None,
        100.0,
        Refused(r"transforms\[0\] has non-finite"),
    ),
    "3x3 transform": (
        lambda n: [[0]],
        [np.eye(3)],
        None,
        100.0,
        Refused(r"transforms\[0\]: expected a 4x4"),
    ),
    "negative weight": (lambda n: [[0]], [turn()], [-1.0], 100.0, Refused(r"weights\[0\] = -1")),
    "weights of the wrong length": (
        lambda n: [[0]],
        [turn()],
        [1.0, 2.0],
        100.0,
        Refused(r"weights: expected \(1,\)"),
    ),
    "zero stiffness": (
        lambda n: [[0]],
        [turn()],
        None,
        0.0,
        Refused(r"pull: expected a value in \(0, 1e\+12\], got 0"),
    ),
    "NaN stiffness": (
        lambda n: [[0]],
        [turn()],
        None,
        np.nan,
        Refused(r"pull: expected a value in \(0, 1e\+12\], got nan"),
    ),
    "stiffness above 1e12": (
        lambda n: [[0]],
        [turn()],
        None,
        1e300,
        Refused(r"pull: expected a value in \(0, 1e\+12\], got 1e\+300"),
    ),
    "weight above 1e12": (
        lambda n: [[0]],
        [turn()],
        [1e300],
        100.0,
        Refused(r"weights\[0\] = 1e\+300 is not"),
    ),
    "a far translation (1e6 extents)": (lambda n: [[0]], [turn(0.0, 2e6)], None, 100.0, WORKS),
    "a translation beyond 1e15": (
        lambda n: [[0]],
        [turn(0.0, -1.7e308)],
        None,
        100.0,
        Refused(r"transforms\[0\]: the translation .* is beyond 1e\+15"),
    ),
}


@pytest.mark.parametrize("case", HANDLES)
@pytest.mark.parametrize("entry", ["reduced", "full"])
def test_handle_case(tube, case, entry):
    V, F, basis = tube
    make, transforms, weights, stiffness, outcome = HANDLES[case]
    handles = make(len(V))

    def reduced():
        solver = mdc.ReducedSolver(basis, handles, pull=stiffness, weights=weights)
        solver.set_transforms(transforms)
        finite(solver.solve(max_iterations=20)["energy"], solver.positions())

    def full():
        finite(
            mdc.solve_full(
                V, F, handles, transforms, pull=stiffness, weights=weights, max_iterations=20
            )[0]
        )

    expect(outcome, reduced if entry == "reduced" else full)


def test_solver_refuses_what_is_not_a_basis(tube):
    with pytest.raises(ValueError, match=r"basis: expected a modal_deform.core.Basis"):
        mdc.ReducedSolver({"vectors": None}, [[0]])


def test_positions_refuse_a_wrong_buffer(tube):
    V, F, basis = tube
    solver = mdc.ReducedSolver(basis, [[0]])
    for out in (
        np.empty((len(V), 3)),
        np.empty((len(V) - 1, 3), np.float32),
        np.empty((3, len(V)), np.float32).T,
    ):
        with pytest.raises(ValueError, match=r"out: expected a writeable C-contiguous float32"):
            solver.positions(out)


# --- Stored bases ----------------------------------------------------------------------------------


def stored_corruptions(arrays):
    """(pattern the error must match, corrupted copy) beyond test_bake's list."""

    def changed(**replacements):
        return {**arrays, **replacements}

    yield r"rest: missing", {k: v for k, v in arrays.items() if k != "rest"}
    yield r"vectors: expected dtype float32", changed(vectors=arrays["vectors"].tolist())
    yield r"rest\[0\]: vertex 0 has a coordinate too large", changed(rest=arrays["rest"] * 1e200)
    yield r"scale 1e\+300 does not scale rest", changed(scale=np.array(1e300))
    ghost_vectors = arrays["ghost_vectors"].copy()
    ghost_vectors[3, 1] = 1e300
    yield r"ghost_vectors", changed(ghost_vectors=ghost_vectors)
    ghost_vertices = arrays["ghost_vertices"].copy()
    ghost_vertices[0] = 1e6
    yield r"ghost_vertices", changed(ghost_vertices=ghost_vertices)
    yield r"num_rigid", changed(num_rigid=np.array(2**31 - 1, np.int32))


def test_from_arrays_refuses_corrupted_bases(tube):
    arrays = tube[2].to_arrays()
    for pattern, corrupted in stored_corruptions(arrays):
        with pytest.raises(ValueError, match=pattern):
            mdc.Basis.from_arrays(corrupted)
    basis = mdc.Basis.from_arrays(arrays)
    solver = mdc.ReducedSolver(basis, [[0]])
    solver.set_transforms([turn()])
    finite(solver.solve()["energy"], solver.positions())
