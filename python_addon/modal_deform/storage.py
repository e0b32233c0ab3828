"""The baked basis in the .blend file, and whether it still fits the mesh.

Where: a Palette datablock (geometry-free, named with a leading "." so ID menus hide it) that
``Object.modal_deform.basis`` points to. The pointer is a user, so the datablock is saved with the
object, follows it when the object is appended or linked, and becomes an orphan (dropped on save)
when the object is deleted. Not on the Object or its Mesh: the depsgraph copies the ID properties
of a tagged ID on every update (docs/measurements.md, "The add-on in Blender"), while palettes are
not copied-on-write at all.

How: each array of ``Basis.to_arrays()`` as one flat ID property array of its own dtype (float32,
float64, int32: Blender keeps the bytes as they are, so the .blend grows by the data and no more),
their shapes in "shapes", 0-d values as plain ID properties. Reading back is a zero-copy
``np.frombuffer`` of each property; ``Basis.from_arrays`` checks everything.

Staleness: the vertex count, a hash of the faces' corners and a hash of the rest positions at the
bake, compared with the mesh now; and the stiffness and region vertex groups with hashes of their
weights (painting anew, choosing another group or deleting it makes the basis stale).
"""

import collections
import hashlib
import time
import uuid

import bpy
import numpy as np

from . import app_handlers, mesh_io
from . import core as mdc

PREFIX = ".Modal Deform "
_SHAPES = "shapes"
BAKE_ID = "bake_id"


class RecentLoads:
    """What was loaded from stored arrays, by bake id, the `size` most recently used kept: a pose,
    a solve and the preview share one load."""

    def __init__(self, size):
        self._loads = collections.OrderedDict()
        self._size = size

    def load(self, block, from_arrays, what):
        """What the stored `block` (write_arrays) holds, from_arrays(read_arrays(block)), kept by its
        bake id: read once. Raises NotReady naming `what` when its arrays are damaged."""
        bake_id = block.get(BAKE_ID)
        if bake_id in self._loads:
            self._loads.move_to_end(bake_id)
            return self._loads[bake_id]
        try:
            loaded = from_arrays(read_arrays(block))
        except (KeyError, TypeError, ValueError, AttributeError) as error:
            raise NotReady(f"{what} is damaged ({error}): re-bake") from None
        self.keep(bake_id, loaded)
        return loaded

    def keep(self, bake_id, load):
        self._loads[bake_id] = load
        self._loads.move_to_end(bake_id)
        while len(self._loads) > self._size:
            self._loads.popitem(last=False)

    def clear(self):
        self._loads.clear()


# Loaded bases.
_bases = RecentLoads(2)
# Mesh fingerprints for the panel by mesh pointer, and vertex group hashes by (mesh pointer, group
# name), dropped when the depsgraph reports new geometry (weight painting is a geometry update).
_fingerprints = {}
_group_hashes = {}


class NotReady(Exception):
    """The object cannot be posed: not baked, edited since the bake, or its stored basis damaged."""


#: The vertex groups a bake reads, by their setting on Object.modal_deform (and the status property
#: keeping the name at the bake): what each is for, as the messages name it.
GROUPS = {"stiffness_group": "stiffness", "region_group": "region"}

Groups = collections.namedtuple("Groups", "names weights hashes")
Groups.__doc__ = """The vertex groups a bake reads (GROUPS), each by its setting: names ("" for none),
weights (#V,) float64 (None for none) and hashes of the weights ("" for none)."""


def groups(obj):
    """obj's bake vertex groups now (Groups). Raises ValueError naming a group that is set but no
    longer exists."""
    names, weights, hashes = {}, {}, {}
    for setting, purpose in GROUPS.items():
        name = getattr(obj.modal_deform, setting)
        names[setting], weights[setting], hashes[setting] = name, None, ""
        if not name:
            continue
        weights[setting] = mesh_io.group_weights(obj, name)
        if weights[setting] is None:
            raise ValueError(
                f"'{obj.name}': the {purpose} vertex group '{name}' does not exist (deleted or "
                f"renamed?): choose another one or clear it"
            )
        hashes[setting] = digest(weights[setting])
    return Groups(names, weights, hashes)


def _group_hash(obj, group, cached):
    key = (obj.data.as_pointer(), group)
    if not cached or key not in _group_hashes:
        _group_hashes[key] = digest(mesh_io.group_weights(obj, group))
    return _group_hashes[key]


def digest(*arrays):
    """A hash (32 hex digits) of the arrays' bytes, one after another."""
    h = hashlib.blake2b(digest_size=16)
    for a in arrays:
        h.update(memoryview(np.ascontiguousarray(a)).cast("B"))
    return h.hexdigest()


def fingerprint(mesh):
    """(vertex count, topology hash, rest-position hash) of the mesh now."""
    totals, corners = mesh_io.face_corners(mesh)
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    return len(mesh.vertices), digest(totals, corners), digest(co)


def _cached_fingerprint(mesh):
    key = mesh.as_pointer()
    if key not in _fingerprints:
        _fingerprints[key] = fingerprint(mesh)
    return _fingerprints[key]


