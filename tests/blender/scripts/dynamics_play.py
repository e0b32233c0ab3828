"""Secondary motion on Suzanne: the head's controller turns fast and stops; playing the timeline
simulates frame after frame into the cache, the mesh overshoots the static pose and settles;
scrubbing back reads the cache; a jump forward simulates every frame in between and gives the
same bits as playing, and so do frames simulated again after a cut in the middle of a block of
BFGS's memory; a changed keyframe or setting invalidates what follows; Bake gives the same
bits again; Free empties the cache; a mesh edited between frames and a damaged cache are refused."""

import bpy
import numpy as np
from support import blender as support

frame_cache, frame_keys, timeline, frame_display, posing = support.enable_addon(
    "playback.frame_cache",
    "playback.frame_keys",
    "playback.timeline",
    "playback.frame_display",
    "pose.posing",
)
obj, V = support.baked_suzanne(2, 20, 52, 1000)  # the demo's Suzanne and the default basis
size = np.ptp(V, axis=0).max()
# The core of the head is held by the controller, tilted fast and stopped (as the demo does); the
# ears and the chin are free to swing.
controller = support.add_handle(
    obj, (np.hypot(V[:, 0], V[:, 1]) < 0.55) & (V[:, 2] > -0.35)
).controller
controller.keyframe_insert("rotation_euler", frame=1)
controller.rotation_euler.y = 0.6
controller.keyframe_insert("rotation_euler", frame=6)
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 40
dynamics = obj.modal_deform.dynamics
dynamics.enabled = True  # the period and damping the core defaults to


def key():
    return support.evaluated_positions(obj)


# Play: each frame simulated from the one before it.
played = {}
for frame in range(1, 41):
    scene.frame_set(frame)
    cache = frame_cache.get(obj)
    assert (cache.start, cache.end, cache.kind) == (1, frame, "DYNAMIC"), (cache.start, cache.end)
    played[frame] = key()
assert np.array_equal(support.positions(obj), V), "the artist's mesh changed"
# The pose Solve gives for the controller at rest after frame 6: the ears overshoot it, then settle
# (where they are on their way from rest, 0, to that pose, 1).
pose = posing.Pose(bpy.context, obj)
pose.follow_controllers()
pose.converge()
static = pose.solver.positions()
ears = np.abs(V[:, 0]) > 1.0
way = (static[ears] - V[ears]).ravel()
along = np.array(
    [np.dot((played[f][ears] - V[ears]).ravel(), way) / np.dot(way, way) for f in range(1, 41)]
)
assert along[4:12].max() > 1.05, f"no overshoot after the stop: {np.round(along, 3)}"
assert np.abs(along[-5:] - 1).max() < 0.02, f"the motion does not settle: {np.round(along, 3)}"

# Scrubbing back reads the cache: nothing is simulated.
player = timeline.player(obj, scene)
player.next = player.first = None
for frame in (12, 3, 30):
    scene.frame_set(frame)
    assert key().tobytes() == played[frame].tobytes(), frame
del player.next, player.first

# Bake: every frame from the start again, the same bits as playing.
assert bpy.ops.modal_deform.bake_animation() == {"FINISHED"}
assert len(frame_cache.get(obj)) == 40 and scene.frame_current == 30
for frame in (40, 7, 20):
    scene.frame_set(frame)
    assert key().tobytes() == played[frame].tobytes(), (
        f"the bake differs from playing at frame {frame}"
    )

