"""Bake animation over 10 frames with a keyframed controller, then save."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
import bpy  # noqa: E402
import numpy as np  # noqa: E402
import support  # noqa: E402

jobs = support.enable_addon("jobs")
obj = support.suzanne(1)
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 15, 20, 400
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
V = support.positions(obj)
top = support.add_handle(obj, V[:, 2] > 0.5)
support.add_handle(obj, V[:, 2] < -0.5).controller = None
controller = top.controller
controller.keyframe_insert("location", frame=1)
controller.location.y += 0.5
controller.keyframe_insert("location", frame=10)
scene = bpy.context.scene
scene.frame_set(3)
assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=10) == {"FINISHED"}
assert scene.frame_current == 3
names = [b.name for b in obj.data.shape_keys.key_blocks]
assert names == ["Basis"] + [f"Modal Deform {f:04d}" for f in range(1, 11)], names
# Again: the keys of the first run are replaced, not added to.
assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=10) == {"FINISHED"}
assert [b.name for b in obj.data.shape_keys.key_blocks] == names
assert len(jobs.action_fcurves(obj.data.shape_keys.animation_data)) == 10
for f in (1, 5, 10):
    np.save(support.tmp(f"frame{f}.npy"), support.key_positions(obj, f"Modal Deform {f:04d}"))
np.save(support.tmp("rest.npy"), V)
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("animated.blend"))
print("ANIMATED")
