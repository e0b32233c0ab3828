"""Dynamics following a rig (issue 50, items 2, 3 and 5): a tube skinned by an Armature modifier to a
chain of three bones (weights by formula), attached at its base (Fill Attach from Armature, then
the top taken out as an artist paints it), with a corrective shape key. The armature object is
keyed to jump and stop: before the jump the mesh is the Armature modifier's result to the bit, the
free end lags and overshoots, and settles back to that result; frames are the same bits played,
jumped to, baked, and after Free; both exports (rest space, skinned) play back in Blender's Mesh
Cache modifier; bad rigs are refused with a message in the panel's problem, and the artist's mesh,
weights and keyframes never change. A rig of 200 bones plays."""

import os
import time
import types

import bpy
import numpy as np
from mathutils import Quaternion
from support import blender as support
from support import rig as rig_support

timeline, frame_cache, frame_display, frame_keys, rig_module, ui, mdc = support.enable_addon(
    "playback.timeline",
    "playback.frame_cache",
    "playback.frame_display",
    "playback.frame_keys",
    "playback.rig",
    "ui",
    "core",
)
scene, view_layer = bpy.context.scene, bpy.context.view_layer
LENGTH, BONES = 3.0, 3
V, F = mdc.testing.cylinder(12, 24, radius=0.2, length=LENGTH)
obj = support.mesh_object("Tube", V, F)
obj.location, obj.rotation_euler = (0.4, -0.3, 0.2), (0.0, 0.0, 0.5)
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 12, 20, 300
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
size = np.ptp(V, axis=0).max()


def make_armature(name, bones=BONES):
    """An armature object placed as the mesh object, a chain of `bones` bones along z."""
    return rig_support.chain_armature(name, bones, LENGTH, obj.matrix_world)


def weight(target, armature, bones=BONES):
    """Vertex groups named like the bones, weights by chain_weights, and an Armature modifier."""
    return rig_support.skin(target, armature, chain_weights(V[:, 2], bones))


def chain_weights(z, bones=BONES):
    return rig_support.chain_weights(z, bones, LENGTH)


rig = make_armature("Rig")
armature_modifier = weight(obj, rig)
obj.parent = rig  # the character moves with its armature object (and is skinned by its bones)
obj.matrix_parent_inverse = rig.matrix_world.inverted()
# A corrective shape key, active: it bulges the middle ring, and must still apply under the display.
obj.shape_key_add(name="Basis")
corrective = obj.shape_key_add(name="Corrective", from_mix=False)
bulge = np.abs(V[:, 2] - LENGTH / 2) < 0.3
co = V.copy()
co[bulge, :2] *= 1.3
corrective.data.foreach_set("co", co.astype(np.float32).ravel())
corrective.value = 1.0
obj.active_shape_key_index = 1

dynamics = obj.modal_deform.dynamics
dynamics.enabled, dynamics.follow_rig = True, True
dynamics.period, dynamics.damping = 8.0, 0.3

# No Attach group yet: refused with a message.
scene.frame_set(1)
assert "no Attach group" in timeline.problems.get(obj.name, ""), timeline.problems
# Fill Attach from Armature: every vertex is within a quarter of a bone's length of the chain.
assert bpy.ops.modal_deform.fill_attach() == {"FINISHED"}
attach = obj.vertex_groups[dynamics.attach_group]
assert dynamics.attach_group == "Attach"
held = [v.index for v in obj.data.vertices if any(g.group == attach.index for g in v.groups)]
assert len(held) == len(V), len(held)
# Painted: only the base stays attached.
attach.remove([int(i) for i in np.flatnonzero(V[:, 2] > 0.4)])

# The reference: the same mesh and modifiers without the add-on's display.
reference = obj.copy()
scene.collection.objects.link(reference)
reference.modal_deform.dynamics.enabled = False
reference.modal_deform.dynamics.cache = None
for modifier in list(reference.modifiers):
    if modifier.type == "NODES":
        reference.modifiers.remove(modifier)
free_end = V[:, 2] > LENGTH - 0.3

