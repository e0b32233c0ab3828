"""Stiffness painted with a vertex group (issue 24): baked with the group's weights, stale when they
are painted anew, a missing group refused; posed, and saved for painted_reload.py.

Writes TEST_TMP/painted.blend and TEST_TMP/painted_pose.npy (the pose's shape key).
"""

import math

import bpy
import numpy as np
from mathutils import Matrix
from support import blender as support

mdc, posing, storage = support.enable_addon("core", "pose.posing", "storage")

V, F = mdc.testing.cylinder(10, 30, 0.5, 6.0)
obj = support.mesh_object("Bar", V, F)
settings = obj.modal_deform
settings.modes, settings.derivatives, settings.ghost = 16, 40, 2000
middle = (V[:, 2] > 2) & (V[:, 2] < 4)
group = obj.vertex_groups.new(name="Stiff")
group.add([int(i) for i in np.flatnonzero(middle)], 1.0, "REPLACE")

# A group that does not exist: a clear error, and nothing changes.
settings.stiffness_group = "Nowhere"
state = support.mesh_state(obj)
support.expect_error(
    bpy.ops.modal_deform.bake, "the stiffness vertex group 'Nowhere' does not exist"
)
assert support.mesh_state(obj) == state

settings.stiffness_group, settings.max_stiffness = "Stiff", 100.0
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
basis = storage.load(obj)
assert (
    np.array_equal(basis.stiffness_weights, middle.astype(np.float64))
    and basis.max_stiffness == 100.0
)
assert storage.stale_reason(obj) == ""

# The bar held at its bottom ring, its top ring turned by 40° and pushed down: an arc.
bottom = support.add_handle(obj, V[:, 2] < 1e-6)
bottom.controller = None
top = support.add_handle(obj, V[:, 2] > 6 - 1e-6)
top.controller.matrix_world = (
    Matrix.Translation((0.0, -0.3, -0.4))
    @ top.controller.matrix_world
    @ Matrix.Rotation(math.radians(40), 4, "X")
)
bpy.context.view_layer.update()

# Painted anew: stale until painted back.
group.add([0], 0.5, "REPLACE")
assert storage.stale_reason(obj) == "stiffness weights painted anew", storage.stale_reason(obj)
support.expect_error(bpy.ops.modal_deform.solve, "(stiffness weights painted anew): re-bake")
group.remove([0])
assert storage.stale_reason(obj) == ""
settings.stiffness_group = ""
assert storage.stale_reason(obj) == "stiffness group '', the bake had 'Stiff'"
settings.stiffness_group = "Stiff"

assert bpy.ops.modal_deform.solve() == {"FINISHED"}
np.save(support.tmp("painted_pose.npy"), support.key_positions(obj, posing.POSE_KEY))
assert support.positions(obj).tobytes() == V.astype(np.float32).tobytes(), "the base mesh changed"
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("painted.blend"))
