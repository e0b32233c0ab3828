"""Partial keys, a bone as a controller, and the cache's operators on in-betweens (issue 51): the
head's Empty keyed at frames 1, 10 and 20, a bone holding the left ear keyed at 1 and 15 only (so
each is free where only the other is keyed); the motion passes through every key of each; the
bone's keys on another bone count for nothing; Export Mesh Cache writes the frames the timeline
shows, Free empties the cache and the next frame solves the same motion again."""

import bpy
import numpy as np
from mathutils import Euler
from support import blender as support

frame_cache, timeline, handles, motion, keys_, point_cache, mdc = support.enable_addon(
    "playback.frame_cache",
    "playback.timeline",
    "handles",
    "inbetweens.motion",
    "inbetweens.keys",
    "playback.point_cache",
    "core",
)
scene, view_layer = bpy.context.scene, bpy.context.view_layer
obj, V = support.baked_suzanne(1, 12, 20, 400)
diagonal = np.linalg.norm(np.ptp(V, axis=0))
head = support.add_handle(obj, (np.hypot(V[:, 0], V[:, 1]) < 0.55) & (V[:, 2] > -0.35))
ear = support.add_handle(obj, V[:, 0] > 1.1)
bpy.data.objects.remove(ear.controller)

rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
scene.collection.objects.link(rig)
view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
for name, x in (("Ear", 1.3), ("Other", -1.3)):
    bone = rig.data.edit_bones.new(name)
    bone.head, bone.tail = (x, 0.0, 0.2), (x, 0.0, 0.6)
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj
ear.controller, ear.bone = rig, "Ear"

scene.frame_start, scene.frame_end = 1, 30
for frame, turn in ((1, 0.0), (10, 0.4), (20, -0.2)):
    head.controller.rotation_euler = Euler((0.0, turn, 0.0))
    head.controller.keyframe_insert("rotation_euler", frame=frame)
pose_bone = rig.pose.bones["Ear"]
for frame, lift in ((1, 0.0), (15, 0.15)):
    pose_bone.location = (0.0, lift, 0.0)  # along the bone: up
    pose_bone.keyframe_insert("location", frame=frame)
other = rig.pose.bones["Other"]
other.keyframe_insert("location", frame=7)  # another bone's key: not the ear's
obj.modal_deform.dynamics.enabled = obj.modal_deform.dynamics.inbetweens = True

player = timeline.player(obj, scene)
keys = keys_.read(obj, scene, player.handles)
layout = [(f, [T is not None for T in transforms]) for f, transforms in keys]
assert layout == [
    (1, [True, True]),
    (10, [True, False]),
    (15, [False, True]),
    (20, [True, False]),
], layout

# A controller without keys holds its place: keyed there at every key frame when moved off its
# bind, none of its own at its bind (a spring at rest, as a pinned handle).
still = support.add_handle(obj, V[:, 0] < -1.1)
for moved in (False, True):
    still.controller.location.z += 0.1 * moved
    found = keys_.read(obj, scene, timeline.player(obj, scene).handles)
    placed = handles.transforms(obj, timeline.player(obj, scene).handles)[2]
    if moved:
        assert all(np.array_equal(transforms[2], placed) for _, transforms in found), found
    else:
        assert all(transforms[2] is None for _, transforms in found), found
bpy.data.objects.remove(still.controller)
obj.modal_deform.handles.remove(2)

shown = {}
for frame in range(1, 31):
    scene.frame_set(frame)
    assert not timeline.problems, timeline.problems
    shown[frame] = support.evaluated_positions(obj)
for frame, transforms in keys:
    for handle, T in zip(player.handles, transforms):
        if T is None:
            continue
        rest = V[handle.indices].astype(np.float64)
        fit = mdc.rigid_fit(rest, shown[frame][handle.indices].astype(np.float64))
        error = np.linalg.norm(np.c_[rest, np.ones(len(rest))] @ (fit - T)[:3].T, axis=1).max()
        print(f"key at frame {frame}, {handle.name}: within {error / diagonal:.2e} of the diagonal")
        assert error < 0.01 * diagonal, (frame, handle.name, error / diagonal)
# Free between keys of the ear: at frame 10 the ear is not where its curve interpolates.
scene.frame_set(10)
interpolated = handles.transforms(obj, player.handles)[1]
rest = V[player.handles[1].indices].astype(np.float64)
fit = mdc.rigid_fit(rest, shown[10][player.handles[1].indices].astype(np.float64))
assert np.abs(fit - interpolated).max() > 1e-3, "the ear follows its curve between its keys"

# Export Mesh Cache: the frames the timeline shows.
path = support.tmp("inbetweens.pc2")
assert bpy.ops.modal_deform.export_mesh_cache(filepath=path, file_format="PC2") == {"FINISHED"}
data = np.fromfile(path, np.float32, offset=32).reshape(30, -1, 3)
assert all(data[f - 1].tobytes() == shown[f].tobytes() for f in range(1, 31))
# Bake (the Dynamics panel's Bake is Solve with in-betweens) is refused with a message.
support.expect_error(bpy.ops.modal_deform.bake_animation, "Solve In-betweens")
digest = frame_cache.digest(frame_cache.get(obj))
# Free: the cache goes; the next frame shown solves the same bits again.
assert bpy.ops.modal_deform.free_cache() == {"FINISHED"} and frame_cache.get(obj) is None
scene.frame_set(12)
assert frame_cache.digest(frame_cache.get(obj)) == digest
assert support.evaluated_positions(obj).tobytes() == shown[12].tobytes()
# The operator solves again (execute: at once) with the same bits.
assert bpy.ops.modal_deform.solve_inbetweens() == {"FINISHED"}
assert frame_cache.digest(frame_cache.get(obj)) == digest
# Export Shape Keys: a key per frame, the cache freed.
assert bpy.ops.modal_deform.export_shape_keys() == {"FINISHED"}
assert len(obj.data.shape_keys.key_blocks) == 31