# Keys: the armature object jumps by 1.5 along x between frames 6 and 10 and stops.
rig.keyframe_insert("location", frame=6)
rig.location.x += 1.5
rig.keyframe_insert("location", frame=10)
# Then the middle bone bends fast (the chain's free end follows through) and stops.
bend = rig.pose.bones["Bone1"]
bend.keyframe_insert("rotation_quaternion", frame=30)
bend.rotation_quaternion = Quaternion((1.0, 0.0, 0.0), 0.6)
bend.keyframe_insert("rotation_quaternion", frame=34)
scene.frame_start, scene.frame_end = 1, 90
frozen = support.mesh_state(obj)


def group_weights():
    return {
        g.name: rig_module.mesh_io.group_weights(obj, g.name).tobytes() for g in obj.vertex_groups
    }


def keyframes():
    curves = frame_keys.action_fcurves(rig.animation_data)
    return [(c.data_path, tuple(p.co)) for c in curves for p in c.keyframe_points]


weights_before, keys_before = group_weights(), keyframes()


def offset():
    return frame_display.offset_values(obj.data).copy()


played, shown = {}, {}
for frame in range(1, 91):
    scene.frame_set(frame)
    assert obj.name not in timeline.problems, timeline.problems[obj.name]
    if frame == 1:
        player = timeline.player(obj, scene)  # the rig is read once: playback's writes keep it
    assert timeline.player(obj, scene) is player
    played[frame], shown[frame] = offset(), support.evaluated_positions(obj)
    if frame <= 6:  # before the jump: exactly the Armature modifier's result, shape key included
        assert not played[frame].any(), frame
        expected = support.evaluated_positions(reference)
        assert shown[frame].tobytes() == expected.tobytes(), (
            f"frame {frame} before motion is not the armature's",
            np.abs(shown[frame] - expected).max(),
        )
# The jump: the free end lags (against x in rest space), overshoots, and settles.
along = np.array([played[f][free_end, 0].mean() for f in range(1, 91)]) / size
assert along[6:11].min() < -0.01, np.round(along[:30], 4)
assert along[10:30].max() > 0.005, np.round(along[:30], 4)
bent = np.array([np.abs(played[f][free_end]).max() for f in range(28, 60)]) / size
assert bent[3:10].max() > 10 * bent[:3].max(), np.round(bent, 4)  # follow-through
assert bent[-5:].max() < 0.1 * bent.max(), np.round(bent, 4)  # and it decays
assert np.abs(played[90]).max() < 1e-5 * size, np.abs(played[90]).max()
scene.frame_set(90)
settled = np.abs(support.evaluated_positions(obj) - support.evaluated_positions(reference)).max()
assert settled < 1e-5 * size, settled
# With motion the corrective still applies: the mesh is the skinning of basis + key + offset.
scene.frame_set(12)
player = timeline.player(obj, scene)
cache = frame_cache.get(obj)
rig_frame = cache.array("rig")[cache.row(12)].reshape(-1, 4, 4)
keyed = np.where(bulge[:, None], co, V) + played[12]
expected = player.rig.skinned(keyed, rig_frame)
error = np.abs(support.evaluated_positions(obj) - expected).max()
assert error < 1e-5 * size, f"the corrective key under the offset: {error}"
print(f"settle error {settled / size:.2e} of the size; peak lag {along[6:11].min():.4f}")

# The same bits jumped to, scrubbed, baked, and after Free and replay.
timeline.free(obj)
scene.frame_set(1)
scene.frame_set(50)  # simulates 2..49 without showing them
assert offset().tobytes() == played[50].tobytes(), "jumped to differs from played"
scene.frame_set(23)
assert offset().tobytes() == played[23].tobytes()
cache = frame_cache.get(obj)
cache.cut(37)  # a cut inside a block of BFGS's memory
scene.frame_set(60)
assert offset().tobytes() == played[60].tobytes(), "after a cut"
assert bpy.ops.modal_deform.bake_animation() == {"FINISHED"}
for frame in (90, 8, 44):
    scene.frame_set(frame)
    assert offset().tobytes() == played[frame].tobytes(), f"the bake differs at {frame}"
    assert support.evaluated_positions(obj).tobytes() == shown[frame].tobytes(), frame
