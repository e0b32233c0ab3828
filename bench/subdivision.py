"""Midpoint subdivision, the project's way of making dense meshes from the shared ones. NumPy
only: benchmarks running inside Blender import it beside the installed extension, which must be
the only modal_deform they load."""
import numpy as np


def midpoint_subdivide(V, F):
    """One level of midpoint subdivision: a vertex on every edge, each triangle split into four.
    (V (n, 3), F (m, 3)) -> (n + #edges vertices, 4m faces); the first n vertices are V."""
    F = np.asarray(F, dtype=np.int64)
    n = len(V)
    halfedges = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    keys = np.sort(halfedges, axis=1)
    edges, index = np.unique(keys, axis=0, return_inverse=True)
    index = index.reshape(3, -1).T + n  # per face: the new vertex on edges 01, 12, 20
    V = np.vstack([V, 0.5 * (V[edges[:, 0]] + V[edges[:, 1]])])
    a, b, c = F.T
    ab, bc, ca = index.T
    F = np.concatenate([np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]])
    return V, F.astype(np.int32)
