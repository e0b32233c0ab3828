"""Binding on a rig (issue 50): with Follow Rig, a handle's controller bound while the rig is posed
holds its vertices where the rig puts them until the controller itself moves. A tube skinned to a
chain of three bones, its middle bone bent; an Empty (parented to the armature object) grabs the
middle ring, weighted to two bones, and a bone of another chain grabs the free end. Bound in that
pose: the mesh is the Armature modifier's result, still when the armature object moves with the
mesh; moving the other chain's bone carries the free end from where the rig put it."""

import bpy
import numpy as np
from mathutils import Quaternion
from support import blender as support
from support import rig as rig_support

timeline, frame_display, handles, mdc = support.enable_addon(
    "playback.timeline", "playback.frame_display", "handles", "core"
)
scene, view_layer = bpy.context.scene, bpy.context.view_layer
LENGTH, BONES = 3.0, 3
V, F = mdc.testing.cylinder(12, 24, radius=0.2, length=LENGTH)
obj = support.mesh_object("Tube", V, F)
obj.location, obj.rotation_euler = (0.4, -0.3, 0.2), (0.0, 0.0, 0.5)
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 12, 20, 300
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
size = np.ptp(V, axis=0).max()

# The armature: the chain along z, and a root bone of another chain beside it, deforming nothing.
rig = rig_support.chain_armature("Rig", BONES, LENGTH, obj.matrix_world)
view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
other = rig.data.edit_bones.new("Other")
other.head, other.tail, other.use_deform = (1, 0, 0), (1, 0, 1), False
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj

# Weights along z, linear between the bones' centres; an Armature modifier.
rig_support.skin(obj, rig, rig_support.chain_weights(V[:, 2], BONES, LENGTH))
obj.parent = rig
obj.matrix_parent_inverse = rig.matrix_world.inverted()
dynamics = obj.modal_deform.dynamics
dynamics.enabled, dynamics.follow_rig = True, True
dynamics.period, dynamics.damping = 8.0, 0.5
assert bpy.ops.modal_deform.fill_attach() == {"FINISHED"}
obj.vertex_groups["Attach"].remove([int(i) for i in np.flatnonzero(V[:, 2] > 0.4)])

# The pose the handles are bound in: the middle bone bent, held from frame 1 on.
bent = rig.pose.bones["Bone1"]
bent.rotation_quaternion = Quaternion((1.0, 0.0, 0.0), 0.6)
bent.keyframe_insert("rotation_quaternion", frame=1)
scene.frame_start, scene.frame_end = 1, 120
scene.frame_set(1)
view_layer.update()

middle = np.flatnonzero(np.abs(V[:, 2] - LENGTH / 2) < 0.15)  # weighted to Bone1 and its neighbours
tip = np.flatnonzero(V[:, 2] > LENGTH - 0.2)
empty = bpy.data.objects.new("Grip", None)
scene.collection.objects.link(empty)
empty.parent, empty.location = rig, (0.3, 0.2, 1.0)
view_layer.update()
for name, indices, controller, bone in (
    ("Middle", middle, empty, ""),
    ("Tip", tip, rig, "Other"),
):
    group = obj.vertex_groups.new(name=name)
    group.add([int(i) for i in indices], 1.0, "REPLACE")
    handle = obj.modal_deform.handles.add()
    handle.name, handle.vertex_group, handle.controller = name, name, controller
    handle.bone = bone  # binds
    assert not np.allclose(np.array(handle.bind_skinning), np.eye(4), atol=1e-3), name


def offset():
    return frame_display.offset_values(obj.data).copy()


def shown_error(frame):
    """The largest offset at `frame` (zero: the mesh is the Armature modifier's result)."""
    scene.frame_set(frame)
    assert obj.name not in timeline.problems, timeline.problems[obj.name]
    return np.abs(offset()).max() / size


bound = shown_error(1)
assert bound < 1e-5, f"bound in a posed rig, the handles pull the mesh off it: {bound}"

# The armature object jumps with the mesh and the Empty (its children): afterwards nothing has moved
# in the mesh's frame, so the mesh settles back onto the rig.
rig.keyframe_insert("location", frame=10)
rig.location.x += 1.0
rig.rotation_euler.z += 0.4
rig.keyframe_insert("location", frame=14)
rig.keyframe_insert("rotation_euler", frame=14)
rig.rotation_euler.z -= 0.4
rig.keyframe_insert("rotation_euler", frame=10)
rig.rotation_euler.z += 0.4
moving = max(shown_error(f) for f in range(10, 20))
settled = shown_error(60)
assert moving > 1e-3, f"the jump moved nothing: {moving}"
assert settled < 1e-4, f"after the armature and the mesh moved together: {settled}"


# The other chain's bone moves: the free end follows it from where the rig put it.
def world_tip():
    world = np.array(obj.matrix_world)
    return support.evaluated_positions(obj)[tip] @ world[:3, :3].T + world[:3, 3]


scene.frame_set(60)
before = world_tip().mean(axis=0)
pose_other = rig.pose.bones["Other"]
start = rig.matrix_world @ pose_other.matrix
pose_other.keyframe_insert("location", frame=60)
pose_other.location = (0.0, 0.0, -0.3)  # along the bone's local z
pose_other.keyframe_insert("location", frame=64)
scene.frame_set(110)
end = rig.matrix_world @ pose_other.matrix
motion = np.array((end @ start.inverted()).translation)
moved = world_tip().mean(axis=0) - before
along = moved @ motion / (motion @ motion)
print(
    f"bound in a posed rig: offset at bind {bound:.1e}, settled after the jump {settled:.1e} "
    f"of the size; the free end follows the other chain's bone {along:.2f} of its motion"
)
assert 0.6 < along < 1.05, (moved, motion)
assert np.linalg.norm(moved - along * motion) < 0.3 * np.linalg.norm(motion), (moved, motion)
print("rig bind: all checks passed")
