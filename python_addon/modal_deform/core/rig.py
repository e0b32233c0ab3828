"""Linear blend skinning, what Blender's Armature modifier shows, and the checks of a rig's inputs.

A rig is given by its skinning weights W, (n, b): one row per vertex, one column per bone, rows
summing to 1 (the Armature modifier's vertex groups, normalised), no negative weight, no vertex
weighted to no bone (the add-on gives unskinned vertices a column of their own whose matrix is the
object's world matrix, which is where the Armature modifier leaves them). A frame of the rig is B,
(b, 4, 4): each bone's world skinning matrix (the object's world matrix x the bone's pose x its rest
inverse), affine and invertible, scale and shear allowed.
"""

import numpy as np
import scipy.sparse

from .. import _native
from . import _arrays


def skinning_weights(W, num_vertices):
    """W as a (num_vertices, b) CSR matrix of float64 (dense arrays and any scipy sparse format
    taken), checked: ValueError naming what is wrong."""
    if scipy.sparse.issparse(W):
        W = scipy.sparse.csr_matrix(W, dtype=np.float64)
    else:
        W = _arrays.reals(W, "rig")
        if W.ndim != 2:
            raise ValueError(f"rig: expected an (n, bones) matrix of weights, got shape {W.shape}")
        W = scipy.sparse.csr_matrix(W)
    if W.ndim != 2 or W.shape[0] != num_vertices:
        raise ValueError(
            f"rig: expected ({num_vertices}, bones) weights (one row per vertex), got {W.shape}"
        )
    try:  # the index arrays of a matrix built from them are not checked by scipy
        W.check_format(full_check=True)
    except ValueError as error:
        raise ValueError(f"rig: not a valid sparse matrix ({error})") from None
    W.sum_duplicates()
    W.sort_indices()
    _native.check_skinning_weights(W, num_vertices)
    return W


def bone_matrices(B, num_bones, name="bones"):
    """B as a list of num_bones (4, 4) float64 matrices, checked (finite, affine, invertible)."""
    B = _arrays.reals(B, name)
    if B.ndim != 3 or B.shape[1:] != (4, 4) or B.shape[0] != num_bones:
        raise ValueError(
            f"{name}: expected ({num_bones}, 4, 4) matrices (one per bone), got shape {B.shape}"
        )
    B = list(B)
    _native.check_bone_matrices(B, num_bones)
    return B


def skin(X, W, B):
    """Linear blend skinning: Y_i = Σ_b W_ib B_b (X_i, 1), as the Armature modifier blends (Preserve
    Volume off). ``X``: (n, 3) positions in rest space (e.g. ``Simulation.step``'s), ``W``: (n, b)
    weights (dense or scipy sparse, checked as ``Simulation``'s ``rig``), ``B``: (b, 4, 4) affine
    bone matrices. Returns (n, 3) float64 world positions. Costs O(nonzero weights + n)."""
    X = _arrays.reals(X, "X")
    if X.ndim != 2 or X.shape[1] != 3:
        raise ValueError(f"X: expected (n, 3) positions, got shape {X.shape}")
    W = skinning_weights(W, X.shape[0])
    B = np.asarray(bone_matrices(B, W.shape[1]))
    # Each vertex's blended 3x4 matrix A_i = Σ_b W_ib B_b[:3], then A_i (X_i, 1).
    A = (W @ B[:, :3, :].reshape(W.shape[1], 12)).reshape(-1, 3, 4)
    return np.einsum("nij,nj->ni", A[:, :, :3], X) + A[:, :, 3]
