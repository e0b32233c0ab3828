"""Midpoint subdivision, the project's way of making dense meshes from the shared ones. NumPy
only: benchmarks running inside Blender import it beside the installed extension, which must be
the only modal_deform they load."""

import numpy as np


def _edges(F):
    """(the edges (#E, 2), per face the index of its edges 01, 12, 20 (m, 3))."""
    halfedges = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    edges, index = np.unique(np.sort(halfedges, axis=1), axis=0, return_inverse=True)
    return edges, index.reshape(3, -1).T


def midpoint_subdivide(V, F):
    """One level of midpoint subdivision: a vertex on every edge, each triangle split into four.
    (V (n, 3), F (m, 3)) -> (n + #edges vertices, 4m faces); the first n vertices are V."""
    F = np.asarray(F, dtype=np.int64)
    n = len(V)
    edges, index = _edges(F)
    index = index + n  # per face: the new vertex on edges 01, 12, 20
    V = np.vstack([V, 0.5 * (V[edges[:, 0]] + V[edges[:, 1]])])
    a, b, c = F.T
    ab, bc, ca = index.T
    F = np.concatenate([np.c_[a, ab, ca], np.c_[ab, b, bc], np.c_[ca, bc, c], np.c_[ab, bc, ca]])
    return V, F.astype(np.int32)


def split_edges(V, F, count):
    """A vertex on the `count` longest edges, the triangles split to match (red-green refinement:
    one edge split, two triangles; two, three; three, four), so vertex counts between midpoint
    subdivision's factors of 4 can be made (count = len(V): twice the vertices). Longest first, as
    in longest-edge bisection, so no triangle is cut into slivers (random edges made a proxy of the
    3.2M dragon whose stiffness matrix would not factor). (V, F) -> (n + count vertices, faces);
    the first n are V."""
    F = np.asarray(F, dtype=np.int64)
    n = len(V)
    edges, index = _edges(F)
    lengths = np.linalg.norm(V[edges[:, 0]] - V[edges[:, 1]], axis=1)
    chosen = np.argpartition(-lengths, count - 1)[:count]
    midpoint = np.full(len(edges), -1, np.int64)
    midpoint[chosen] = n + np.arange(count)
    V = np.vstack([V, 0.5 * (V[edges[chosen, 0]] + V[edges[chosen, 1]])])
    split = midpoint[index]  # per face: the new vertex on edges 01, 12, 20, or -1
    count_split = (split >= 0).sum(axis=1)
    # Turn each face's corners so that a single split edge is 01 and a single unsplit edge is 20.
    for turn in range(3):
        corners, mids = np.roll(F, -turn, axis=1), np.roll(split, -turn, axis=1)
        if turn == 0:
            F_turned, split_turned = corners.copy(), mids.copy()
            done = count_split != 1
            done &= count_split != 2
        pick = ~done & (
            ((count_split == 1) & (mids[:, 0] >= 0)) | ((count_split == 2) & (mids[:, 2] < 0))
        )
        F_turned[pick], split_turned[pick] = corners[pick], mids[pick]
        done |= pick
    a, b, c = F_turned.T
    ab, bc, ca = split_turned.T
    one, two, three = count_split == 1, count_split == 2, count_split == 3
    faces = [
        F[count_split == 0],
        np.c_[a, ab, c][one],
        np.c_[ab, b, c][one],
        np.c_[ab, b, bc][two],
        np.c_[a, ab, bc][two],
        np.c_[a, bc, c][two],
        np.c_[a, ab, ca][three],
        np.c_[ab, b, bc][three],
        np.c_[ca, bc, c][three],
        np.c_[ab, bc, ca][three],
    ]
    return V, np.concatenate(faces).astype(np.int32)
