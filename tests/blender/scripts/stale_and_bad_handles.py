"""A mesh edited after the bake is detected and refused; bad handles get clear messages."""

import bpy
from support import blender as support

storage = support.enable_addon("storage")

obj = support.suzanne(1)
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 12, 10, 300
solve = bpy.ops.modal_deform.solve
support.expect_error(solve, "no baked basis: bake it first")
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
V = support.positions(obj)
support.expect_error(solve, "has no handles")

# Handles: empty group, missing group, a group holding every vertex, a deleted controller.
handle = support.add_handle(obj, V[:, 2] > 0.5)
group = obj.vertex_groups[handle.vertex_group]
everything = obj.vertex_groups.new(name="Everything")
everything.add(range(len(V)), 1.0, "REPLACE")
handle.vertex_group = "Everything"
support.expect_error(solve, "holds every vertex, so nothing is left to deform")
handle.vertex_group = "Nowhere"
support.expect_error(solve, "vertex group 'Nowhere' does not exist")
empty = obj.vertex_groups.new(name="Empty")
handle.vertex_group = "Empty"
support.expect_error(solve, "vertex group 'Empty' has no vertices")
handle.vertex_group = group.name
controller = handle.controller
bpy.ops.object.select_all(action="DESELECT")
controller.select_set(True)
bpy.context.view_layer.objects.active = controller
bpy.ops.object.delete()
bpy.context.view_layer.objects.active = obj
support.expect_error(solve, "is not in the scene (deleted?)")
handle.controller = None  # pinned
# Overlapping handles: a warning, and the solve goes on.
support.add_handle(obj, V[:, 2] > 0.4)
assert solve() == {"FINISHED"}

# Edits after the bake: moved vertices, changed faces, a different vertex count.
assert storage.stale_reason(obj) == ""
co = V.copy()
co[0, 0] += 1e-3
obj.data.vertices.foreach_set("co", co.ravel())
assert storage.stale_reason(obj) == "vertices moved"
support.expect_error(solve, "was edited after the bake (vertices moved): re-bake")
support.expect_error(bpy.ops.modal_deform.preview_mode, "re-bake")
obj.data.vertices.foreach_set("co", V.ravel())
assert storage.stale_reason(obj) == ""

bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.mesh.quads_convert_to_tris()
bpy.ops.object.mode_set(mode="OBJECT")
assert storage.stale_reason(obj) == "faces changed", storage.stale_reason(obj)
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.mesh.select_all(action="SELECT")
bpy.ops.mesh.subdivide()
bpy.ops.object.mode_set(mode="OBJECT")
assert "vertices, the bake had" in storage.stale_reason(obj), storage.stale_reason(obj)
support.expect_error(solve, "re-bake")
# Re-baking makes it usable again and replaces the old datablock.
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
assert storage.stale_reason(obj) == "" and len(support.stored_bases()) == 1
assert bpy.ops.modal_deform.clear_basis() == {"FINISHED"}
assert obj.modal_deform.basis is None and len(support.stored_bases()) == 0
