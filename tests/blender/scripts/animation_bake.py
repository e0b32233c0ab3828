"""Bake animation over 10 frames with a keyframed controller, then save."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
import bpy  # noqa: E402
import numpy as np  # noqa: E402
import support  # noqa: E402

jobs = support.enable_addon("jobs")
obj, V = support.baked_suzanne(1, 15, 20, 400)
controller = support.top_and_bottom_handles(obj, V).controller
controller.keyframe_insert("location", frame=1)
controller.location.y += 0.5
controller.keyframe_insert("location", frame=10)
scene = bpy.context.scene
scene.frame_set(3)

# The job the operator ticks on its timer: cancelled (Esc) after three frames, or failing on the
# third, it takes away what it added and says so; the mesh and the frame are as they were.
before = support.mesh_state(obj)
job = jobs.AnimationJob(bpy.context, obj, range(1, 11))
job.start()
assert job.tick() and job.tick() and job.tick() and job.overall == 0.3
assert len(obj.data.shape_keys.key_blocks) == 4  # the reference key and three frames
job.cancel()
assert not job.tick()
assert job.finish() == ("WARNING", "Animation bake cancelled: nothing changed") and not job.written
assert support.mesh_state(obj) == before and scene.frame_current == 3

job = jobs.AnimationJob(bpy.context, obj, range(1, 11))
converge = job.pose.converge
job.pose.converge = lambda: converge() if job.frames_done < 2 else 1 / 0
job.run()
level, message = job.finish()
assert level == "ERROR" and message == "Animation bake failed: division by zero" and not job.written, message
assert support.mesh_state(obj) == before and scene.frame_current == 3
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
