"""The ghost: a coarse mesh made by edge collapse, and the restriction of fine vectors to it.

Each fine vertex collapses onto one ghost vertex; a ghost quantity is the lumped-mass-weighted
mean of the fine quantity over the vertices collapsed onto it (paper section 5).
"""

import numpy as np

from .. import _native
from . import _arrays

_INT32_MAX = np.iinfo(np.int32).max


def ghost_mesh(V, F, vertices=1000, progress=None):
    """Simplify the triangle mesh (V, F) by edge collapse to about ``vertices`` vertices.

    Returns ``(Vg, Fg, ghost_map)``: ghost positions (g, 3) float64, ghost triangles (h, 3)
    int32, and ghost_map (n,) int32, the ghost vertex each fine vertex collapses onto. Each ghost
    vertex sits at the lumped-mass-weighted centroid of its fine vertices. ``vertices`` must be
    at least 4; g is larger when no valid collapse is left, and ``vertices >= n`` gives the mesh
    itself with the identity map. ``progress(stage, fraction)`` is called now and then; returning
    False raises ``Cancelled``.
    """
    V, F = _arrays.vertices(V), _arrays.faces(F)
    vertices = _arrays.integer(vertices, "vertices")
    if vertices < 4:
        raise ValueError(f"vertices: a ghost needs at least 4 vertices, got {vertices}")
    if progress is not None and not callable(progress):
        raise ValueError(
            f"progress: expected a callable progress(stage, fraction) or None, got {progress!r}"
        )
    return _native.ghost_mesh(V, F, min(vertices, _INT32_MAX), progress)


def restrict_to_ghost(ghost_map, mass, U):
    """Restrict fine vectors to the ghost: the ``mass``-weighted mean per ghost vertex.

    ghost_map (n,) from ghost_mesh, mass (n,) lumped masses (``mdc.mass``), U (3n,) or (3n, r)
    with coordinates interleaved (x0 y0 z0 x1 ...). Returns (3g,) or (3g, r) float64 with
    g = ghost_map.max() + 1; every ghost vertex needs a fine vertex.
    """
    ghost_map = np.asarray(ghost_map)
    if ghost_map.ndim != 1 or ghost_map.size == 0 or ghost_map.dtype.kind not in "iu":
        raise ValueError(
            f"ghost_map: expected a non-empty (n,) integer array, got shape {ghost_map.shape} "
            f"dtype {ghost_map.dtype}"
        )
    if ghost_map.min() < 0 or ghost_map.max() >= _INT32_MAX:
        raise ValueError(
            f"ghost_map: expected indices in [0, {_INT32_MAX}), got [{ghost_map.min()}, {ghost_map.max()}]"
        )
    mass = np.ascontiguousarray(mass, dtype=np.float64)
    if mass.shape != ghost_map.shape:
        raise ValueError(
            f"mass: expected shape {ghost_map.shape} (one per fine vertex), got {mass.shape}"
        )
    U = np.asarray(U, dtype=np.float64)
    if U.ndim not in (1, 2) or U.shape[0] != 3 * ghost_map.size:
        raise ValueError(
            f"U: expected shape ({3 * ghost_map.size},) or ({3 * ghost_map.size}, r), got {U.shape}"
        )
    restricted = _native.restrict_to_ghost(
        np.ascontiguousarray(ghost_map, dtype=np.int32),
        int(ghost_map.max()) + 1,
        mass,
        np.asfortranarray(U.reshape(U.shape[0], -1)),
    )
    return restricted.reshape(-1) if U.ndim == 1 else restricted
