"""Meshes: validation report, lumped mass, file reading and generated test shapes."""
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


def grid(nx, ny, width=1.0, height=1.0):
    """Flat grid of nx by ny quads (two triangles each) in the z = 0 plane, centred at 0."""
    return _native.grid(nx, ny, width, height)


def bumpy_plane(n, size=10.0, bumps=12, amplitude=1.0, seed=1):
    """Square n by n grid with Gaussian bumps (the Botsch–Sorkine bumpy plane)."""
    return _native.bumpy_plane(n, size, bumps, amplitude, seed)


def cylinder(around, along, radius=1.0, length=4.0):
    """Open tube along z from 0 to ``length``."""
    return _native.cylinder(around, along, radius, length)


def bar(nx, ny, nz, sx=1.0, sy=1.0, sz=4.0):
    """Closed surface of the box [0, sx] x [0, sy] x [0, sz], faces oriented outwards."""
    return _native.bar(nx, ny, nz, sx, sy, sz)
