"""The bake: from a mesh to the reduced shape space the solver poses in (paper sections 4, 5).

    basis = mdc.bake(V, F, modes=20, derivatives=52, ghost=1000)
    x = basis.rest.reshape(-1) + basis.vectors @ q          # any q of length basis.dimension

The basis holds the rigid motions of the simulated components, the lowest vibration modes of the
energy's Hessian at rest, and modal derivatives (eq. 13), M-orthonormal in the normalised frame
(longest bounding-box edge 10), with a ghost (a coarse mesh) and the basis restricted to it.
Scan debris (components with less than 10% of the largest one's area), unreferenced vertices and
vertices without mass are not simulated: they follow the affine motion of nearby simulated
vertices, so they move rigidly with the mesh.
"""
import warnings

import numpy as np

from .. import _native
from . import _arrays

FORMAT_VERSION = 2  # 2: the prolongation of a basis baked on a proxy (version 1 has none)

#: ``bake``'s defaults for dense meshes: more than PROXY_ABOVE vertices are baked on a proxy of
#: about PROXY vertices. Measured on the shared 2-core machine (bench/multires.py, docs): the
#: 100k dragon bakes as it is in about 20 s within 2.1 GB, while a raw scan of 406k took
#: 1120 s and 9 GB; on the dragon subdivided twice (1.6M), a 50k proxy bakes in about 24 s and a
#: 100k one in 34 s, and both pose within 0.3% RMS of the 100k dragon's own bake.
PROXY_ABOVE = 150_000
PROXY = 50_000

# name: (dtype, number of dimensions) of each array to_arrays writes; shapes are checked
# natively against each other (validate_basis).
_ARRAYS = {
    "format_version": (np.int32, 0),
    "rest": (np.float64, 2),
    "mass": (np.float64, 1),
    "vectors": (np.float32, 2),
    "num_rigid": (np.int32, 0),
    "num_modes": (np.int32, 0),
    "num_floppy": (np.int32, 0),
    "eigenvalues": (np.float64, 1),
    "ghost_vertices": (np.float64, 2),
    "ghost_faces": (np.int32, 2),
    "ghost_map": (np.int32, 1),
    "ghost_vectors": (np.float64, 2),
    "scale": (np.float64, 0),
    "bending": (np.float64, 0),
    "membrane": (np.float64, 0),
    "num_dropped": (np.int32, 0),
    "prolongation_vertices": (np.int32, 2),
    "prolongation_weights": (np.float32, 2),
}
_SINCE_VERSION_2 = ("prolongation_vertices", "prolongation_weights")