# As after an undo (which makes every Player again): stepped on from the cache alone.
cache = frame_cache.get(obj)
cache.cut(70)
timeline._players.clear()
scene.frame_set(75)
assert offset().tobytes() == played[75].tobytes(), "after the Players were made again"
# Weights painted (the Attach group grown): the cache is made again from its start.
scene.frame_set(20)
attach.add([int(np.flatnonzero(V[:, 2] > 0.4)[0])], 1.0, "REPLACE")  # reported as an edit
scene.frame_set(21)
assert frame_cache.get(obj).end == 21 and frame_cache.get(obj).row(1) == 0
assert offset().tobytes() != played[21].tobytes()
attach.remove([int(np.flatnonzero(V[:, 2] > 0.4)[0])])
scene.frame_set(22)
assert offset().tobytes() == played[22].tobytes()
assert bpy.ops.modal_deform.bake_animation() == {"FINISHED"}

# Exports, played by Blender's Mesh Cache modifier on copies without the add-on.
for space in ("REST", "SKINNED"):
    path = support.tmp(f"tube_{space.lower()}.pc2")
    assert bpy.ops.modal_deform.export_mesh_cache(filepath=path, space=space) == {"FINISHED"}
    copy = reference.copy()
    scene.collection.objects.link(copy)
    cached = copy.modifiers.new("Mesh Cache", "MESH_CACHE")
    cached.cache_format, cached.filepath, cached.frame_start = "PC2", path, 1
    if space == "REST":  # the positions before the Armature modifier
        with bpy.context.temp_override(object=copy):
            bpy.ops.object.modifier_move_to_index(modifier=cached.name, index=0)
    else:  # the skinned mesh itself, without the shape key and the Armature modifier
        copy.modifiers.remove(copy.modifiers["Armature"])
    corrective.mute = True  # a file holds positions: the shape key is not in them
    for frame in (3, 8, 12, 33):
        scene.frame_set(frame)
        error = np.abs(support.evaluated_positions(copy) - support.evaluated_positions(obj)).max()
        assert error < 1e-6 * size, f"{space} export at frame {frame}: {error}"
    corrective.mute = False
    bpy.data.objects.remove(copy)
# Shape keys in rest space: they add to the corrective before the Armature modifier, as the
# offset did; the cache goes and Dynamics is turned off (the keys take their place).
assert bpy.ops.modal_deform.export_shape_keys() == {"FINISHED"}
assert frame_cache.get(obj) is None and not dynamics.enabled
for frame in (8, 12, 30):
    scene.frame_set(frame)
    error = np.abs(support.evaluated_positions(obj) - shown[frame]).max()
    assert error < 1e-6 * size, f"shape key export at frame {frame}: {error}"
frame_keys.remove_keys(obj, [f"Modal Deform {f:04d}" for f in range(1, 91)])
obj.active_shape_key_index = 1
dynamics.enabled = True

# Bad input: each refused with a message while the timeline plays on; nothing of the artist's
# changes, and the display goes (the mesh is the Armature modifier's).


class Layout:
    """A stand-in for a panel's layout (headless Blender draws no panel): records what it shows."""

    def __init__(self, shown):
        self.shown = shown

    def __getattr__(self, name):
        def record(*args, **kwargs):
            self.shown.append((name, args, kwargs))
            return self

        return record


def dynamics_panel():
    """What the Dynamics panel draws for obj: (call, args, kwargs) of its layout."""
    drawn = []
    context = types.SimpleNamespace(
        object=obj,
        scene=scene,
        region=types.SimpleNamespace(width=400),
        preferences=types.SimpleNamespace(system=types.SimpleNamespace(ui_scale=1.0)),
    )
    ui.VIEW3D_PT_modal_deform_dynamics.draw(types.SimpleNamespace(layout=Layout(drawn)), context)
    return drawn


def panel_text(drawn):
    return " ".join(kwargs.get("text", "") for name, _, kwargs in drawn if name == "label")


def refused(fragment, frame=31):
    scene.frame_set(frame)
    problem = timeline.problems.get(obj.name, "")
    assert fragment in problem, f"expected {fragment!r}, got {problem!r}"
    assert fragment in panel_text(dynamics_panel())
    assert not frame_display.shows(obj) or not frame_display.offset_values(obj.data).any()
    print("refused:", problem)


def plays(frame=32):
    scene.frame_set(frame)
    assert obj.name not in timeline.problems, timeline.problems[obj.name]


armature_modifier.use_deform_preserve_volume = True
refused("Preserve Volume")
armature_modifier.use_deform_preserve_volume = False
armature_modifier.show_viewport = False
refused("disabled")
armature_modifier.show_viewport = True
plays()
with bpy.context.temp_override(object=obj):
    bpy.ops.object.modifier_move_to_index(modifier=armature_modifier.name, index=0)
