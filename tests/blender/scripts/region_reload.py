"""Open the file region_bake.py wrote: the region bake is fresh, poses as before, and the ear's
tip pulled further still leaves every vertex outside the ear exactly where it was, refined too."""

import bpy
import numpy as np
from mathutils import Matrix
from support import blender as support

posing, storage = support.enable_addon("pose.posing", "storage")

obj = bpy.data.objects["Suzanne"]
bpy.context.view_layer.objects.active = obj
V = support.positions(obj)
ear = V[:, 0] > 0.75
assert storage.stale_reason(obj) == ""
np.testing.assert_array_equal(storage.load(obj).region, np.flatnonzero(ear))
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
saved = np.load(support.tmp("region_pose.npy"))
assert np.abs(support.key_positions(obj, posing.POSE_KEY) - saved).max() < 1e-4
controller = obj.modal_deform.handles[0].controller
controller.matrix_world = Matrix.Translation((0.0, -0.2, 0.2)) @ controller.matrix_world
bpy.context.view_layer.update()
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
pose = support.key_positions(obj, posing.POSE_KEY)
assert pose[~ear].tobytes() == V[~ear].tobytes(), "a vertex outside the region moved"
assert np.abs(pose - saved).max() > 0.1
assert bpy.ops.modal_deform.refine() == {"FINISHED"}
refined = support.key_positions(obj, posing.POSE_KEY)
assert refined[~ear].tobytes() == V[~ear].tobytes(), "Refine moved a vertex outside the region"
assert np.abs(refined - pose).max() > 1e-4, "Refine left the reduced pose as it was"