class Basis:
    """A baked reduced space: fine positions x = x̄ + U q in the mesh's units.

    Arrays are read-only views of the native basis (no copies). ``vectors`` (3n, r) float32 holds
    the rigid motions (``num_rigid`` columns), then the vibration modes (up to ``num_modes``), then
    the modal derivatives; ``modes`` is a view of the first ``num_modes`` columns.
    ``eigenvalues`` (num_modes,) are those of the normalised frame, ascending (0 for the rigid
    motions). ``num_floppy`` modes after the rigid ones are zero modes of a floppy mesh
    (mechanisms, e.g. flaps at non-manifold vertices); ``num_dropped`` derivatives were dropped as
    numerically dependent. ``ghost_vertices`` (g, 3), ``ghost_faces`` (h, 3) int32 and
    ``ghost_map`` (n,) int32 describe the ghost, ``ghost_vectors`` (3g, r) the restricted basis.
    ``timings`` maps each bake stage to seconds.

    A dense mesh baked on a proxy (``on_proxy``) keeps the proxy's basis: ``vectors`` is then
    (3p, r) over its ``num_basis_vertices`` = p vertices, and each fine vertex i moves with
    ``prolongation_weights[i]`` (3,) float32 (barycentric) of the proxy vertices
    ``prolongation_vertices[i]`` (3,) int32: x_i = x̄_i + Σ_k w_ik (U q)_{v_ik}. Both are (0, 3)
    for a basis of the mesh itself. ``fine_vectors(columns)`` gives the fine (3n, c) basis in either case.
    """

    def __init__(self, native):
        self._native = native

    rest = property(lambda self: self._native.rest, doc="(n, 3) float64 rest positions")
    mass = property(lambda self: self._native.mass, doc="(n,) float64 lumped vertex masses (mesh units)")
    vectors = property(lambda self: self._native.vectors, doc="(3n, r) float32 basis vectors U")
    eigenvalues = property(lambda self: self._native.eigenvalues, doc="(num_modes,) float64, ascending")
    ghost_vertices = property(lambda self: self._native.ghost_vertices, doc="(g, 3) float64")
    ghost_faces = property(lambda self: self._native.ghost_faces, doc="(h, 3) int32")
    ghost_map = property(lambda self: self._native.ghost_map, doc="(n,) int32 fine vertex -> ghost vertex")
    ghost_vectors = property(lambda self: self._native.ghost_vectors, doc="(3g, r) float64")
    num_rigid = property(lambda self: self._native.num_rigid)
    num_modes = property(lambda self: self._native.num_modes)
    num_floppy = property(lambda self: self._native.num_floppy)
    num_dropped = property(lambda self: self._native.num_dropped)
    scale = property(lambda self: self._native.scale, doc="factor from mesh units to the normalised frame")
    bending = property(lambda self: self._native.bending)
    membrane = property(lambda self: self._native.membrane)
    dimension = property(lambda self: self._native.dimension, doc="r, the number of basis vectors")
    num_vertices = property(lambda self: self._native.num_vertices)
    on_proxy = property(lambda self: self._native.on_proxy, doc="baked on a proxy of the mesh")
    num_basis_vertices = property(lambda self: self._native.num_basis_vertices,
                                  doc="vertices of vectors' rows: the proxy's, or n")
    prolongation_vertices = property(lambda self: self._native.prolongation_vertices, doc="(n, 3) or (0, 3) int32")
    prolongation_weights = property(lambda self: self._native.prolongation_weights, doc="(n, 3) or (0, 3) float32")

    def fine_vectors(self, columns=slice(None)):
        """(3n, c) float32: the basis vectors ``columns`` (default all r) on the fine mesh: a view of
        ``vectors``, or their prolongation from the proxy (a new array; at 1.6M vertices all 67 take
        1.3 GB, so ask for the columns needed)."""
        if not self.on_proxy:
            return self.vectors[:, columns]
        U = self.vectors[:, columns].reshape(self.num_basis_vertices, 3, -1)
        fine = np.einsum("nk,nkcr->ncr", self.prolongation_weights, U[self.prolongation_vertices])
        return fine.reshape(3 * self.num_vertices, -1)

    @property
    def modes(self):
        """(3n, num_modes) float32: the first columns of ``vectors`` (a view)."""
        return self.vectors[:, :self.num_modes]

    @property
    def timings(self):
        """dict: seconds spent in each stage of the bake (empty for a basis read back)."""
        return dict(self._native.timings)

    def __repr__(self):
        return (f"<Basis: {self.num_vertices} vertices, dimension {self.dimension} ({self.num_rigid} rigid, "
                f"{self.num_modes} modes, {self.dimension - self.num_modes} derivatives), "
                f"ghost {len(self.ghost_vertices)} vertices"
                f"{f', proxy {self.num_basis_vertices} vertices' if self.on_proxy else ''}>")

    def to_arrays(self):
        """dict[str, np.ndarray] of copies, counts and scalars as 0-d arrays, with a format version:
        what from_arrays reads back bit for bit (timings are not kept)."""
        arrays = {"format_version": np.array(FORMAT_VERSION, dtype=np.int32)}
        for name, (dtype, _) in _ARRAYS.items():
            if name != "format_version":
                arrays[name] = np.array(getattr(self, name), dtype=dtype)
        return arrays

    @classmethod
    def from_arrays(cls, arrays):
        """The Basis of a dict written by to_arrays, e.g. read back from a .blend file.

        Every array is checked (dtype, number of dimensions, then natively its shape against the
        others, finiteness, index ranges and counts) before anything reads it; a ValueError names
        the first offending array.
        """
        try:
            keys = set(arrays.keys())
        except AttributeError:
            raise ValueError(f"arrays: expected a dict of numpy arrays, got {type(arrays).__name__}") from None
        checked = {}
        for name, (dtype, ndim) in _ARRAYS.items():
            if name not in keys and name in _SINCE_VERSION_2 and int(checked["format_version"]) == 1:
                checked[name] = np.zeros((0, 3), dtype)  # a basis of the mesh itself
                continue
            if name not in keys:
                raise ValueError(f"{name}: missing from the stored basis")
            a = np.asarray(arrays[name])
            if a.dtype != dtype:
                raise ValueError(f"{name}: expected dtype {np.dtype(dtype)}, got {a.dtype}")
            if a.ndim != ndim:
                raise ValueError(f"{name}: expected {ndim} dimensions, got shape {a.shape}")
            checked[name] = a
        version = int(checked.pop("format_version"))
        if version not in (1, FORMAT_VERSION):
            raise ValueError(f"format_version: this add-on reads versions 1 and {FORMAT_VERSION}, got {version}; re-bake")
        for name in ("rest", "ghost_vertices", "ghost_faces") + _SINCE_VERSION_2:
            if checked[name].shape[1] != 3:
                raise ValueError(f"{name}: expected 3 columns, got shape {checked[name].shape}")
        scalars = {name: a.item() for name, a in checked.items() if a.ndim == 0}
        arrays = {name: np.ascontiguousarray(a) for name, a in checked.items() if a.ndim > 0}
        arrays["ghost_vectors"] = np.asfortranarray(checked["ghost_vectors"])
        return cls(_native.Basis(**arrays, **scalars))