refused("comes before")
plays(33)  # the display is put back first
assert frame_display.modifier_of(obj) == obj.modifiers[0]
second = obj.modifiers.new("Armature.001", "ARMATURE")
second.object = rig
refused("2 Armature modifiers")
obj.modifiers.remove(second)
armature_modifier.object = None
refused("has no armature")
armature_modifier.object = rig
plays()
attach_name = dynamics.attach_group
dynamics.attach_group = "Empty"
refused("does not exist")
obj.vertex_groups.new(name="Empty")
refused("holds no vertex")
obj.vertex_groups.remove(obj.vertex_groups["Empty"])
dynamics.attach_group = attach_name
plays()
# The armature itself as a handle's controller on the mesh it skins.
handle_group = obj.vertex_groups.new(name="Tip")
handle_group.add([int(i) for i in np.flatnonzero(free_end)], 1.0, "REPLACE")
handle = obj.modal_deform.handles.add()
handle.name, handle.vertex_group, handle.controller = "Tip", "Tip", rig
refused("skins")
# One of its bones, bound in the rig's rest pose (frame 1): the handle holds the tip where that
# bone puts it, as the skinning does: the first frame is the Armature modifier's result (to float
# precision), and the rig plays.
scene.frame_set(1)
handle.bone = "Bone2"
timeline.free(obj)
plays(1)
assert np.abs(offset()).max() < 1e-6 * size, np.abs(offset()).max()
plays(32)
# The bone under the handle scaled to nothing: refused, naming the handle (a clear message where
# the rest-space transform's inverse does not exist).
rig.pose.bones["Bone2"].scale = (0.0, 0.0, 0.0)
refused("bones under handle 'Tip' blend to a singular matrix", 32)
rig.pose.bones["Bone2"].scale = (1.0, 1.0, 1.0)
plays(32)
obj.modal_deform.handles.remove(0)
obj.vertex_groups.remove(handle_group)
# A bone renamed: Blender renames its vertex group, the rig plays on.
rig.data.bones["Bone2"].name = "Tip Bone"
assert obj.vertex_groups.get("Tip Bone") is not None
plays()
rig.data.bones["Tip Bone"].name = "Bone2"
# A deforming bone with no weighted vertex plays; scaled and sheared bones play (skinned as the
# Armature modifier skins them).
view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
spare = rig.data.edit_bones.new("Spare")
spare.head, spare.tail = (1, 0, 0), (1, 0, 1)
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj
plays()
assert "Spare" not in timeline.player(obj, scene).rig.bones
view_layer.objects.active = rig  # a bone added before the chain's: the pose indexed again
bpy.ops.object.mode_set(mode="EDIT")
rig.data.edit_bones.remove(rig.data.edit_bones["Spare"])
rig.data.edit_bones.new("Aaa").tail = (0, 0.1, 0)
rig.data.edit_bones["Aaa"].use_deform = False
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj
plays(33)
frame_cache.get(obj).cut(33)
scene.frame_set(34)
scene.frame_set(33)
assert offset().tobytes() == played[33].tobytes(), "the pose's bones indexed again"
rig.pose.bones["Bone1"].scale = (1.0, 1.4, 0.8)
plays(34)
assert np.isfinite(offset()).all()
rig.pose.bones["Bone1"].scale = (1.0, 1.0, 1.0)
rig.scale = (0.0, 1.0, 1.0)
refused("scaled to nothing", 34)
rig.scale = (1.0, 1.0, 1.0)
# A weighted bone deleted: the vertices weighted to it alone are weighted to no bone, which the
# panel says, and stay where the Armature modifier leaves them (unskinned); the bone made again,
# all is as before (the vertex groups were never touched).
view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
rig.data.edit_bones.remove(rig.data.edit_bones["Bone2"])
bpy.ops.object.mode_set(mode="OBJECT")
plays(35)
warnings = timeline.rig_warnings(obj)
alone = np.count_nonzero(chain_weights(V[:, 2])[:, 2] == 1)
assert any(f"{alone} vertices are weighted to no bone" in w for w in warnings), (alone, warnings)
print("warned:", warnings)
scene.frame_set(36)
unskinned = np.flatnonzero(chain_weights(V[:, 2])[:, 2] == 1)
error = np.abs(
    support.evaluated_positions(obj)[unskinned] - support.evaluated_positions(reference)[unskinned]
).max()
offset_there = np.abs(offset()[unskinned]).max()
assert error <= offset_there + 1e-6, (error, offset_there)

