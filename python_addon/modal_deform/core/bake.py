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
from . import _arrays, _options

# 2: the prolongation of a basis baked on a proxy; 3: the painted stiffness (stiffness_weights,
# max_stiffness). Each field's version comes from the native schema.
FORMAT_VERSION = 3

#: ``bake``'s options, the native core's (cpp/bake/bake.h, for_each_bake_option): {name: Option}.
BAKE_OPTIONS = _options.table(_native.BAKE_OPTIONS)

#: The bake's stages in the order they run, the names its progress reports and ``Basis.timings``
#: use (the native core's list). A bake without a proxy skips the first and the last.
BAKE_STAGES = _native.BAKE_STAGES


def bake_fraction(stage, fraction, on_proxy):
    """Fraction of a whole bake done when it reports (stage, fraction), counting each of its stages
    alike (their costs vary by mesh): for one progress bar, which then only moves forward. 0 before
    the first report of a stage."""
    stages = BAKE_STAGES if on_proxy else BAKE_STAGES[1:-1]
    if stage not in stages:
        return 0.0
    return (stages.index(stage) + fraction) / len(stages)


# The stored fields, one table: the native core's (cpp/basis/basis.h, for_each_stored_field), each
# with its name, the format version that introduced it, dtype, number of dimensions, fixed number of
# columns (0: any) and whether it is column-major. Shapes are checked natively against each other
# (validate_basis).
_SCHEMA = tuple(_native.Basis.schema)


class Basis:
    """A baked reduced space: fine positions x = x̄ + U q in the mesh's units.

    Arrays are read-only views of the native basis (no copies). ``vectors`` (3n, r) float32 holds
    the rigid motions (``num_rigid`` columns), then the vibration modes (up to ``num_modes``), then
    the modal derivatives; ``modes`` is a view of the first ``num_modes`` columns.
    ``eigenvalues`` (num_modes,) are those of the normalised frame, ascending (0 for the rigid
    motions). ``num_floppy`` modes after the rigid ones are zero modes of a floppy mesh
    (mechanisms, e.g. large parts joined at a single vertex); ``num_dropped`` derivatives were dropped as
    numerically dependent. ``ghost_vertices`` (g, 3), ``ghost_faces`` (h, 3) int32 and
    ``ghost_map`` (n,) int32 describe the ghost (a region bake's ghost is its submesh's, and the
    vertices outside that map to 0), ``ghost_vectors`` (3g, r) the restricted basis.
    ``timings`` maps each bake stage to seconds. ``rest`` (n, 3) float64 and ``mass`` (n,) float64
    are the rest mesh's positions and lumped masses (mesh units), ``scale`` the factor from mesh
    units to the normalised frame, ``bending`` and ``membrane`` the energy's weights, and
    ``stiffness_weights`` (n,) float64 (or (0,): uniform) with ``max_stiffness`` their painting per
    vertex (see ``bake``), which the solver's ghost takes over as means. ``region`` (k,) int32: a
    region bake's vertices, ascending ((0,) for the whole mesh); all rows of other vertices are 0.

    A dense mesh baked on a proxy (``on_proxy``) keeps the proxy's basis: ``vectors`` is then
    (3p, r) over its ``num_basis_vertices`` = p vertices, and each fine vertex i moves with
    ``prolongation_weights[i]`` (3,) float32 (barycentric, or all 0 for a vertex outside a region)
    of the proxy vertices ``prolongation_vertices[i]`` (3,) int32: x_i = x̄_i + Σ_k w_ik (U q)_{v_ik}. Both are (0, 3)
    for a basis of the mesh itself. ``fine_vectors(columns)`` gives the fine (3n, c) basis in either case.
    """

    def __init__(self, native):
        self._native = native

    # The stored fields (_SCHEMA) are read-only views of the native basis, and so are these:
    dimension = property(lambda self: self._native.dimension, doc="r, the number of basis vectors")
    num_vertices = property(lambda self: self._native.num_vertices)
    on_proxy = property(lambda self: self._native.on_proxy, doc="baked on a proxy of the mesh")
    num_basis_vertices = property(
        lambda self: self._native.num_basis_vertices,
        doc="vertices of vectors' rows: the proxy's, or n",
    )

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
        return self.vectors[:, : self.num_modes]

    @property
    def timings(self):
        """dict: seconds spent in each stage of the bake (empty for a basis read back)."""
        return dict(self._native.timings)

    def __repr__(self):
        return (
            f"<Basis: {self.num_vertices} vertices, dimension {self.dimension} ({self.num_rigid} rigid, "
            f"{self.num_modes} modes, {self.dimension - self.num_modes} derivatives), "
            f"ghost {len(self.ghost_vertices)} vertices"
            f"{f', proxy {self.num_basis_vertices} vertices' if self.on_proxy else ''}>"
        )

    def to_arrays(self):
        """dict[str, np.ndarray] of copies, counts and scalars as 0-d arrays, with a format version:
        what from_arrays reads back bit for bit (timings are not kept)."""
        arrays = {"format_version": np.array(FORMAT_VERSION, dtype=np.int32)}
        for field in _SCHEMA:
            arrays[field["name"]] = np.array(getattr(self, field["name"]), dtype=field["dtype"])
        return arrays

    @classmethod
    def from_arrays(cls, arrays):
        """The Basis of a dict written by to_arrays (of this format version or an earlier one),
        e.g. read back from a .blend file.

        Every array is checked (dtype, number of dimensions, then natively its shape against the
        others, finiteness, index ranges and counts) before anything reads it; a ValueError names
        the first offending array. Fields newer than the stored version keep their defaults.
        """
        try:
            keys = set(arrays.keys())
        except AttributeError:
            raise ValueError(
                f"arrays: expected a dict of numpy arrays, got {type(arrays).__name__}"
            ) from None
        if "format_version" not in keys:
            raise ValueError("format_version: missing from the stored basis")
        version = np.asarray(arrays["format_version"])
        if version.dtype != np.int32 or version.ndim != 0:
            raise ValueError(
                f"format_version: expected a 0-d int32, got {version.dtype} of shape {version.shape}"
            )
        version = int(version)
        if not 1 <= version <= FORMAT_VERSION:
            raise ValueError(
                f"format_version: this add-on reads versions 1 to {FORMAT_VERSION}, got {version}; "
                f"re-bake"
            )
        fields = {}
        for field in _SCHEMA:
            name = field["name"]
            if name not in keys:
                if field["since"] > version:
                    continue
                raise ValueError(f"{name}: missing from the stored basis")
            a = np.asarray(arrays[name])
            if a.dtype != field["dtype"]:
                raise ValueError(f"{name}: expected dtype {field['dtype']}, got {a.dtype}")
            if a.ndim != field["ndim"]:
                raise ValueError(
                    f"{name}: expected {field['ndim']} dimensions, got shape {a.shape}"
                )
            if field["columns"] and a.shape[1] != field["columns"]:
                raise ValueError(
                    f"{name}: expected {field['columns']} columns, got shape {a.shape}"
                )
            if a.ndim == 0:
                fields[name] = a.item()
            else:
                fields[name] = np.asfortranarray(a) if field["fortran"] else np.ascontiguousarray(a)
        return cls(_native.Basis(**fields))


