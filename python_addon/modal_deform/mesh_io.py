"""numpy arrays from a Blender mesh, and shape keys written back.

Positions are the base mesh's (``vertices.co``), the rest state every bake and pose starts from.
Only an interactive pose writes them, and puts them back when it ends (pose.displays.PositionsDisplay).
"""

import ctypes
import sys

import numpy as np

# The C library's memcmp (msvcrt's on Windows), to compare two arrays without building a third.
_memcmp = (ctypes.cdll.msvcrt if sys.platform == "win32" else ctypes.CDLL(None)).memcmp
_memcmp.restype = ctypes.c_int
_memcmp.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t)


def positions(mesh):
    """#V by 3 float64 rest positions (object space)."""
    co = np.empty(3 * len(mesh.vertices), np.float64)
    mesh.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def triangles(mesh):
    """#T by 3 int32: Blender's triangulation of the faces (quads and n-gons split) for the energy.

    Loop triangles are a cache Blender keeps beside the mesh: the faces stay as they are.
    """
    mesh.calc_loop_triangles()
    F = np.empty(3 * len(mesh.loop_triangles), np.int32)
    mesh.loop_triangles.foreach_get("vertices", F)
    return F.reshape(-1, 3)


def face_corners(mesh):
    """(corners per face (#faces,) int32, vertex of each corner (#corners,) int32): the topology."""
    totals = np.empty(len(mesh.polygons), np.int32)
    mesh.polygons.foreach_get("loop_total", totals)
    corners = np.empty(len(mesh.loops), np.int32)
    mesh.loops.foreach_get("vertex_index", corners)
    return totals, corners


def group_weights(obj, group_name):
    """(#V,) float64 weights of the vertex group, 0 for the vertices not in it, or None when the
    object has no group of that name.

    Blender has no bulk access to group weights: this walks the vertices once (too slow for every
    update: docs/measurements.md, "The add-on in Blender"), so callers read a group once.
    """
    group = obj.vertex_groups.get(group_name)
    if group is None:
        return None
    index = group.index
    weights = np.zeros(len(obj.data.vertices))
    for v in obj.data.vertices:
        for g in v.groups:
            if g.group == index:
                weights[v.index] = g.weight
    return weights


def members(weights):
    """Sorted int32 indices of the vertices with a weight above 0 (of group_weights)."""
    return np.flatnonzero(weights > 0.0).astype(np.int32)


def group_vertices(obj, group_name):
    """The members of the vertex group, or None when the object has no group of that name."""
    weights = group_weights(obj, group_name)
    return None if weights is None else members(weights)


def selected_vertices(mesh):
    """int32 indices of the selected vertices (of the mesh data: sync Edit Mode first)."""
    selected = np.empty(len(mesh.vertices), bool)
    mesh.vertices.foreach_get("select", selected)
    return np.flatnonzero(selected).astype(np.int32)


def ensure_reference_key(obj):
    """Give a mesh without shape keys its "Basis" reference key (the rest positions); returns the
    names of the keys created here (none when it had one)."""
    if obj.data.shape_keys is not None:
        return []
    obj.shape_key_add(name="Basis", from_mix=False)
    return [obj.data.shape_keys.reference_key.name]


def shape_key(obj, name):
    """The shape key `name` of obj, created (after a "Basis" key when the mesh has none) if needed.

    Returns (key block, names of the keys created here) so a caller can take them away again.
    """
    created = ensure_reference_key(obj)
    block = obj.data.shape_keys.key_blocks.get(name)
    if block is None:
        block = obj.shape_key_add(name=name, from_mix=False)
        created.append(block.name)
    return block, created


def remove_shape_keys(obj, names):
    """Remove the named shape keys (the reference key last, so the others stay relative to it)."""
    keys = obj.data.shape_keys
    if keys is None:
        return
    reference = keys.reference_key.name
    for name in sorted(names, key=lambda n: n == reference):
        block = obj.data.shape_keys.key_blocks.get(name) if obj.data.shape_keys else None
        if block is not None:
            obj.shape_key_remove(block)


