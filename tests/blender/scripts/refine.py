"""Refine: the pose polished on the full mesh into the "Modal Deform" key (base mesh untouched), a
cancelled refine that leaves the key as it was, and the refined animation bake."""

import bpy
import numpy as np
from support import blender as support

refine, core = support.enable_addon("pose.refine", "core")
# Suzanne unsubdivided (507 vertices): the full solves stay short in each of the four Blenders tested.
obj, rest = support.baked_suzanne(
    0, 15, 40, 300
)  # the eyes are free components: no handle holds them
top = support.top_and_bottom_handles(obj, rest)
top.controller.location.y += 0.15
top.controller.rotation_euler.x += 0.2
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
reduced = support.key_positions(obj, "Modal Deform")

# Cancelled (Esc before the first progress report): the key stays the reduced pose, bit for bit.
before = support.mesh_state(obj)
job = refine.RefineJob(bpy.context, obj)
job.cancel()
job.run()
level, message = job.finish()
assert level == "WARNING" and "cancelled" in message, (level, message)
assert not job.written and support.mesh_state(obj) == before, "a cancelled refine changed the mesh"

# Refined: a converged minimum below the reduced pose's objective, in the same key.
job = refine.RefineJob(bpy.context, obj)
job.run()
level, message = job.finish()
assert level == "INFO" and job.written, (level, message)
assert job.stats["converged"] and job.stats["energy"] < job.stats["initial_energy"], job.stats
refined = support.key_positions(obj, "Modal Deform")
assert np.abs(refined - reduced).max() > 1e-4, "Refine left the reduced pose as it was"
assert np.array_equal(support.positions(obj), rest), "Refine changed the base mesh"
assert bpy.ops.modal_deform.refine() == {"FINISHED"}

# The animation bake, refined frame by frame.
controller = top.controller
controller.keyframe_insert("location", frame=1)
controller.location.y -= 0.15
controller.keyframe_insert("location", frame=3)
assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=3, refine=True) == {"FINISHED"}
names = [b.name for b in obj.data.shape_keys.key_blocks]
assert [f"Modal Deform {f:04d}" for f in range(1, 4)] == names[-3:], names
assert np.array_equal(support.positions(obj), rest)