def _count(value, name, minimum):
    value = _arrays.integer(value, name)
    if value < minimum:
        raise ValueError(f"{name}: expected at least {minimum}, got {value}")
    return min(value, np.iinfo(np.int32).max)


def _flag(value, name):
    if not isinstance(value, (bool, np.bool_)):
        raise ValueError(f"{name}: expected True or False, got {value!r}")
    return bool(value)


def bake(V, F, modes=20, derivatives=52, ghost=1000, energy="shells", bending=1.0, membrane=1.0, progress=None,
         rotation_pairs=True, proxy=PROXY, proxy_above=PROXY_ABOVE):
    """Bake the reduced space of the triangle mesh (V (n, 3), F (m, 3)) for posing.

    modes: vibration modes, the rigid motions of the simulated components (6 each) included;
    derivatives: modal derivatives of pairs of modes, low eigenvalues first, in the paper's rule: all
    modes but the translations and zero modes pair, the linearised rotations included, so that
    ``modes=15, derivatives=52`` is the paper's 67-dimensional basis (``rotation_pairs=False``:
    pairs of flexible modes only, the rule before; it needs more modes); ghost: the
    ghost's target vertex count (at least 4; the mesh itself when it has fewer vertices);
    energy: "shells" (discrete shells with weights ``bending`` and ``membrane``) or "arap" (only
    with derivatives=0: ARAP has no third derivative); proxy, proxy_above: a mesh with more than
    ``proxy_above`` vertices is baked on a proxy of about ``proxy`` vertices (4 to
    ``proxy_above``), made by the ghost's edge collapse, and its basis carried to every fine
    vertex by barycentric weights on the nearest proxy triangle (``Basis.on_proxy``; stages
    "proxy" and "prolongation"); ``proxy=None`` bakes any mesh as it is.
    ``progress(stage, fraction)`` is called
    at least every second or so (not during a CHOLMOD factorisation, about 2 s at 100k vertices);
    returning False raises ``Cancelled``, and an exception it raises propagates.

    Returns a ``Basis`` with dimension modes + num_floppy + derivatives - num_dropped. Raises
    ValueError for a bad mesh or option, RuntimeError when a solver fails. Warns when the mesh is
    floppy: its zero modes besides the rigid motions (mechanisms) come on top of ``modes``, after
    the rigid motions, and get no modal derivatives.
    """
    V, F = _arrays.vertices(V), _arrays.faces(F)
    if not isinstance(energy, str):
        raise ValueError(f"energy: expected \"shells\" or \"arap\", got {energy!r}")
    if progress is not None and not callable(progress):
        raise ValueError(f"progress: expected a callable progress(stage, fraction) or None, got {progress!r}")
    native = _native.bake(V, F, _count(modes, "modes", 1), _count(derivatives, "derivatives", 0),
                          _count(ghost, "ghost", 4), energy, _arrays.number(bending, "bending"),
                          _arrays.number(membrane, "membrane"), _flag(rotation_pairs, "rotation_pairs"),
                          0 if proxy is None else _count(proxy_above, "proxy_above", 1),
                          4 if proxy is None else _count(proxy, "proxy", 4), progress)
    basis = Basis(native)
    if basis.num_floppy:
        warnings.warn(f"the mesh is floppy: it has {basis.num_floppy} zero modes besides its rigid motions "
                      f"(mechanisms, e.g. flaps at non-manifold edges or vertices); they are in the basis on top "
                      f"of the {modes} modes asked for, without modal derivatives", stacklevel=2)
    return basis