# A cut in the middle of a block of BFGS's memory (memory_frames frames from the cache's start;
# the simulation holds frame 40's): the frames after it simulated again, from the block's first
# frame, the same bits as playing.
memory_frames = timeline.player(obj, scene).simulation.memory_frames
assert 1 < memory_frames < 11, memory_frames
frame_cache.get(obj).cut(2 + memory_frames + memory_frames // 2)
scene.frame_set(30)
assert frame_cache.get(obj).end == 30
for frame in (30, 2 + memory_frames + memory_frames // 2, 2 + 2 * memory_frames):
    scene.frame_set(frame)
    assert key().tobytes() == played[frame].tobytes(), (
        f"simulated again after a cut, frame {frame} differs"
    )

# Free, then a jump forward: every frame up to it simulated, the same bits as playing.
assert bpy.ops.modal_deform.free_cache() == {"FINISHED"}
assert frame_cache.get(obj) is None and not frame_display.shows(obj)
assert support.evaluated_positions(obj).tobytes() == V.tobytes(), "Free left a frame shown"
scene.frame_set(25)
assert frame_cache.get(obj).end == 25 and scene.frame_current == 25
assert key().tobytes() == played[25].tobytes(), "a jump forward differs from playing"

# The keyframes' digest sees every change that moves a curve: a key's point, its handles (free
# handles: auto ones are computed again), its interpolation and easing; the last key's
# interpolation shapes no segment. On a curve of its own.
empty = bpy.data.objects.new("Keys", None)
scene.collection.objects.link(empty)
for frame, z in ((1, 0.0), (6, 0.6)):
    empty.location.z = z
    empty.keyframe_insert("location", index=2, frame=frame)
curve = frame_keys.action_fcurves(empty.animation_data)[0]
points = curve.keyframe_points
for point in points:
    point.handle_left_type = point.handle_right_type = "FREE"
curves = [("Keys:location[2]", curve)]
digests = {frame_cache.keys_digest(curves)}
for change in (
    lambda: setattr(points[0], "interpolation", "LINEAR"),
    lambda: setattr(points[0], "easing", "EASE_IN"),
    lambda: setattr(points[0].handle_right, "y", 0.3),
    lambda: setattr(points[1].co, "y", 0.7),
    lambda: setattr(points[1].handle_left, "x", 4.5),
):
    change()
    digests.add(frame_cache.keys_digest(curves))
assert len(digests) == 6, "a change of a keyframe left the digest as it was"
points[1].interpolation = "CONSTANT"
assert frame_cache.keys_digest(curves) in digests
bpy.data.objects.remove(empty)

# A changed keyframe invalidates from the first frame it changes (2: the turn's curve), and a
# change of a setting everything; what follows is simulated again.
scene.frame_set(5)
controller.rotation_euler.z = 1.2
controller.keyframe_insert("rotation_euler", frame=6)
scene.frame_set(8)
assert frame_cache.get(obj).end == 8
assert frame_cache.get(obj).array("q")[0].tobytes() == frame_cache.get(obj).state(1)[0].tobytes()
assert np.abs(key() - played[8]).max() > 0.01 * size, "frame 8 kept the old motion"
pose = timeline.player(obj, scene).pose
dynamics.damping = 0.3
assert frame_cache.get(obj) is None
scene.frame_set(9)
assert frame_cache.get(obj).end == 9
# A change of a dynamics setting keeps the pose's solver (it starts from rest at the first frame):
# the same bits as a player made anew.
assert timeline.player(obj, scene).pose is pose
kept = key()
timeline.free(obj)
scene.frame_set(9)
assert timeline.player(obj, scene).pose is not pose and key().tobytes() == kept.tobytes()

# Playing compares the mesh's positions with the bake's only when Blender reported an update of the
# mesh (after an edit, or in the next frame's evaluation; never for playback's own writes): an edit
# between frames is refused either way, and undoing it plays again.
compared = []
same_positions = timeline.mesh_io.same_positions
timeline.mesh_io.same_positions = lambda mesh, co: (
    compared.append(mesh.name) or same_positions(mesh, co)
)
for frame in (10, 11, 12):
    scene.frame_set(frame)
    bpy.context.view_layer.update()
assert compared == [] and obj.name not in timeline.problems, (compared, timeline.problems)


def move_vertex(x):
    """Vertex 0 to x (the mesh without shape keys: playback writes none; read anew: Blender 4 moves
    the positions of a mesh when they are written while its evaluated copy shares them)."""
    assert obj.data.shape_keys is None
    obj.data.vertices[0].co.x = x


x = obj.data.vertices[0].co.x
for frame, reported in ((13, bpy.context.view_layer.update), (15, lambda: None)):
    move_vertex(x + 0.1)
    reported()
    scene.frame_set(frame)
    assert "edited after the bake" in timeline.problems.get(obj.name, ""), (
        frame,
        timeline.problems,
    )
    move_vertex(x)
    scene.frame_set(frame + 1)
    assert obj.name not in timeline.problems, (frame, timeline.problems)
assert len(compared) == 4, compared
timeline.mesh_io.same_positions = same_positions
# A damaged cache (an array gone) is refused with a message, and the mesh shows its rest; Free takes it away.
del dynamics.cache["q"]
scene.frame_set(12)
assert "is damaged (no 'q')" in timeline.problems.get(obj.name, ""), timeline.problems
assert key().tobytes() == V.tobytes()
assert bpy.ops.modal_deform.free_cache() == {"FINISHED"} and dynamics.cache is None
