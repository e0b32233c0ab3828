"""Raw-scan-like meshes made from the shared dragons: the damage a range scan brings, on purpose.

A raw scan (the full-resolution Stanford dragon: 437k vertices, 1,116 zero-area faces, 151
components, holes, non-manifold edges) is kept out of the shared meshes, so the corpus makes its
own from the shared, decimated dragons: midpoint subdivision for the size, then every kind of
damage a scan has, each placed at random (seeded) and in proportion to the mesh's size:

- slivers: a vertex inserted just inside a face, next to one of its edges, splits the face into two
  sound triangles and one sliver whose shape ratio is log-uniform in [1e-9, 1e-1] (around and
  far below the bake's threshold for simulating a face);
- sliver pairs: the same on both faces of an edge, with shape ratios log-uniform in
  [1e-3, 1e-2], just thick enough to be simulated: the hinge between the two slivers is the
  stiffest element a scan has (about 0.3 / ratio³ times an equilateral hinge before the bake
  bounds it);
- needles and near-coincident vertices: an edge split very close to one end (relative distance
  log-uniform in [1e-10, 1e-2]) gives two needles on either side and two vertices almost at one
  place, both still on sound faces;
- seams: a vertex duplicated a tiny distance away and used by half its faces (a crack);
- duplicated faces, and duplicates with flipped orientation (double sheets);
- flipped faces (inconsistent orientation);
- zero-area faces: faces with a repeated index, and collinear triples;
- holes: faces removed around a few seeds;
- non-manifold edges: fins standing on interior edges;
- debris: small floating clusters of triangles (many components).

    V, F = raw_scans.damaged(*mdc.read_mesh(path), seed=1)
    V, F = raw_scans.raw_scan("dragon_res2")      # ~400k vertices, every kind of damage
"""

import numpy as np

from support.meshes import read_scan
from support.subdivision import midpoint_subdivide

#: What each kind of damage does to a mesh, per 10,000 faces of the input.
RATES = {
    "slivers": 20,
    "sliver_pairs": 2,
    "needles": 10,
    "seams": 3,
    "duplicates": 4,
    "double_sheets": 2,
    "flips": 20,
    "zero_area": 5,
    "holes": 0.3,
    "fins": 2,
    "debris": 3,
}


def _log_uniform(rng, low, high, size):
    return np.exp(rng.uniform(np.log(low), np.log(high), size))


def _faces_on_both_sides(F, touched, k, rng):
    """Up to k interior edges with exactly two faces, neither `touched`, chosen at random: their
    faces (2k,), side by side, and those faces' rows rotated so that the edge comes first."""
    halfedges = np.concatenate([F[:, [0, 1]], F[:, [1, 2]], F[:, [2, 0]]])
    face = np.tile(np.arange(len(F)), 3)
    first = np.repeat([0, 1, 2], len(F))
    _, inverse, counts = np.unique(
        np.sort(halfedges, axis=1), axis=0, return_inverse=True, return_counts=True
    )
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    starts = np.flatnonzero(counts[inverse[order]] == 2)
    starts = starts[(np.arange(len(starts)) % 2 == 0)]  # the first half-edge of each such edge
    both = np.c_[order[starts], order[starts + 1]]
    both = both[~touched[face[both]].any(axis=1) & (face[both[:, 0]] != face[both[:, 1]])]
    both = both[rng.permutation(len(both))]
    chosen, seen = [], set()
    for h in both:
        faces = set(face[h])
        if faces & seen:
            continue
        seen |= faces
        chosen.append(h)
        if len(chosen) == k:
            break
    h = np.array(chosen, dtype=np.int64).reshape(-1)
    rows = np.arange(3)[None, :] + first[h][:, None]
    return face[h], np.take_along_axis(F[face[h]], rows % 3, axis=1)