def stale_reason(obj, cached=False):
    """Why the stored basis no longer fits obj's mesh ("" when it fits), e.g. "vertices moved".

    cached: reuse the fingerprint computed since the last geometry update (for drawing panels).
    """
    status = obj.modal_deform.status
    count, topology, rest = (_cached_fingerprint if cached else fingerprint)(obj.data)
    if count != status.num_vertices:
        return f"{count} vertices, the bake had {status.num_vertices}"
    if topology != status.topology_hash:
        return "faces changed"
    if rest != status.rest_hash:
        return "vertices moved"
    for setting, purpose in GROUPS.items():
        group, baked = getattr(obj.modal_deform, setting), getattr(status, setting)
        if group != baked:
            return f"{purpose} group '{group}', the bake had '{baked}'"
        if group and obj.vertex_groups.get(group) is None:
            return f"{purpose} group '{group}' was deleted"
        if group and _group_hash(obj, group, cached) != getattr(status, setting + "_hash"):
            return f"{purpose} weights painted anew"
    return ""


def write_arrays(name, arrays):
    """A new datablock `name` holding `arrays` (dict of numpy arrays, as ``to_arrays`` gives) and a
    new bake id (BAKE_ID)."""
    block = bpy.data.palettes.new(name)
    block.use_fake_user = (
        False  # palettes get one by default; this one lives as long as its objects
    )
    shapes = {}
    for key, a in arrays.items():
        if a.ndim == 0:
            block[key] = a.item()
        else:
            block[key] = a.ravel()
            shapes[key] = list(a.shape)
    block[_SHAPES] = shapes
    block[BAKE_ID] = uuid.uuid4().hex
    return block


def read_arrays(block):
    """The arrays write_arrays kept in `block`, each flat one a zero-copy view of its ID property
    (for ``from_arrays`` to check). Raises KeyError, TypeError or AttributeError on a damaged one."""
    shapes = block[_SHAPES].to_dict()
    arrays = {}
    for name in block.keys():
        if name in (_SHAPES, BAKE_ID):
            continue
        value = block[name]
        if name in shapes:
            arrays[name] = np.frombuffer(value, dtype=value.typecode).reshape(shapes[name])
        else:
            arrays[name] = np.array(value, dtype=np.int32 if isinstance(value, int) else np.float64)
    return arrays


def store(obj, basis, mesh_fingerprint, vertex_groups, seconds, energy):
    """Keep `basis` (baked from obj's mesh with `mesh_fingerprint` and the Groups `vertex_groups`)
    in the .blend as obj's basis."""
    block = write_arrays(PREFIX + obj.name, basis.to_arrays())
    bake_id = block[BAKE_ID]

    settings = obj.modal_deform
    release(settings, "basis")
    settings.basis = block
    status = settings.status
    status.dimension = basis.dimension
    status.num_rigid = basis.num_rigid
    status.num_modes = basis.num_modes
    status.num_derivatives = basis.dimension - basis.num_modes
    status.num_floppy = basis.num_floppy
    status.ghost_vertices = len(basis.ghost_vertices)
    status.proxy_vertices = basis.num_basis_vertices if basis.on_proxy else 0
    status.energy = energy
    status.baked_at = time.strftime("%Y-%m-%d %H:%M")
    status.seconds = seconds
    status.num_vertices, status.topology_hash, status.rest_hash = mesh_fingerprint
    for setting in GROUPS:
        setattr(status, setting, vertex_groups.names[setting])
        setattr(status, setting + "_hash", vertex_groups.hashes[setting])
    _bases.keep(bake_id, basis)


def clear(obj):
    """Forget obj's basis (the datablock goes when no other object uses it)."""
    settings = obj.modal_deform
    release(settings, "basis")
    settings.property_unset("status")


def release(owner, name):
    """Point owner's datablock property `name` at nothing; the datablock goes when nothing else
    uses it (and it is not linked from a library)."""
    block = getattr(owner, name)
    setattr(owner, name, None)
    if block is not None and block.users == 0 and block.library is None:
        bpy.data.palettes.remove(block)


def load(obj):
    """obj's stored Basis (cached per bake). Raises NotReady when there is none or it is damaged."""
    block = obj.modal_deform.basis
    if block is None:
        raise NotReady(f"'{obj.name}' has no baked basis: bake it first")
    return _bases.load(block, mdc.Basis.from_arrays, f"the basis stored for '{obj.name}'")


def ready_basis(obj):
    """obj's Basis when it fits the mesh as it is now; raises NotReady saying what to do otherwise."""
    if obj.modal_deform.basis is None:
        raise NotReady(f"'{obj.name}' has no baked basis: bake it first")
    reason = stale_reason(obj)
    if reason:
        raise NotReady(f"'{obj.name}' was edited after the bake ({reason}): re-bake")
    return load(obj)


def _forget_geometry(scene, depsgraph):
    for update in depsgraph.updates:
        if update.is_updated_geometry and isinstance(update.id, bpy.types.Mesh):
            mesh = update.id.original.as_pointer()
            _fingerprints.pop(mesh, None)
            for key in [key for key in _group_hashes if key[0] == mesh]:
                del _group_hashes[key]


def _forget_everything(*args):
    _bases.clear()
    _fingerprints.clear()
    _group_hashes.clear()


_HANDLERS = (("depsgraph_update_post", _forget_geometry), ("load_post", _forget_everything))


def register():
    app_handlers.register(_HANDLERS)


def unregister():
    app_handlers.unregister(_HANDLERS)
    _forget_everything()
