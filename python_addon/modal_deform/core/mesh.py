"""Meshes: validation report, lumped mass and file reading (the test shapes are in ``testing``)."""

from .. import _native
from . import _arrays


def check(V, F):
    """Report what is awkward about the triangle mesh (V, F).

    Returns a dict with counts (``vertices``, ``faces``, ``edges``, ``components``,
    ``component_sizes``, largest first), ``vertex_component`` ((n,) int32: each vertex's connected
    component, -1 for a vertex in no face) and, for each of ``boundary_edges``,
    ``nonmanifold_edges``, ``nonmanifold_vertices``, ``unreferenced_vertices``,
    ``degenerate_faces`` and ``duplicate_faces``, a dict ``{"count": int, "first": [indices]}``.
    Raises ValueError for a mesh nothing can be computed on (no faces, a non-finite coordinate,
    an index out of range), naming the first offending vertex or face.
    """
    return _native.check(_arrays.vertices(V), _arrays.faces(F))


def mass(V, F):
    """Lumped vertex masses, (n,): a third of the area of the triangles around each vertex."""
    return _native.mass(_arrays.vertices(V), _arrays.faces(F))


def read_mesh(path):
    """Read an .obj or ASCII .ply file (optionally .gz) as (V (n,3) float64, F (m,3) int32)."""
    return _native.read_mesh(str(path))
