"""In-betweens on Suzanne (issue 51): the head's controller keyed at three frames only; the motion
passes through the keys, differs from Blender's interpolation and from Dynamics between them, plays
the same bits in any order; a key moved solves again while the old motion plays until the new one
is ready; bad keys leave a message and the motion as it was. Saves the file for the reload and the
one-frame render (inbetweens_reload.py)."""

import bpy
import numpy as np
from mathutils import Euler
from support import blender as support

frame_cache, timeline, handles, motion, keys_, mdc = support.enable_addon(
    "playback.frame_cache",
    "playback.timeline",
    "handles",
    "inbetweens.motion",
    "inbetweens.keys",
    "core",
)
obj, V = support.baked_suzanne(1, 12, 20, 400)
diagonal = np.linalg.norm(np.ptp(V, axis=0))
head = support.add_handle(obj, (np.hypot(V[:, 0], V[:, 1]) < 0.55) & (V[:, 2] > -0.35))
controller = head.controller
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 40
# Three poses: rest at 1, turned and raised at 10, turned back the other way at 20.
for frame, turn, lift in ((1, 0.0, 0.0), (10, 0.5, 0.2), (20, -0.3, 0.0)):
    controller.rotation_euler = Euler((0.0, turn, 0.0))
    controller.location.z = lift
    controller.keyframe_insert("rotation_euler", frame=frame)
    controller.keyframe_insert("location", frame=frame)
obj.modal_deform.dynamics.enabled = True
obj.modal_deform.dynamics.inbetweens = True
assert frame_cache.kind(obj) == "INBETWEEN"


def shown():
    return support.evaluated_positions(obj)


def keyed_transform(frame):
    timeline.set_frame(scene, frame)
    return handles.transforms(obj, timeline.player(obj, scene).handles)[0]


def head_error(X, T):
    """How far the head handle's rigid fit in X lies from T, over the mesh's diagonal."""
    rest = V[head_indices].astype(np.float64)
    fit = mdc.rigid_fit(rest, X[head_indices].astype(np.float64))
    points = np.c_[rest, np.ones(len(rest))]
    return np.linalg.norm(points @ (fit - T)[:3].T, axis=1).max() / diagonal


# Played: the first frame shown solves the whole motion (no window: here, at once).
played = {}
for frame in range(1, 41):
    scene.frame_set(frame)
    played[frame] = shown()
    assert not timeline.problems, timeline.problems
cache = frame_cache.get(obj)
assert (cache.kind, cache.start, cache.end) == ("INBETWEEN", 1, 40), (cache.kind, cache.end)
assert np.array_equal(support.positions(obj), V), "the artist's mesh changed"
head_indices = timeline.player(obj, scene).handles[0].indices
for frame in (1, 10, 20):
    error = head_error(played[frame], keyed_transform(frame))
    print(f"key at frame {frame}: the head's fit within {error:.2e} of the diagonal")
    assert error < 0.01, (frame, error)
# Between the keys: not the F-curves' interpolation (the head's fit is elsewhere) ...
between = max(head_error(played[f], keyed_transform(f)) for f in range(11, 20))
print(f"between keys 10 and 20, the head is {between:.3f} of the diagonal off the interpolation")
assert between > 0.01, between
# ... and after the last key it swings on and settles (follow-through): the ears still move.
ears = np.abs(V[:, 0]) > 1.0
swing = [np.abs(played[f + 1][ears] - played[f][ears]).max() for f in range(20, 39)]
assert max(swing) > 1e-3 * diagonal and swing[-1] < max(swing), swing

# Jumped: any frame, any order, the same bits, read from the cache.
player = timeline.player(obj, scene)
player.next = player.first = None  # nothing is simulated frame by frame
for frame in (33, 4, 17, 1, 40, 10):
    scene.frame_set(frame)
    assert shown().tobytes() == played[frame].tobytes(), frame
del player.next, player.first

# In the background: the old motion plays until the new one is ready, and Esc (cancel) keeps it.
digest = frame_cache.digest(cache)
job = motion.InbetweenJob(obj, scene)
job.cancel()
job.start()
while not job.done:
    assert frame_cache.digest(frame_cache.get(obj)) == digest
    job._thread.join(0.01)
level, message = job.finish()
assert level == "WARNING" and "cancelled" in message and not job.written, message
assert frame_cache.digest(frame_cache.get(obj)) == digest

# A key moved (frame 10's to frame 14) solves again: the motion passes through it there now.
for curve in keys_.transform_curves(timeline.player(obj, scene).handles[0]):
    for point in curve.keyframe_points:
        if point.co.x == 10:
            point.co.x += 4
            point.handle_left.x += 4
            point.handle_right.x += 4
    curve.update()