def _float3_view(items):
    """A writeable #items by 3 float32 view of the Blender array behind the RNA collection `items`
    (a shape key's points, a mesh's vertices, a vector attribute's values), each item starting with
    its float[3] position. The stride is the distance between the first two items: 12 bytes for a
    float[3] array, 16 for Blender 3.4's MVert."""
    count = len(items)
    if not count:
        return np.empty((0, 3), np.float32)
    memory, stride = item_memory(items, 12)
    return np.ndarray((count, 3), np.float32, buffer=memory, strides=(stride, 4))


def item_memory(items, item_bytes, stride=None):
    """Blender's array behind the RNA collection `items` (not empty; its items one after another in
    one array: a mesh's vertices, a key's points, an F-curve's keyframes), in place: a ctypes buffer
    from the first item to the first `item_bytes` of the last, and the stride between items (the
    distance between the first two, unless the caller knows it: `stride`). Read anew each time: use
    at once, never keep it."""
    count = len(items)
    address = items[0].as_pointer()
    if stride is None:
        stride = items[1].as_pointer() - address if count > 1 else item_bytes
    return (ctypes.c_char * (stride * (count - 1) + item_bytes)).from_address(address), stride


def shape_key_co(mesh, block):
    """The positions of the shape key `block` of `mesh`: a writeable #V by 3 float32 view of
    Blender's own array, for the solver to write the pose straight into (no array and copy between).

    A mesh's shape key keeps its positions as one contiguous float[3] array per key, which
    ``block.data[0]`` points at. Writing into it directly takes a hundredth of the time
    ``foreach_set`` takes (it goes through RNA item by item), which would cost a tenth of the pose's
    frame budget (docs/measurements.md, "The add-on in Blender"). The length is checked against the
    mesh every time, and the address read anew, so a key reallocated since (undo, edit) is never
    written through an old pointer: use the view at once, never keep it.
    """
    count = len(block.data)
    if count != len(mesh.vertices) or block.id_data != mesh.shape_keys:
        raise ValueError(
            f"shape key '{block.name}' has {count} points for {len(mesh.vertices)} vertices: "
            f"the mesh changed"
        )
    return _float3_view(block.data)


def attribute_co(mesh, attribute):
    """The values of the FLOAT_VECTOR point attribute `attribute` of `mesh`: a writeable #V by 3
    float32 view of Blender's own array, as shape_key_co gives a key's (checked against the mesh and
    read anew each time: use at once, never keep it)."""
    count = len(attribute.data)
    if (
        attribute.data_type != "FLOAT_VECTOR"
        or attribute.domain != "POINT"
        or count != len(mesh.vertices)
    ):
        raise ValueError(
            f"attribute '{attribute.name}' is {attribute.data_type} on {count} "
            f"{attribute.domain.lower()}s, not a vector on each of the {len(mesh.vertices)} vertices"
        )
    return _float3_view(attribute.data)


def vertex_positions(mesh):
    """The mesh's own vertex positions (the base mesh): a writeable #V by 3 float32 view of
    Blender's array, contiguous from Blender 3.5 on (the "position" attribute), strided in 3.4 (the
    co of each MVert). Read anew from the mesh each time, like shape_key_co: use at once."""
    return _float3_view(mesh.vertices)


def same_positions(mesh, co):
    """Whether the mesh's vertex positions are bit for bit `co` (#V by 3 float32, C-contiguous):
    one memcmp over Blender's array where it is contiguous (Blender 3.5 on), without the array of
    booleans numpy's comparison builds first, which takes twice as long on a large mesh."""
    positions = vertex_positions(mesh)
    if len(positions) != len(co):
        return False
    if not (positions.flags.c_contiguous and co.flags.c_contiguous and co.dtype == np.float32):
        return np.array_equal(positions, co)
    return _memcmp(positions.ctypes.data, co.ctypes.data, co.nbytes) == 0


def write_shape_key(mesh, block, co):
    """Write float32 positions (#V by 3 or 3#V) into the shape key `block` of `mesh` and tag it for
    redraw."""
    co = np.asarray(co, np.float32).reshape(-1, 3)
    target = shape_key_co(mesh, block)
    if len(co) != len(target):
        raise ValueError(
            f"shape key '{block.name}' has {len(target)} points for {len(co)} positions: the mesh changed"
        )
    np.copyto(target, co)
    mesh.update()
