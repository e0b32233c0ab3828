"""Linear blend skinning, what Blender's Armature modifier shows, and the checks of a rig's inputs.

A rig is given by its skinning weights W, (n, b): one row per vertex, one column per bone, rows
summing to 1 (the Armature modifier's vertex groups, normalised), no negative weight, no vertex
weighted to no bone (the add-on gives unskinned vertices a column of their own whose matrix is the
object's world matrix, which is where the Armature modifier leaves them). A frame of the rig is B,
(b, 4, 4): each bone's world skinning matrix (the object's world matrix x the bone's pose x its rest
inverse), affine and invertible, scale and shear allowed.
"""

from typing import NamedTuple

import numpy as np

from .. import _native
from . import _arrays


class SkinningWeights(NamedTuple):
    """Checked skinning weights: the compressed rows (``row_pointers`` (n + 1,), ``columns`` and
    ``values`` alike long; a repeated column of a row adds) and the core's copy (``native``)."""

    shape: tuple
    row_pointers: np.ndarray
    columns: np.ndarray
    values: np.ndarray
    native: object


def skinning_weights(W, num_vertices):
    """W, (num_vertices, b), checked: a dense array, or a SciPy sparse matrix (read by its
    compressed rows; the add-on itself needs no SciPy, which Blender does not ship). Returns
    SkinningWeights; ValueError naming what is wrong."""
    if hasattr(W, "tocsr"):  # a SciPy sparse matrix
        W = W.tocsr()
        shape = tuple(W.shape)
        row_pointers, columns, values = W.indptr, W.indices, _arrays.reals(W.data, "rig")
    else:
        W = _arrays.reals(W, "rig")
        if W.ndim != 2:
            raise ValueError(f"rig: expected an (n, bones) matrix of weights, got shape {W.shape}")
        shape = W.shape
        rows, columns = np.nonzero(W)
        values = W[rows, columns]
        row_pointers = np.concatenate(([0], np.cumsum(np.bincount(rows, minlength=shape[0]))))
    if len(shape) != 2 or shape[0] != num_vertices:
        raise ValueError(
            f"rig: expected ({num_vertices}, bones) weights (one row per vertex), got {shape}"
        )
    row_pointers = _arrays.indices(row_pointers, "rig's row pointers")
    columns = _arrays.indices(columns, "rig's column indices")
    native = _native.SkinningWeights(shape[0], shape[1], row_pointers, columns, values)
    return SkinningWeights(shape, row_pointers, columns, values, native)


def bone_matrices(B, name="bones"):
    """B as a list of (4, 4) float64 matrices; their count and contents (finite, affine,
    invertible) are the core's to check (check_bone_matrices)."""
    B = _arrays.reals(B, name)
    if B.ndim != 3 or B.shape[1:] != (4, 4):
        raise ValueError(f"{name}: expected (bones, 4, 4) matrices (one per bone), got {B.shape}")
    return list(B)


def skin(X, W, B):
    """Linear blend skinning: Y_i = Σ_b W_ib B_b (X_i, 1), as the Armature modifier blends (Preserve
    Volume off). ``X``: (n, 3) positions in rest space (e.g. ``Simulation.step``'s), ``W``: (n, b)
    weights (dense or scipy sparse, checked as ``Simulation``'s ``rig``), ``B``: (b, 4, 4) affine
    bone matrices. Returns (n, 3) float64 world positions. Costs O(nonzero weights + n)."""
    X = _arrays.reals(X, "X")
    if X.ndim != 2 or X.shape[1] != 3:
        raise ValueError(f"X: expected (n, 3) positions, got shape {X.shape}")
    W = skinning_weights(W, X.shape[0])
    B = bone_matrices(B)
    _native.check_bone_matrices(B, W.shape[1])
    B = np.asarray(B)
    # Each vertex's blended 3x4 matrix A_i = Σ_b W_ib B_b[:3] (every row has a weight: checked),
    # then A_i (X_i, 1).
    terms = W.values[:, None] * B[W.columns, :3, :].reshape(-1, 12)
    A = np.add.reduceat(terms, W.row_pointers[:-1], axis=0).reshape(-1, 3, 4)
    return np.einsum("nij,nj->ni", A[:, :, :3], X) + A[:, :, 3]
