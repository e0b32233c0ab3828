"""Open the file cache_save.py wrote: the cache is there bit for bit, plays back what it showed
before the save without computing anything, simulates the frame after it as before the save, and
a mesh edited since the bake is refused."""

import bpy
import numpy as np
from support import blender as support

frame_cache, timeline = support.enable_addon("playback.frame_cache", "playback.timeline")
obj = bpy.data.objects["Suzanne"]
scene = bpy.context.scene
cache = frame_cache.get(obj)
with open(support.tmp("digest.txt")) as f:
    assert frame_cache.digest(cache) == f.read(), "the cache did not reload bit for bit"
assert np.array_equal(support.positions(obj), np.load(support.tmp("rest.npy"))), (
    "the artist's mesh changed"
)
shown = np.load(support.tmp("shown.npy"))
assert support.evaluated_positions(obj).tobytes() == shown[0].tobytes(), (
    "the file does not show the frame saved"
)
player = timeline.player(obj, scene)
player.first = player.next = None  # nothing is computed: every frame is read back
for frame in (12, 1, 7, 3):
    scene.frame_set(frame)
    assert support.evaluated_positions(obj).tobytes() == shown[frame - 1].tobytes(), frame
del player.first, player.next
if (
    cache.kind == "DYNAMIC"
):  # simulated from the cached frame before it: the same bits after the reload
    kept = {name: cache.array(name).copy() for name in ("q", "v", "transforms", "curves")}
    scene.frame_set(13)
    assert len(cache) == 13 and all(
        cache.array(name)[:12].tobytes() == rows.tobytes() for name, rows in kept.items()
    )
    assert support.evaluated_positions(obj).tobytes() == np.load(support.tmp("next.npy")).tobytes()

# A mesh edited after the bake (Edit Mode, a vertex moved): playback refuses it and shows the mesh as edited.
bpy.context.view_layer.objects.active = obj
bpy.ops.object.mode_set(mode="EDIT")
bpy.ops.object.mode_set(mode="OBJECT")
obj.data.vertices[0].co.x += 0.1
scene.frame_set(5)
assert "edited after the bake" in timeline.problems.get(obj.name, ""), timeline.problems
assert support.evaluated_positions(obj).tobytes() == support.positions(obj).tobytes()
