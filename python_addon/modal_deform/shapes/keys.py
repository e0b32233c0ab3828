"""A mesh's shape keys as a shape space's input: the basis, the keys' shapes, their weights.

Which keys: every key of the mesh but the reference key (Blender's "Basis", the weight-0 shape) and
the frame keys an export wrote (playback.frame_keys: correctives that Blender's mix adds on top).
A key's shape is what Blender's mix adds at weight 1 on the basis: basis + (key − its Relative To)
(the key itself when it is relative to the basis), so the linear blend of the shapes is Blender's
mix. Refused: absolute keys (the Key's Relative off: an evaluation time, not weights) and a key with
a Vertex Group (its weight per vertex is no weight of a shape).

Weights: each key's value, 0 when it is muted; with the object's Shape Key Lock (show only the
active key) 1 for the active key and 0 for the others, as Blender shows it. Read from the evaluated Key when a depsgraph is given
(a frame in a render, whose keyframes and drivers are evaluated there), else from the original.
"""

import numpy as np

from .. import mesh_io, storage
from ..playback import frame_keys


def check(obj):
    """The Key of obj's mesh when Blend as Shapes can take its keys; raises ValueError saying why not."""
    keys = obj.data.shape_keys
    if keys is None or len(keys.key_blocks) < 2:
        raise ValueError(
            f"'{obj.name}' has no shape key besides its Basis: add the keys to blend first"
        )
    if not keys.use_relative:
        raise ValueError(
            f"'{obj.name}': its shape keys are absolute (Relative off, blended by Evaluation Time): "
            f"Blend as Shapes blends relative keys; turn Relative on"
        )
    for block in blocks(obj):
        if block.vertex_group:
            raise ValueError(
                f"shape key '{block.name}' has the vertex group '{block.vertex_group}': a blend of "
                f"shapes takes whole keys; clear its Vertex Group (or Apply it as a new key)"
            )
    return keys


def blocks(obj):
    """The key blocks of the space, in the mesh's order (every key but the reference and frame keys)."""
    keys = obj.data.shape_keys
    reference = keys.reference_key
    return [b for b in keys.key_blocks if b != reference and not frame_keys.is_frame_key(b.name)]


def names(obj):
    """The names of the keys a space baked now takes (blocks), in order."""
    return [b.name for b in blocks(obj)]


def basis(obj):
    """The reference key's positions (#V by 3 float64): the basis of the blend."""
    mesh = obj.data
    return mesh_io.shape_key_co(mesh, mesh.shape_keys.reference_key).astype(np.float64)


def shapes(obj, V, space_names):
    """The shapes (each #V by 3 float64) of the keys `space_names`: V + (key − its Relative To),
    the key itself when relative to the reference key."""
    mesh = obj.data
    reference = mesh.shape_keys.reference_key
    found = []
    for block in (mesh.shape_keys.key_blocks[name] for name in space_names):
        X = mesh_io.shape_key_co(mesh, block).astype(np.float64)
        relative = block.relative_key
        if relative != reference:
            X = V + (X - mesh_io.shape_key_co(mesh, relative))
        found.append(X)
    return found


def raw(obj, space_names):
    """What the space of the keys `space_names` is made of, as Blender holds it now: the reference
    key's and each key's positions (zero-copy views: read at once), with each key's Relative To's
    name. Raises KeyError naming a key of the space the mesh no longer has."""
    mesh = obj.data
    keys = mesh.shape_keys
    arrays = [mesh_io.shape_key_co(mesh, keys.reference_key)]
    relatives = []
    for name in space_names:
        block = keys.key_blocks.get(name)
        if block is None:
            raise KeyError(name)
        arrays.append(mesh_io.shape_key_co(mesh, block))
        relatives.append(block.relative_key.name)
    return arrays, relatives


def digest(obj, space_names):
    """A hash of the faces, the basis and the keys `space_names` (coordinates, names, Relative To).
    Raises KeyError as raw does."""
    arrays, relatives = raw(obj, space_names)
    totals, corners = mesh_io.face_corners(obj.data)
    text = np.frombuffer(repr((list(space_names), relatives)).encode(), np.uint8)
    return storage.digest(totals, corners, text, *arrays)


def weights(obj, space_names, depsgraph=None):
    """(k,) float64: the weight of each of `space_names` (the space's keys) now, and the names of the
    keys outside the space whose weight is not 0 (they came after the bake)."""
    keys = obj.data.shape_keys
    if depsgraph is not None:
        keys = keys.evaluated_get(depsgraph)
    found = keys.key_blocks
    w = np.zeros(len(space_names))
    index = {name: i for i, name in enumerate(space_names)}
    outside = []
    if obj.show_only_shape_key:  # Blender shows the active key alone, at full strength
        i = obj.active_shape_key_index
        active = found[i] if 0 <= i < len(found) else None
        if active is not None and active.name in index and not active.mute:
            w[index[active.name]] = 1.0
        return w, outside
    reference = keys.reference_key
    for block in found:
        if block.mute or block == reference:
            continue
        i = index.get(block.name)
        if i is not None:
            w[i] = block.value
        elif block.value != 0.0 and not frame_keys.is_frame_key(block.name):
            outside.append(block.name)
    return w, outside