drawn = dynamics_panel()
props = [args[1] for name, args, _ in drawn if name in ("prop", "prop_search")]
assert "follow_rig" in props and "attach_group" in props, props
operators = [args[0] for name, args, _ in drawn if name == "operator"]
assert "modal_deform.fill_attach" in operators, operators
assert "weighted to no bone" in panel_text(drawn)
bpy.ops.object.mode_set(mode="EDIT")
bone = rig.data.edit_bones.new("Bone2")
bone.head, bone.tail = (0, 0, 2 * LENGTH / 3), (0, 0, LENGTH)
bone.parent, bone.use_connect = rig.data.edit_bones["Bone1"], True
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj
plays(37)
assert not timeline.rig_warnings(obj)
# Follow Rig off: the display of positions again, the offset attribute gone.
dynamics.follow_rig = False
scene.frame_set(38)
assert frame_display.OFFSET_ATTRIBUTE not in obj.data.attributes
dynamics.follow_rig = True
plays(38)  # and the offset display in its place
assert frame_display.shows_offset(obj) and frame_display.ATTRIBUTE not in obj.data.attributes
assert keyframes() == keys_before, "the rig's keyframes changed"
# The armature deleted.
bpy.data.objects.remove(rig)
refused("has no armature", 37)
for state in (frozen, now := support.mesh_state(obj)):  # the caches come and go
    state["palettes"] = [p for p in state["palettes"] if not p.startswith(frame_cache.PREFIX)]
assert now == frozen, "the artist's mesh changed"
after = group_weights()
assert all(after[name] == weights_before[name] for name in weights_before), "weights changed"

# A rig of 200 bones plays, its frames cheap.
many = make_armature("Many", bones=200)
big = obj.copy()
big.data = obj.data.copy()
big.name = "Tube 200"
scene.collection.objects.link(big)
for group in list(big.vertex_groups):
    if group.name.startswith("Bone"):
        big.vertex_groups.remove(group)
big.modifiers.remove(big.modifiers["Armature"])
W = chain_weights(V[:, 2], 200)
rig_support.skin(big, many, W)
big.parent, big.matrix_parent_inverse = many, many.matrix_world.inverted()
many.keyframe_insert("rotation_euler", frame=1)
many.rotation_euler.x = 0.5
many.keyframe_insert("rotation_euler", frame=5)
big.modal_deform.dynamics.cache = None
obj.modal_deform.dynamics.enabled = False
timings = []
for frame in range(1, 12):
    start = time.perf_counter()
    scene.frame_set(frame)
    timings.append(time.perf_counter() - start)
    assert big.name not in timeline.problems, timeline.problems[big.name]
used = np.flatnonzero((W > 0).any(axis=0))  # more bones than rings: some weigh no vertex
assert timeline.player(big, scene).rig.bones == [f"Bone{b}" for b in used]
assert len(used) > 40 and len(many.data.bones) == 200
assert np.abs(frame_display.offset_values(big.data)).max() > 0
print(f"200 bones: a frame {1000 * np.median(timings[2:]):.1f} ms (whole frame change)")

# Saved and loaded: the cached frames (rig included) read back, and a frame stepped again from them
# is the same bits.
before = {f: frame_display.offset_values(big.data).copy() for f in (11,)}
scene.frame_set(8)
before[8] = frame_display.offset_values(big.data).copy()
path = support.tmp("rig.blend")
bpy.ops.wm.save_as_mainfile(filepath=path)
bpy.ops.wm.open_mainfile(filepath=path)
scene, big = bpy.context.scene, bpy.data.objects["Tube 200"]
scene.frame_set(8)
assert frame_display.offset_values(big.data).tobytes() == before[8].tobytes()
frame_cache.get(big).cut(10)
scene.frame_set(11)
assert frame_display.offset_values(big.data).tobytes() == before[11].tobytes(), "after a reload"
print("rig dynamics: all checks passed", os.environ.get("TEST_TMP", ""))
