"""Cache an animation of Suzanne (static, or simulated with `dynamic`), record what it holds and
shows, and save the file."""

import bpy
import numpy as np
from support import blender as support

frame_cache, timeline = support.enable_addon("playback.frame_cache", "playback.timeline")
kind = support.arguments()[0]
obj, V, _ = support.keyed_suzanne(6, 15, 20, 400)
obj.modal_deform.dynamics.enabled = kind == "dynamic"
assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=12) == {"FINISHED"}
cache = frame_cache.get(obj)
assert cache.kind == kind.upper() and len(cache) == 12
scene = bpy.context.scene
shown = []
for frame in range(1, 13):
    scene.frame_set(frame)
    shown.append(support.evaluated_positions(obj))
np.save(support.tmp("shown.npy"), np.array(shown))
np.save(support.tmp("rest.npy"), V)
with open(support.tmp("digest.txt"), "w") as f:
    f.write(frame_cache.digest(cache))
scene.frame_set(1)
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("cached.blend"))
# The frame after the cache, computed after the save: the reloaded file computes it again.
scene.frame_set(13)
np.save(support.tmp("next.npy"), support.evaluated_positions(obj))
print("the cache holds", cache.nbytes(), "bytes")
