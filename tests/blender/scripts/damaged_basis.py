"""A basis damaged in the saved .blend (an array truncated, a shape resized, NaN, an index out of
range, an array missing) is refused with a message when the add-on loads it after the file is
opened, and neither the mesh nor the stored basis is touched by the refusal."""

import bpy
import numpy as np
from support import blender as support

support.enable_addon()

obj = support.suzanne(0)
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 10, 5, 100
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
support.add_handle(obj, support.positions(obj)[:, 2] > 0.3)
path = support.tmp("baked.blend")
bpy.ops.wm.save_as_mainfile(filepath=path)


def array(block, name):
    value = block[name]
    return np.frombuffer(value, dtype=value.typecode).copy()


def replace(block, name, value):
    """block[name] = value, dropping the old property first: Blender 4.5 and 5.0 copy a NumPy array
    into an existing array property of the same type without resizing it (a shorter one is padded
    with the old values, a longer one overruns the buffer)."""
    del block[name]
    block[name] = value


def truncated(block):
    replace(block, "vectors", array(block, "vectors")[:-7])


def resized(block):
    shapes = block["shapes"].to_dict()
    rows, columns = shapes["vectors"]
    replace(block, "vectors", np.zeros((rows + 3) * columns, np.float32))
    shapes["vectors"] = [rows + 3, columns]
    block["shapes"] = shapes


def nan(block):
    ghost_vectors = array(block, "ghost_vectors")
    ghost_vectors[5] = np.nan
    replace(block, "ghost_vectors", ghost_vectors)


def out_of_range(block):
    ghost_map = array(block, "ghost_map")
    ghost_map[3] = 2**31 - 1
    replace(block, "ghost_map", ghost_map)


def missing(block):
    del block["rest"]


for damage, fragment in [
    (truncated, "cannot reshape"),
    (resized, "vectors"),
    (nan, "ghost_vectors"),
    (out_of_range, "ghost_map[3] = 2147483647"),
    (missing, "rest"),
]:
    bpy.ops.wm.open_mainfile(filepath=path)  # the add-on forgets its loaded bases (load_post)
    obj = bpy.data.objects["Suzanne"]
    bpy.context.view_layer.objects.active = obj
    damage(obj.modal_deform.basis)
    before = support.mesh_state(obj)
    message = support.expect_error(bpy.ops.modal_deform.solve, "is damaged")
    assert fragment in message and "re-bake" in message, (damage.__name__, message)
    support.expect_error(bpy.ops.modal_deform.preview_mode, "is damaged")
    assert support.mesh_state(obj) == before, f"{damage.__name__}: the refusal changed the object"

# The undamaged file still solves.
bpy.ops.wm.open_mainfile(filepath=path)
bpy.context.view_layer.objects.active = bpy.data.objects["Suzanne"]
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