def damaged(V, F, seed=0, rates=None):
    """(V, F) with every kind of damage of RATES (per 10,000 input faces; `rates` overrides some)
    added at random places chosen by `seed`. Returns new arrays (float64, int32)."""
    rates = {**RATES, **(rates or {})}
    rng = np.random.default_rng(seed)
    V = [np.asarray(V, dtype=np.float64)]
    F = np.asarray(F, dtype=np.int64).copy()
    n_total = len(V[0])
    extent = np.ptp(V[0], axis=0).max()

    def count(kind):
        return int(round(rates[kind] * len(F) / 1e4))

    def add_vertices(P):
        nonlocal n_total
        first = n_total
        V.append(np.atleast_2d(P))
        n_total += len(V[-1])
        return np.arange(first, n_total)

    positions = lambda: np.vstack(V)  # noqa: E731
    # Damage in place first (the face list keeps its order), then appended faces.
    touched = np.zeros(len(F), bool)

    def pick(k):
        free = np.flatnonzero(~touched)
        chosen = rng.choice(free, size=min(k, len(free)), replace=False)
        touched[chosen] = True
        return chosen

    new_faces = []
    P = positions()

    def insert_slivers(faces, rotated, ratio):
        """Face (a, b, c) (its rows `rotated`) -> (a, p, c), (p, b, c) and the sliver (a, b, p), p
        inside next to the middle of (a, b), `ratio` of its length off it."""
        a, b, c = rotated.T
        foot = 0.5 * (P[a] + P[b])
        towards = P[c] - foot
        towards /= np.linalg.norm(towards, axis=1)[:, None]
        p = add_vertices(foot + (ratio * np.linalg.norm(P[b] - P[a], axis=1))[:, None] * towards)
        F[faces] = np.c_[a, p, c]
        new_faces.extend([np.c_[p, b, c], np.c_[a, b, p]])

    # Slivers on the first edge of random faces.
    faces = pick(count("slivers"))
    insert_slivers(faces, F[faces], _log_uniform(rng, 1e-9, 1e-1, len(faces)))
    # Sliver pairs: both faces of an interior edge, each rotated to start with that edge.
    faces, rotated = _faces_on_both_sides(F, touched, count("sliver_pairs"), rng)
    touched[faces] = True
    insert_slivers(faces, rotated, np.repeat(_log_uniform(rng, 1e-3, 1e-2, len(faces) // 2), 2))
    # Needles: edge (a, b) of a face split at a relative distance t from a, in this face only (the
    # neighbour keeps the whole edge: a T-junction, as scans have at patch seams).
    faces = pick(count("needles"))
    t = _log_uniform(rng, 1e-10, 1e-2, len(faces))
    a, b, c = F[faces].T
    p = add_vertices(P[a] + t[:, None] * (P[b] - P[a]))
    F[faces] = np.c_[a, p, c]
    new_faces.append(np.c_[p, b, c])
    # Seams: vertex a of a face duplicated 1e-9 of the extent away, used by that face only.
    faces = pick(count("seams"))
    a = F[faces, 0]
    F[faces, 0] = add_vertices(P[a] + 1e-9 * extent * rng.standard_normal((len(faces), 3)))
    # Flips.
    faces = pick(count("flips"))
    F[faces] = F[faces, ::-1]
    # Holes: a face and its neighbours' neighbours removed.
    keep = np.ones(len(F), bool)
    for seed_face in rng.choice(len(F), size=count("holes"), replace=False):
        ring = set(F[seed_face])
        for _ in range(2):
            ring |= set(F[np.isin(F, list(ring)).any(axis=1)].ravel())
        keep &= ~np.isin(F, list(ring)).all(axis=1)
    F = F[keep]
    P = positions()
    # Appended: duplicates, double sheets, zero-area faces, fins, debris.
    new_faces.append(F[rng.choice(len(F), count("duplicates"), replace=False)])
    new_faces.append(F[rng.choice(len(F), count("double_sheets"), replace=False)][:, ::-1])
    chosen = F[rng.choice(len(F), count("zero_area"), replace=False)]
    half = len(chosen) // 2
    new_faces.append(
        np.c_[chosen[:half, 0], chosen[:half, 1], chosen[:half, 1]]
    )  # a repeated index
    ends = chosen[half:]
    middle = add_vertices(0.5 * (P[ends[:, 0]] + P[ends[:, 1]]))  # collinear with its edge
    new_faces.append(np.c_[ends[:, 0], ends[:, 1], middle])
    chosen = F[rng.choice(len(F), count("fins"), replace=False)]
    normal = np.cross(P[chosen[:, 1]] - P[chosen[:, 0]], P[chosen[:, 2]] - P[chosen[:, 0]])
    normal /= np.maximum(np.linalg.norm(normal, axis=1), 1e-300)[:, None]
    edge = np.linalg.norm(P[chosen[:, 1]] - P[chosen[:, 0]], axis=1)[:, None]
    top = add_vertices(0.5 * (P[chosen[:, 0]] + P[chosen[:, 1]]) + edge * normal)
    new_faces.append(np.c_[chosen[:, 0], chosen[:, 1], top])
    for _ in range(count("debris")):
        centre = P[rng.integers(len(P))] + 0.02 * extent * rng.standard_normal(3)
        size = _log_uniform(rng, 1e-4, 1e-2, 1)[0] * extent
        k = int(rng.integers(1, 6))
        corners = add_vertices(centre + size * rng.standard_normal((k + 2, 3)))
        new_faces.append(np.c_[np.full(k, corners[0]), corners[1:-1], corners[2:]])
    F = np.vstack([F] + [f.reshape(-1, 3) for f in new_faces])
    return positions(), F.astype(np.int32)


def raw_scan(name="dragon_res2", levels=1, seed=0, rates=None):
    """A shared scan midpoint-subdivided `levels` times and damaged (dragon_res2, one level: about
    400k vertices)."""
    V, F = read_scan(name)
    for _ in range(levels):
        V, F = midpoint_subdivide(V, F)
    return damaged(V, F, seed=seed, rates=rates)
