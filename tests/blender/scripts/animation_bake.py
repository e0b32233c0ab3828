"""Bake animation into the per-frame cache over 10 frames with a keyframed controller: it plays back
what the per-frame solve gives, scrubbing reads it without solving, a changed keyframe cuts it where
the motion changed, Esc or a failure leaves it as it was; exported to PC2 and MDD files that
Blender's Mesh Cache modifier plays and to shape keys (a cancelled export changes nothing); then
saved with the shape keys."""

import os

import bpy
import numpy as np
from support import blender as support

frame_cache, frame_keys, operators, timeline, frame_display, posing = support.enable_addon(
    "playback.frame_cache",
    "playback.frame_keys",
    "playback.operators",
    "playback.timeline",
    "playback.frame_display",
    "pose.posing",
)
obj, V, controller = support.keyed_suzanne(10, 15, 20, 400)
scene = bpy.context.scene
scene.frame_set(3)
size = np.ptp(V, axis=0).max()

# Without a cache nor dynamics, the frame handler leaves the mesh alone.
before = support.mesh_state(obj)
scene.frame_set(4)
assert support.mesh_state(obj) == before and frame_cache.get(obj) is None

# The job the operator ticks on its timer: cancelled (Esc) after three frames, or failing on the
# third, it leaves the cache (none here) and the mesh as they were, and the frame where it was.
job = operators.CacheJob(bpy.context, obj, 1, 10)
job.start()
assert (
    job.tick()
    and job.tick()
    and job.tick()
    and job.overall == 0.3
    and len(frame_cache.get(obj)) == 3
)
job.cancel()
assert not job.tick()
assert (
    job.finish() == ("WARNING", "Cache bake cancelled: the cache is as it was") and not job.written
)
assert (
    support.mesh_state(obj) == before and scene.frame_current == 4 and frame_cache.get(obj) is None
)
job = operators.CacheJob(bpy.context, obj, 1, 10)
job.player.next = lambda *args, **kwargs: 1 / 0  # frame 2, after frame 1's first()
job.run()
level, message = job.finish()
assert level == "ERROR" and message == "Cache bake failed: division by zero" and not job.written, (
    message
)
assert (
    support.mesh_state(obj) == before and scene.frame_current == 4 and frame_cache.get(obj) is None
)
del job.player.next  # the player is kept for the object's next frames

assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=10) == {"FINISHED"}
cache = frame_cache.get(obj)
assert cache.kind == "STATIC" and (cache.start, cache.end) == (1, 10) and scene.frame_current == 4
assert cache.nbytes() < 20000, cache.nbytes()  # a shape key per frame would take 12 bytes a vertex
assert obj.data.shape_keys is None and obj.modifiers[0].name == frame_display.MODIFIER, (
    "not shown by the display"
)
assert np.array_equal(support.positions(obj), V), "the artist's mesh changed"

# Against the solve per frame as Bake Animation did it before the cache (a pose, converged frame
# after frame from the previous one, mapped by the solver): the same poses within the solver's
# tolerance (the cache's solver warm-started through other frames: the jobs above).
pose = posing.Pose(bpy.context, obj)
shown = {}
for frame in range(1, 11):
    scene.frame_set(frame)
    pose.follow_controllers()
    pose.converge()
    shown[frame] = support.evaluated_positions(obj)
    error = np.abs(shown[frame] - pose.solver.positions()).max() / size
    assert error < 1e-4, (
        f"frame {frame}: the cache plays {error:.2e} of the size away from the solve"
    )
moved = np.abs(shown[10] - V).max()
assert moved > 0.3, f"the animated handle did not move the mesh ({moved})"

# Scrubbing back reads the cache: nothing is solved.
player = timeline.player(obj, scene)
player.first = player.next = None
for frame in (7, 2, 9):
    scene.frame_set(frame)
    assert support.evaluated_positions(obj).tobytes() == shown[frame].tobytes()
del player.first, player.next
# Before the first frame the mesh holds it.
scene.frame_set(-3)
assert support.evaluated_positions(obj).tobytes() == shown[1].tobytes()

# A changed keyframe cuts the cache at the first frame its motion changed (2: the curve from frame
# 1 to 10 bends anew), and the frames played after it are solved again.
kept = cache.array("q")[:1].tobytes()
scene.frame_set(10)
controller.location.y += 0.5
controller.keyframe_insert("location", frame=10)
scene.frame_set(6)
assert (cache.start, cache.end) == (1, 6), (cache.start, cache.end)
assert cache.array("q")[:1].tobytes() == kept
assert np.abs(support.evaluated_positions(obj) - shown[6]).max() > 0.05, (
    "frame 6 kept the old motion"
)
# A jump forward solves every frame up to it.
scene.frame_set(10)
assert cache.end == 10 and np.abs(support.evaluated_positions(obj) - shown[10]).max() > 0.3
# A stiffness change empties it; the static cache keeps the range baked from.
obj.modal_deform.stiffness *= 2
scene.frame_set(3)
assert (frame_cache.get(obj).start, frame_cache.get(obj).end) == (1, 3)
obj.modal_deform.stiffness /= 2
assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=10) == {"FINISHED"}
scene.frame_set(10)
final = {f: None for f in (1, 5, 10)}
for frame in final:
    scene.frame_set(frame)
    final[frame] = support.evaluated_positions(obj).copy()

# Point-cache files, played by Blender's own Mesh Cache modifier on a copy of the mesh without keys.
for fmt in ("PC2", "MDD"):
    path = support.tmp(f"suzanne.{fmt.lower()}")
    assert bpy.ops.modal_deform.export_mesh_cache(filepath=path, file_format=fmt) == {"FINISHED"}
    assert os.path.getsize(path) == {"PC2": 32, "MDD": 8 + 4 * 10}[fmt] + 10 * 12 * len(V)
    copy = bpy.data.objects.new(f"Played {fmt}", obj.data.copy())
    scene.collection.objects.link(copy)
    copy.shape_key_clear()
    modifier = copy.modifiers.new("Mesh Cache", "MESH_CACHE")
    modifier.cache_format, modifier.filepath, modifier.frame_start = fmt, path, 1
    for frame, expected in final.items():
        scene.frame_set(frame)
        error = np.abs(support.evaluated_positions(copy) - expected).max()
        assert error < 1e-6, f"{fmt} frame {frame}: the Mesh Cache modifier plays {error} away"
    bpy.data.objects.remove(copy)

# Shape keys: one per frame in place of the cache (the export cancelled after two frames changes
# nothing), and the file saved for a Blender without the add-on.
before = support.mesh_state(obj)
job = frame_keys.AnimationJob(
    bpy.context, obj, operators.cached_frames(obj), positions=operators.cached_positions(obj, scene)
)
assert job.tick() and job.tick() and len(obj.data.shape_keys.key_blocks) == 3
job.cancel()
assert job.finish() == ("WARNING", "Shape key export cancelled: nothing changed")
assert support.mesh_state(obj) == before and frame_cache.get(obj) is not None
assert bpy.ops.modal_deform.export_shape_keys() == {"FINISHED"}
assert frame_cache.get(obj) is None
names = [b.name for b in obj.data.shape_keys.key_blocks]
assert names == ["Basis"] + [f"Modal Deform {f:04d}" for f in range(1, 11)], names
for frame, expected in final.items():
    np.save(support.tmp(f"frame{frame}.npy"), expected)
    assert support.key_positions(obj, f"Modal Deform {frame:04d}").tobytes() == expected.tobytes()
np.save(support.tmp("rest.npy"), V)
scene.frame_set(1)
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("animated.blend"))