def _stored_field(name):
    return property(lambda self: getattr(self._native, name))


for _field in _SCHEMA:
    setattr(Basis, _field["name"], _stored_field(_field["name"]))


@_options.takes_options(BAKE_OPTIONS)
def bake(V, F, progress=None, **options):
    """Bake the reduced space of the triangle mesh (V (n, 3), F (m, 3)) for posing.

    The modal derivatives pair all modes but the translations and zero modes, the linearised
    rotations included, so that ``modes=15, derivatives=52`` is the paper's 67-dimensional basis.
    A dense mesh baked on a proxy (``Basis.on_proxy``) reports the stages "proxy" and
    "prolongation" too; ``proxy=None`` bakes any mesh as it is. The painted stiffness is seen by
    the modes, derivatives, proxy and ghost, and by the solver (shells only; all-zero weights give
    the plain bake). With a region, all the modes and derivatives are spent inside it (no rigid
    motions, but for a part of the region that touches nothing outside: its come as zero modes),
    handles must lie in it, a region of more than ``proxy_above`` vertices is baked on a proxy of
    its own faces, and ``Basis.region`` keeps it, ascending.
    ``progress(stage, fraction)`` is called
    at least every second or so (not during a CHOLMOD factorisation, which takes seconds on large
    meshes: bench/results/table1.json, "bake_stages_s");
    returning False raises ``Cancelled``, and an exception it raises propagates.

    Returns a ``Basis`` with dimension modes + num_floppy + derivatives - num_dropped. Raises
    ValueError for a bad mesh or option, RuntimeError when a solver fails. Warns when the mesh is
    floppy: its zero modes besides the rigid motions (mechanisms) come on top of ``modes``, after
    the rigid motions, and get no modal derivatives.
    """
    V, F = _arrays.vertices(V), _arrays.faces(F)
    if "region" in options:
        options["region"] = _arrays.indices(options["region"], "region")
        if not options["region"].size:
            raise ValueError(
                "region: it has no vertices; give the vertices that may move, or None for the whole mesh"
            )
    if "stiffness_weights" in options:
        options["stiffness_weights"] = _arrays.stiffness_weights(
            options["stiffness_weights"], len(V)
        )
    if progress is not None and not callable(progress):
        raise ValueError(
            f"progress: expected a callable progress(stage, fraction) or None, got {progress!r}"
        )
    if "proxy" in options and options["proxy"] is None:
        del options["proxy"]
        options["proxy_above"] = 0
    basis = Basis(_native.bake(V, F, progress=progress, **options))
    if basis.num_floppy:
        warnings.warn(
            f"the mesh is floppy: it has {basis.num_floppy} zero modes besides its rigid motions "
            f"(mechanisms, e.g. large parts of the mesh joined at a single vertex, or the rigid motions of a part of "
            f"the region that touches nothing outside it); they are in the basis on top of the "
            f"{options.get('modes', BAKE_OPTIONS['modes'].default)} modes asked for, without modal derivatives",
            stacklevel=3,
        )
    return basis