scene.frame_set(14)
moved = frame_cache.get(obj)
assert frame_cache.digest(moved) != digest and not timeline.problems, timeline.problems
assert head_error(shown(), keyed_transform(14)) < 0.01
scene.frame_set(10)
assert shown().tobytes() != played[10].tobytes()
solved = {f: (scene.frame_set(f), shown())[1] for f in (1, 14, 20, 30)}


def refused(fragment):
    """Show a frame: the motion shown is still the last one solved, and the panel says why not
    another."""
    scene.frame_set(20)
    problem = motion.problem(obj)
    assert fragment in problem, (fragment, problem)
    assert shown().tobytes() == solved[20].tobytes(), fragment
    print("refused:", problem)


# Bad keys: a key between frames, on no whole frame.
curve = keys_.transform_curves(timeline.player(obj, scene).handles[0])[0]
point = curve.keyframe_points.insert(25.5, curve.evaluate(25.5))
refused("between two frames")
curve.keyframe_points.remove(point)
# A stray key far away.
point = curve.keyframe_points.insert(5000, 0.0)
refused("from frame 1 to 5000")
curve.keyframe_points.remove(point)
# A thousand keys.
many = curve.keyframe_points
count = len(many)
many.add(1000)
for i in range(1000):
    many[count + i].co = (100 + i, 0.0)
curve.update()
refused("1003 keyed frames")
for _ in range(1000):
    many.remove(many[-1])
curve.update()
scene.frame_set(20)
assert not motion.problem(obj) and frame_cache.digest(frame_cache.get(obj)) == frame_cache.digest(
    moved
), "the keys as they were: the motion as it was"
# A handle whose vertex group changed (renamed away): refused; back, the motion as it was.
head.vertex_group, group = "No Such Group", head.vertex_group
refused("does not exist")
head.vertex_group = group
# No keys at all.
action = controller.animation_data.action
controller.animation_data.action = None
refused("has no keys")
controller.animation_data.action = action
scene.frame_set(20)
assert not motion.problem(obj) and shown().tobytes() == solved[20].tobytes()
# Follow Rig on: refused (the core's motion is not skinned); off again, the same motion.
obj.modal_deform.dynamics.follow_rig = True
scene.frame_set(20)
assert motion.ON_A_RIG in timeline.problems.get(obj.name, ""), timeline.problems
obj.modal_deform.dynamics.follow_rig = False
scene.frame_set(20)
assert not timeline.problems and shown().tobytes() == solved[20].tobytes(), timeline.problems
# A pose the basis cannot reach (the head pulled two sizes away from the pinned rest of the mesh's
# other handle): solved, and the panel says which key is missed.
base = support.add_handle(obj, V[:, 2] < -0.6)
base.controller = None
timeline.player(obj, scene)
scene.frame_set(30)
assert not motion.problem(obj), motion.problem(obj)
controller.location.z = 2 * diagonal
controller.keyframe_insert("location", frame=30)
scene.frame_set(30)
notes = motion.notes(frame_cache.get(obj))
assert any("cannot reach" in n for n in notes), notes
print("notes:", notes)
for curve in keys_.transform_curves(timeline.player(obj, scene).handles[0]):
    for point in list(curve.keyframe_points):
        if point.co.x == 30:
            curve.keyframe_points.remove(point)
obj.modal_deform.handles.remove(len(obj.modal_deform.handles) - 1)

# Dynamics with the same keys, In-betweens off: the interpolated path followed with inertia differs.
dynamics_played = {}
obj.modal_deform.dynamics.inbetweens = False
for frame in range(1, 21):
    scene.frame_set(frame)
    dynamics_played[frame] = shown()
obj.modal_deform.dynamics.inbetweens = True
scene.frame_set(1)
inbetween = {f: (scene.frame_set(f), shown())[1] for f in range(1, 21)}
assert inbetween[14].tobytes() == solved[14].tobytes()
gap = max(np.abs(inbetween[f] - dynamics_played[f]).max() for f in range(2, 21)) / diagonal
print(f"in-betweens against Dynamics on the same keys: {gap:.3f} of the diagonal apart at most")
assert gap > 0.01, gap

# Saved: inbetweens_reload.py plays it again, and renders frame 17 alone in another process.
shown_frames = np.array([(scene.frame_set(f), shown())[1] for f in range(1, 41)])
np.save(support.tmp("inbetweens.npy"), shown_frames)
with open(support.tmp("digest.txt"), "w") as f:
    f.write(frame_cache.digest(frame_cache.get(obj)))
scene.frame_set(1)
scene.render.engine = "BLENDER_WORKBENCH"  # a small, quick render for inbetweens_render.py
scene.render.resolution_x = scene.render.resolution_y = 32
scene.render.filepath = support.tmp("render_")
scene.camera = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
scene.collection.objects.link(scene.camera)
scene.camera.location = (0.0, -8.0, 0.0)
scene.camera.rotation_euler = (1.5708, 0.0, 0.0)
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("inbetweens.blend"))
