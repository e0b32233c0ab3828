"""Shape and dtype checks at the boundary to the native core.

Each function returns an array the native core takes without a copy (C order, the right dtype)
and raises ValueError naming the argument when the input cannot be one. Contents (index ranges,
finiteness) are checked by the native core, which must refuse bad data on its own anyway.
"""

import operator

import numpy as np


def reals(x, name):
    """x as a float64 array; a ValueError naming `name` for anything that is not real numbers
    (strings, objects, complex values, None)."""
    x = np.asarray(x)
    if x.dtype.kind not in "biuf":
        raise ValueError(f"{name}: expected real numbers, got dtype {x.dtype}")
    return np.ascontiguousarray(x, dtype=np.float64)


def vertices(V, name="V"):
    """(n, 3) float64, C order."""
    V = reals(V, name)
    if V.ndim != 2 or V.shape[1] != 3:
        raise ValueError(f"{name}: expected an (n, 3) array of positions, got shape {V.shape}")
    return V


def faces(F, name="F"):
    """(m, 3) int32, C order; larger integer types are narrowed when their values fit."""
    F = np.asarray(F)
    if F.ndim != 2 or F.shape[1] != 3:
        raise ValueError(
            f"{name}: expected an (m, 3) array of triangle indices, got shape {F.shape}"
        )
    if F.dtype.kind not in "iu":
        raise ValueError(f"{name}: expected integer indices, got dtype {F.dtype}")
    if F.size and (F.max() > np.iinfo(np.int32).max or F.min() < np.iinfo(np.int32).min):
        raise ValueError(f"{name}: an index does not fit in 32 bits")
    return np.ascontiguousarray(F, dtype=np.int32)


def positions(X, num_vertices, name="X"):
    """Flat (3n,) float64 view of an (n, 3) or (3n,) array of positions or displacements."""
    X = reals(X, name)
    if X.shape not in ((num_vertices, 3), (3 * num_vertices,)):
        raise ValueError(
            f"{name}: expected shape ({num_vertices}, 3) or ({3 * num_vertices},), got {X.shape}"
        )
    return X.reshape(-1)


def positions_out(out, num_vertices):
    """Where to write x̄ + U q: a new (n, 3) float32 array, or ``out`` once checked to be a writeable
    C-contiguous float32 array of shape (n, 3) or (3n,) (e.g. the buffer of Blender's
    ``foreach_set("co", ...)``)."""
    n = num_vertices
    if out is None:
        return np.empty((n, 3), dtype=np.float32)
    if not (
        isinstance(out, np.ndarray)
        and out.dtype == np.float32
        and out.flags.c_contiguous
        and out.flags.writeable
        and out.shape in ((n, 3), (3 * n,))
    ):
        raise ValueError(
            f"out: expected a writeable C-contiguous float32 array of shape ({n}, 3) or ({3 * n},), "
            f"got {getattr(out, 'dtype', type(out).__name__)} {getattr(out, 'shape', '')}"
        )
    return out


def values(x, name, length=None):
    """(length,) float64, C order."""
    x = reals(x, name)
    if x.ndim != 1 or (length is not None and x.shape[0] != length):
        expected = f"({length},)" if length is not None else "a 1-d array"
        raise ValueError(f"{name}: expected {expected}, got shape {x.shape}")
    return x


def stiffness_weights(w, num_vertices):
    """(num_vertices,) float64 weights painted per vertex, or (0,) for None or no weights (a
    uniform material, as a basis baked without paint stores it); values are checked natively."""
    if w is None or np.size(w) == 0:
        return np.zeros(0)
    return values(w, "stiffness_weights", num_vertices)


def indices(x, name):
    """(k,) int32 vertex indices from integer input (ranges and repeats are checked natively)."""
    x = np.asarray(x)
    if x.ndim != 1 or (x.size and x.dtype.kind not in "iu"):
        raise ValueError(
            f"{name}: expected a 1-d array of vertex indices, got dtype {x.dtype} and shape {x.shape}"
        )
    if x.size and (x.max() > np.iinfo(np.int32).max or x.min() < np.iinfo(np.int32).min):
        raise ValueError(f"{name}: an index does not fit in 32 bits")
    return np.ascontiguousarray(x, dtype=np.int32)


def labels(x, length, name="labels"):
    """(length,) int32 from integer input."""
    x = np.asarray(x)
    if x.shape != (length,):
        raise ValueError(f"{name}: expected shape ({length},), got {x.shape}")
    if x.dtype.kind not in "iu":
        raise ValueError(f"{name}: expected integers, got dtype {x.dtype}")
    if x.size and (x.max() > np.iinfo(np.int32).max or x.min() < np.iinfo(np.int32).min):
        raise ValueError(f"{name}: a label does not fit in 32 bits")
    return np.ascontiguousarray(x, dtype=np.int32)


def columns(X, rows, name):
    """(rows, k) float64 in Fortran order, the native core's column-major layout; a (rows,)
    vector becomes one column."""
    X = reals(X, name)
    if X.ndim == 1:
        X = X[:, None]
    if X.ndim != 2 or X.shape[0] != rows:
        raise ValueError(f"{name}: expected shape ({rows}, k), got {X.shape}")
    return np.asfortranarray(X)


def number(x, name):
    """A float from a real number (Python or numpy); a ValueError naming `name` otherwise."""
    if isinstance(x, (str, bytes)):
        raise ValueError(f"{name}: expected a number, got {x!r}")
    try:
        return float(x)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected a number, got {x!r}") from None


def integer(x, name):
    """An int from an integer (Python or numpy, not a float or bool-like string); a ValueError
    naming `name` otherwise."""
    try:
        return operator.index(x)
    except TypeError:
        raise ValueError(f"{name}: expected an integer, got {x!r}") from None
