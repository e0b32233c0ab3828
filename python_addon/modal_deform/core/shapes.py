"""Shape keys that blend like shapes: the rotation-aware blend of von Tycowicz, Schulz, Seidel and
Hildebrandt (Real-time Nonlinear Shape Interpolation, ACM TOG 34(3), 2015).

    space = mdc.ShapeSpace(V, F, [X1, X2])      # V the basis (weight 0), the keys X_i (n, 3)
    X = space.blend([0.5, 0.0])                 # (n, 3) float32
    space.stats                                 # the last blend's iterations, convergence, ms

The blend of keys x_1 … x_k with weights w is the shape x minimising

    Σ_i w_i W[x_i, x] + (1 − Σ_i w_i) W[x̄, x],

W[y, x] the Discrete Shells energy of x with y as the rest (the basis's material). Where a part
rotates between the basis and a key, the blend rotates it and keeps its size, where Blender's
linear blend x̄ + Σ w_i (x_i − x̄) cuts through the chord and collapses it.

How the space is built (cpp/solve/shape_space.h): the baked basis of the rest mesh (``bake``: rigid
motions, modes, modal derivatives; on a proxy above ``proxy_above`` vertices), augmented by the
keys' displacements x_i − x̄, M-orthogonalised against it and each other (a key equal to the basis
or to a combination of others adds no column), so that each key is x̄ + U q_i to float32 precision
(on a proxy, the detail the proxy cannot hold is added linearly, Σ w_i r_i). The energy is
evaluated on the basis's ghost: each key's ghost shape x̄_s + U_s q_i is the rest of its energy, and
their weighted sum is one Discrete Shells energy with blended rest lengths, areas and angles, so an
evaluation costs one ghost energy however many keys there are. A blend runs BFGS on the non-rigid
coordinates from the linear blend's q = Σ w_i q_i with the initial inverse Hessian
(Σ |w_j| H_j)⁻¹ (H_j the reduced Hessian of rest j's energy there): a fixed start, so a blend is a
function of the weights alone, bit for bit. The rigid coordinates (the basis's ``num_rigid``
first columns) are held at the linear blend's: the blend has the linear blend's centre of mass and
no linearised rotation from it, so it does not drift.

Cost of a blend, with k keys and r = basis dimension + k: O(k · ghost terms) to blend the rests,
O(k r²) + r³ for the initial inverse Hessian, then per BFGS iteration one energy evaluation on the
ghost, O(ghost terms + ghost vertices · r), and O(r²) (45 to 55 iterations at r = 80 on the
dragon: their count, not an iteration's cost, keeps a blend above its 4 ms target; Newton with the
exact reduced Hessian takes fewer steps, about 20, each costing some 50 evaluations), and the map
to the fine mesh O(n r) (16-bit vectors, as ``ReducedSolver``), plus O(n) per key with a non-zero
weight on a proxy. bench/shape_space.py times blends, where they go, and bakes. Weights outside
[0, 1] (a negative weight makes the energy unbounded below) give the stationary point BFGS reaches
from the linear blend; ``stats["converged"]`` says when none was reached.
"""

import numpy as np

from .. import _native
from . import _arrays, _options
from .bake import BAKE_OPTIONS, Basis, bake

#: A blend's options (cpp/solve/shape_space.h, for_each_blend_option): {name: Option}.
BLEND_OPTIONS = _options.table(_native.BLEND_OPTIONS)
#: The most keys a space takes.
MAX_KEYS = _native.MAX_SHAPE_KEYS
# 1: the augmented basis (Basis's fields), base_dimension, key_coordinates, key_residuals.
FORMAT_VERSION = 1


def _keys(shapes, n):
    try:
        shapes = list(shapes)
    except TypeError:
        raise ValueError(
            f"shapes: expected a list of (n, 3) arrays, one per key, got {type(shapes).__name__}"
        ) from None
    if not shapes:
        raise ValueError("shapes: no key given; a shape space needs at least one")
    if len(shapes) > MAX_KEYS:
        raise ValueError(f"shapes: a shape space takes up to {MAX_KEYS} keys, got {len(shapes)}")
    keys = []
    for i, X in enumerate(shapes):
        X = _arrays.vertices(X, f"shapes[{i}]")
        if len(X) != n:
            raise ValueError(
                f"shapes[{i}]: expected {n} vertices (the basis's), got {len(X)}; every key has "
                f"the basis's vertices"
            )
        keys.append(X)
    return keys


