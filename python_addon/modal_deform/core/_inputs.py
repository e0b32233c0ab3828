"""What the solvers and the simulation take and check alike: a baked basis, handles, their
transforms and weights, and the base class of the objects that move a basis's mesh by q. Shapes and
types are checked here; ranges and contents natively."""

import numpy as np

from . import _arrays
from .bake import Basis


def basis(basis):
    """``basis`` once checked to be a Basis: what the solvers and the simulation take."""
    if not isinstance(basis, Basis):
        raise ValueError(
            f"basis: expected a modal_deform.core.Basis (from bake or Basis.from_arrays), "
            f"got {type(basis).__name__}"
        )
    return basis


def handles(handles):
    """A non-empty list of non-empty 1-d int32 arrays (ranges and repeats are checked natively)."""
    if isinstance(handles, np.ndarray) and handles.ndim == 1 and handles.dtype.kind in "iu":
        raise ValueError(
            "handles: expected a list of index arrays, one per handle, got a single index array "
            "(wrap it in a list for one handle)"
        )
    try:
        handles = list(handles)
    except TypeError:
        raise ValueError(
            f"handles: expected a list of index arrays, got {type(handles).__name__}"
        ) from None
    if not handles:
        raise ValueError("handles: no handle given; posing needs at least one")
    arrays = []
    for h, indices in enumerate(handles):
        indices = np.asarray(indices)
        if indices.ndim != 1 or indices.size == 0:
            raise ValueError(
                f"handles[{h}]: expected a non-empty 1-d array of vertex indices, got shape {indices.shape}"
            )
        if indices.dtype.kind not in "iu":
            raise ValueError(
                f"handles[{h}]: expected integer vertex indices, got dtype {indices.dtype}"
            )
        if indices.max() > np.iinfo(np.int32).max or indices.min() < np.iinfo(np.int32).min:
            raise ValueError(f"handles[{h}]: an index does not fit in 32 bits")
        arrays.append(np.ascontiguousarray(indices, dtype=np.int32))
    return arrays


def transforms(transforms, count):
    """One (4, 4) float64 matrix per handle (rigidity is checked natively)."""
    transforms = [_arrays.reals(T, f"transforms[{h}]") for h, T in enumerate(transforms)]
    if len(transforms) != count:
        raise ValueError(f"transforms: expected {count} (one per handle), got {len(transforms)}")
    for h, T in enumerate(transforms):
        if T.shape != (4, 4):
            raise ValueError(f"transforms[{h}]: expected a 4x4 matrix, got shape {T.shape}")
    return transforms


def weights(weights, count):
    if weights is None:
        return np.ones(count)
    return _arrays.values(weights, "weights", count)


def is_empty(sequence):
    """True for None, an empty list/tuple or an empty array."""
    return sequence is None or (hasattr(sequence, "__len__") and len(sequence) == 0)


class InBasis:
    """What ReducedSolver and Simulation share: a native object (``self._native``) that moves the
    mesh of ``self._basis`` by the reduced coordinates q."""

    @property
    def num_vertices(self):
        return self._basis.num_vertices

    @property
    def dimension(self):
        """r, the number of reduced coordinates (basis.vectors' columns)."""
        return self._native.dimension

    def positions(self, out=None):
        """x̄ + U q on the fine mesh: (n, 3) float32, mesh units.

        With ``out`` (a C-contiguous float32 array of shape (n, 3) or (3n,), e.g. the buffer passed
        to Blender's ``foreach_set("co", ...)``) the result is written there and ``out`` returned.
        """
        out = _arrays.positions_out(out, self.num_vertices)
        self._native.positions(out.reshape(-1))
        return out