class ShapeSpace:
    """The shape space of a mesh's keys: ``blend(weights)`` is their rotation-aware blend.

    ``V`` (n, 3), ``F`` (m, 3): the basis mesh (the weight-0 shape); ``shapes``: the keys, a list of
    (n, 3) arrays. The rest mesh's basis is baked with the options below (``bake``'s), or
    ``basis`` is one baked for (V, F) already (an object's stored basis). Raises ValueError naming
    a key of another vertex count, a non-finite coordinate, or more than ``MAX_KEYS`` keys; a
    region basis is refused. A key may equal the basis or other keys (it adds no column) and may
    fold or collapse the mesh (an element of zero size in a key adds nothing to its term's blend).
    """

    @_options.takes_options(BAKE_OPTIONS, exclude=("region",))
    def __init__(self, V, F, shapes, basis=None, progress=None, **options):
        V, F = _arrays.vertices(V), _arrays.faces(F)
        keys = _keys(shapes, len(V))
        if basis is None:
            basis = bake(V, F, progress=progress, **options)
        elif not isinstance(basis, Basis):
            raise ValueError(
                f"basis: expected a modal_deform.core.Basis or None, got {type(basis).__name__}"
            )
        elif basis.rest.shape != V.shape or not np.array_equal(basis.rest, V):
            raise ValueError("basis: it was baked for another mesh than V; bake V, or pass None")
        self._set_native(_native.ShapeSpace(basis._native, keys))

    def _set_native(self, native):
        self._native = native
        self._basis = Basis(native.basis)
        self._stats = {}

    @property
    def basis(self):
        """The space's Basis: the rest mesh's with the keys' columns after ``base_dimension``."""
        return self._basis

    num_keys = property(lambda self: self._native.num_keys, doc="k, the number of keys")
    num_vertices = property(lambda self: self._native.num_vertices)
    dimension = property(
        lambda self: self._native.dimension, doc="r: the rest's basis and the keys' columns"
    )
    base_dimension = property(
        lambda self: self._native.base_dimension, doc="columns of the rest mesh's own basis"
    )

    @property
    def key_coordinates(self):
        """(r, k) float64: key i is x̄ + U q_i with q_i column i (plus, on a proxy, its detail)."""
        return self._native.coordinates

    @property
    def q(self):
        """The reduced coordinates of the last blend (r,) float64."""
        return self._native.q

    @property
    def stats(self):
        """The last blend's {"iterations", "converged", "ms" (the whole blend, the map included),
        "solve_ms" (the minimisation), "map_ms" (the map to the fine mesh), "evaluations", "energy" (the blended energy, up to a
        constant), "gradient_norm", "stalled", "diverged"}; empty before the first blend.
        "diverged": the minimisation ran off farther than the model's size from the linear blend
        (weights whose rest weight 1 - sum(w) is negative can leave the energy without a minimum,
        such as two keys at 1 that stretch the same part); the linear blend is returned then."""
        return dict(self._stats)

    @_options.takes_options(BLEND_OPTIONS)
    def blend(self, weights, out=None, **options):
        """The blend for ``weights`` (k,), one per key, the basis weighted 1 − Σ w_i: (n, 3)
        float32, mesh units, written into ``out`` when given (a C-contiguous float32 (n, 3) or
        (3n,) array) and returned. Raises ValueError for a weight that is not a number or beyond
        ±10."""
        w = np.asarray(weights)
        if w.dtype.kind not in "biuf" or w.ndim != 1:
            raise ValueError(
                f"weights: expected a 1-d array of numbers, one per key, got "
                f"{w.dtype} of shape {w.shape}"
            )
        if len(w) != self.num_keys:
            raise ValueError(f"weights: expected {self.num_keys} (one per key), got {len(w)}")
        w = np.ascontiguousarray(w, dtype=np.float64)
        bad = np.flatnonzero(~np.isfinite(w))
        if bad.size:
            raise ValueError(f"weights[{bad[0]}]: expected a number, got {w[bad[0]]}")
        out = _arrays.positions_out(out, self.num_vertices)
        self._native.blend(w, out.reshape(-1), **options)
        self._stats = self._native.stats
        return out

    def to_arrays(self):
        """dict[str, np.ndarray] of copies: the space's basis (``Basis.to_arrays``) and its own
        arrays, with a format version: what ``from_arrays`` reads back bit for bit."""
        arrays = self._basis.to_arrays()
        arrays["shape_space_version"] = np.array(FORMAT_VERSION, dtype=np.int32)
        arrays["base_dimension"] = np.array(self.base_dimension, dtype=np.int32)
        arrays["key_coordinates"] = np.array(self._native.coordinates, dtype=np.float64)
        arrays["key_residuals"] = np.array(self._native.residuals, dtype=np.float32)
        return arrays

    @classmethod
    def from_arrays(cls, arrays):
        """The ShapeSpace of a dict written by ``to_arrays`` (e.g. read back from a .blend file).

        Every array is checked before anything reads it (the basis as ``Basis.from_arrays`` does,
        then the space's own: dtypes, shapes, finiteness, the key columns' count); a ValueError
        names the first offending array. Nothing is baked: loading costs the keys' ghost energies
        and reduced Hessians, milliseconds.
        """
        try:
            keys = set(arrays.keys())
        except AttributeError:
            raise ValueError(
                f"arrays: expected a dict of numpy arrays, got {type(arrays).__name__}"
            ) from None
        own = {
            "shape_space_version": (np.int32, 0),
            "base_dimension": (np.int32, 0),
            "key_coordinates": (np.float64, 2),
            "key_residuals": (np.float32, 2),
        }
        for name, (dtype, ndim) in own.items():
            if name not in keys:
                raise ValueError(f"{name}: missing from the stored shape space")
            a = np.asarray(arrays[name])
            if a.dtype != dtype or a.ndim != ndim:
                raise ValueError(
                    f"{name}: expected {ndim} dimensions of {np.dtype(dtype)}, got {a.dtype} of "
                    f"shape {a.shape}"
                )
        version = int(arrays["shape_space_version"])
        if version != FORMAT_VERSION:
            raise ValueError(
                f"shape_space_version: this add-on reads version {FORMAT_VERSION}, got {version}; "
                f"rebuild the shape space"
            )
        basis = Basis.from_arrays({k: v for k, v in arrays.items() if k not in own})
        space = cls.__new__(cls)
        space._set_native(
            _native.ShapeSpace(
                basis._native,
                int(arrays["base_dimension"]),
                np.asfortranarray(arrays["key_coordinates"]),
                np.ascontiguousarray(arrays["key_residuals"]),
            )
        )
        return space

    def __repr__(self):
        return (
            f"<ShapeSpace: {self.num_vertices} vertices, {self.num_keys} keys, dimension "
            f"{self.dimension} ({self.base_dimension} of the basis)>"
        )
