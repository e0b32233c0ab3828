"""A bone as a handle's controller (issue 50, item 1): posed in Pose Mode it drives Solve, Pose and
Refine as an Empty moved by the same world transform does; assigning binds, and moving the armature object
together with the mesh deforms nothing; its keyframes drive Bake Animation and Dynamics as those of
an Empty that follows the bone, a changed keyframe of the bone or of a parent invalidates the cache
and one of another bone does not; bad input (the armature that skins the mesh chosen as a whole, a
bone renamed or deleted, the armature deleted, a scaled or sheared bone) is refused or handled with
a message, and the artist's mesh and keyframes stay as they were."""

import bpy
import numpy as np
from mathutils import Matrix, Quaternion
from support import blender as support

handles, posing, frame_cache, timeline, frame_keys, refine_job, mdc = support.enable_addon(
    "handles",
    "pose.posing",
    "playback.frame_cache",
    "playback.timeline",
    "playback.frame_keys",
    "pose.refine",
    "core",
)
scene, view_layer = bpy.context.scene, bpy.context.view_layer
obj, V = support.baked_suzanne(1, 12, 10, 300)
size = np.linalg.norm(np.ptp(V, axis=0))  # the bounding box's diagonal
# The mesh object away from the origin, so that its space is not the world's.
obj.location, obj.rotation_euler = (0.3, -0.2, 0.1), (0.0, 0.0, 0.4)
top = support.top_and_bottom_handles(obj, V)
empty = top.controller


def armature():
    """An armature object "Rig" away from the origin: a bone "Root", its child "Head" and a bone
    "Other" beside them."""
    rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    scene.collection.objects.link(rig)
    rig.location, rig.rotation_euler = (0.5, 0.2, -0.3), (0.2, 0.1, 0.7)
    view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    bones = rig.data.edit_bones
    root = bones.new("Root")
    root.head, root.tail = (0.0, 0.0, -1.0), (0.0, 0.0, 0.0)
    head = bones.new("Head")
    head.head, head.tail, head.parent = (0.0, 0.0, 0.0), (0.0, 0.3, 0.6), root
    other = bones.new("Other")
    other.head, other.tail = (1.0, 0.0, 0.0), (1.0, 0.0, 0.5)
    bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = obj
    return rig


def bone_world(rig, name):
    return rig.matrix_world @ rig.pose.bones[name].matrix


def solve():
    """Solve (the operator) and the "Modal Deform" key it writes."""
    assert bpy.ops.modal_deform.solve() == {"FINISHED"}
    return support.key_positions(obj, posing.POSE_KEY)


def pose_positions():
    """What Pose computes for the controllers as they are (its session, converged)."""
    pose = posing.Pose(bpy.context, obj)
    pose.follow_controllers()
    pose.converge()
    return pose.solver.positions()


def refine():
    """Refine (its job, run here) and the "Modal Deform" key it writes."""
    job = refine_job.RefineJob(bpy.context, obj)
    job.run()
    assert job.finish()[0] == "INFO" and job.written
    return support.key_positions(obj, posing.POSE_KEY)


def transforms():
    return handles.transforms(obj, handles.resolve(obj, scene, V)[0])


def away(A, B):
    """Largest distance between two sets of positions, as a fraction of the diagonal."""
    return np.abs(np.asarray(A, np.float64) - B).max() / size


def rest_pose(rig):
    for bone in rig.pose.bones:
        bone.location, bone.rotation_quaternion, bone.scale = (0, 0, 0), (1, 0, 0, 0), (1, 1, 1)
    view_layer.update()


rig = armature()
head = rig.pose.bones["Head"]
view_layer.update()

# Assigning binds: the armature object first (no bone), then its bone; the list and the panel.
top.controller = rig
assert top.bone == "" and handles.notice(obj, top, scene) == ("", False)
assert np.allclose(
    Matrix(top.bind_matrix), obj.matrix_world.inverted() @ rig.matrix_world, atol=1e-6
)
top.bone = "Head"
bind = obj.matrix_world.inverted() @ bone_world(rig, "Head")
assert np.allclose(Matrix(top.bind_matrix), bind, atol=1e-6), "choosing a bone did not bind to it"
assert np.abs(np.array(transforms()[0]) - np.eye(4)).max() < 1e-6
# Another controller without that bone clears it; back to the armature, the bone chosen again.
top.controller = empty
assert top.bone == "" and np.allclose(
    Matrix(top.bind_matrix), obj.matrix_world.inverted() @ empty.matrix_world, atol=1e-6
)
top.controller, top.bone = rig, "Head"

# The bone posed (and its parent): Solve and Pose give the shape an Empty moved by the same world
# transform gives.
rig.pose.bones["Root"].rotation_quaternion = Quaternion((0.0, 1.0, 0.0), 0.15)
head.rotation_quaternion = Quaternion((1.0, 0.3, 0.0), 0.4)
head.location = (0.05, 0.1, -0.02)
world_before = bone_world(rig, "Head")
view_layer.update()
motion = bone_world(rig, "Head") @ world_before.inverted()
by_bone = transforms()
solved_bone, posed_bone, refined_bone = solve(), pose_positions(), refine()
assert away(solved_bone, V) > 0.05, "the posed bone did not move the mesh"
assert away(posed_bone, solved_bone) < 1e-6, away(posed_bone, solved_bone)
top.controller = empty
empty.matrix_world = motion @ empty.matrix_world
view_layer.update()
by_empty = transforms()
assert np.abs(np.array(by_bone) - np.array(by_empty)).max() < 1e-5, (by_bone, by_empty)
solved_empty, posed_empty, refined_empty = solve(), pose_positions(), refine()
print(
    f"bone against Empty: transforms {np.abs(np.array(by_bone) - np.array(by_empty)).max():.1e}, "
    f"Solve {away(solved_bone, solved_empty):.1e}, Pose {away(posed_bone, posed_empty):.1e}, "
    f"Refine {away(refined_bone, refined_empty):.1e} of the diagonal"
)
assert away(solved_bone, solved_empty) < 1e-6 and away(posed_bone, posed_empty) < 1e-6
assert away(refined_bone, solved_bone) > 1e-5 and away(refined_bone, refined_empty) < 1e-6
# Reset Pose puts the bone back where it was bound (its armature stays), and the Empty too.
top.controller, top.bone = rig, "Head"  # binds the bone where it is now
moved_to = bone_world(rig, "Head")
head.rotation_quaternion = Quaternion((0.0, 0.0, 1.0), 0.5)
rig_matrix = rig.matrix_world.copy()
view_layer.update()
assert bpy.ops.modal_deform.reset() == {"FINISHED"}
view_layer.update()
assert np.allclose(bone_world(rig, "Head"), moved_to, atol=1e-5) and rig.matrix_world == rig_matrix
assert obj.data.shape_keys is None or posing.POSE_KEY not in obj.data.shape_keys.key_blocks

# Moving the armature object together with the mesh deforms nothing: both moved, then the mesh
# parented to the armature (object parent) and the armature moved.
rest_pose(rig)
top.bone = ""
top.bone = "Head"  # bound at the bone's rest
together = Matrix.Translation((1.0, -2.0, 0.5)) @ Matrix.Rotation(0.8, 4, "Z")
rig.matrix_world = together @ rig.matrix_world
obj.matrix_world = together @ obj.matrix_world
view_layer.update()
assert all(np.abs(np.array(t) - np.eye(4)).max() < 1e-5 for t in transforms()), transforms()
assert away(solve(), V) < 1e-6, away(solve(), V)
obj.parent = rig
obj.matrix_parent_inverse = rig.matrix_world.inverted()
rig.matrix_world = Matrix.Rotation(-0.6, 4, "X") @ rig.matrix_world
rig.location.z += 1.0
view_layer.update()
assert all(np.abs(np.array(t) - np.eye(4)).max() < 1e-5 for t in transforms()), transforms()
assert away(solve(), V) < 1e-6
# With the armature active (Pose Mode) the sidebar and the operators stay with the mesh it parents.
assert handles.owner(rig) == obj
obj.parent = None
view_layer.update()
assert handles.owner(rig) is None
top.bone = ""
top.bone = "Head"
mesh_io = handles.mesh_io
mesh_io.remove_shape_keys(obj, [posing.POSE_KEY])

# Keyframes on the bone drive Bake Animation and Dynamics as an Empty that follows the bone does
# (Copy Transforms), and only the curves that move the bone are the handle's.
follower = bpy.data.objects.new("Follower", None)
scene.collection.objects.link(follower)
copy = follower.constraints.new("COPY_TRANSFORMS")
copy.target, copy.subtarget = rig, "Head"
scene.frame_set(1)
head.keyframe_insert("rotation_quaternion", frame=1)
head.keyframe_insert("location", frame=1)
rig.pose.bones["Other"].keyframe_insert("location", frame=1)
head.rotation_quaternion = Quaternion((1.0, 0.0, 0.0), 0.6)
head.location = (0.0, 0.15, 0.0)
head.keyframe_insert("rotation_quaternion", frame=6)
head.keyframe_insert("location", frame=6)
scene.frame_set(1)
paths = [path for path, _ in frame_cache.controller_curves(obj)]
assert paths and all('pose.bones["Head"]' in path for path in paths), paths


def run_cache(controller, bone, dynamic, last=16):
    """Bake Animation of frames 1 to `last` with the handle on `controller` (and `bone`), bound at
    frame 1; the cache's q rows."""
    scene.frame_set(1)
    top.controller = controller
    top.bone = bone
    obj.modal_deform.dynamics.enabled = dynamic
    assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=last) == {"FINISHED"}
    return frame_cache.get(obj).array("q").copy()


basis_vectors = obj.modal_deform.status.dimension
for dynamic in (False, True):
    q_bone = run_cache(rig, "Head", dynamic)
    q_empty = run_cache(follower, "", dynamic)
    U = timeline.player(obj, scene).basis.vectors
    error = max(away(U @ a, U @ b) for a, b in zip(q_bone, q_empty))
    moved = max(away(U @ a, np.zeros(3 * len(V))) for a in q_bone)
    print(
        f"{'Dynamics' if dynamic else 'Bake Animation'}: bone against Empty {error:.1e} of the diagonal, moved {moved:.3f}"
    )
    assert moved > 0.03 and error < 1e-5, (moved, error)

# Dynamics on the bone: a changed keyframe of another bone keeps the cache; of the bone or its
# parent, cuts it; the armature object moved (not keyed) cuts it at the frame shown.
q_bone = run_cache(rig, "Head", True)
cache = frame_cache.get(obj)
scene.frame_set(16)
assert cache.end == 16
other = rig.pose.bones["Other"]
other.location = (0.0, 0.0, 0.4)
other.keyframe_insert("location", frame=8)
scene.frame_set(16)
assert frame_cache.get(obj).end == 16, "a keyframe of another bone cut the cache"
curve = next(
    c
    for c in frame_keys.action_fcurves(rig.animation_data)
    if c.data_path == 'pose.bones["Head"].location' and c.array_index == 1
)
curve.keyframe_points[1].co.y = 0.25
curve.update()
scene.frame_set(16)
cache = frame_cache.get(obj)
assert cache.end == 16 and not np.array_equal(cache.array("q"), q_bone), (
    "the bone's keyframe changed nothing"
)
assert cache.array("q")[0].tobytes() == q_bone[0].tobytes()
q_now = cache.array("q").copy()
rig.pose.bones["Root"].rotation_quaternion = Quaternion((0.0, 0.0, 1.0), 0.2)
rig.pose.bones["Root"].keyframe_insert("rotation_quaternion", frame=10)
scene.frame_set(9)
assert frame_cache.get(obj).end <= 9, "a keyframe of the bone's parent kept the cache"
scene.frame_set(16)
assert not np.array_equal(frame_cache.get(obj).array("q")[12], q_now[12])
rig.location.x += 0.3
scene.frame_set(12)
assert frame_cache.get(obj).end == 12 and not np.array_equal(
    frame_cache.get(obj).array("q")[11], q_now[11]
), "the armature moved and the frame shown kept"
rig.location.x -= 0.3
timeline.free(obj)
obj.modal_deform.dynamics.enabled = False
scene.frame_set(1)

# Bad input: nothing of the artist's changes.
before = support.mesh_state(obj)


def artist_keys():
    return [
        (c.data_path, c.array_index, tuple(tuple(p.co) for p in c.keyframe_points))
        for c in frame_keys.action_fcurves(rig.animation_data)
    ]


keys = artist_keys()
# The armature that skins the mesh, chosen as a whole (without a bone): refused.
skin = obj.modifiers.new("Armature", "ARMATURE")
skin.object = rig
top.bone = ""
text, is_error = handles.notice(obj, top, scene)
assert is_error and "skins" in text and "choose one of its bones" in text, text
support.expect_error(bpy.ops.modal_deform.solve, "armature 'Rig' skins 'Suzanne' (Armature)")
top.bone = "Head"
assert handles.notice(obj, top, scene) == ("", False)
obj.modifiers.remove(skin)
# The bone renamed, then deleted: refused, by the operators and by playback.
view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
rig.data.edit_bones["Head"].name = "Skull"
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj
message = "bone 'Head' is not in armature 'Rig' (deleted or renamed?)"
text, is_error = handles.notice(obj, top, scene)
assert is_error and message[1:] in text, text  # the panel's sentence starts with a capital
support.expect_error(bpy.ops.modal_deform.solve, message)
support.expect_error(bpy.ops.modal_deform.bake_animation, message, frame_start=1, frame_end=3)
obj.modal_deform.dynamics.enabled = True
scene.frame_set(2)
assert message in timeline.problems.get(obj.name, ""), timeline.problems
obj.modal_deform.dynamics.enabled = False
timeline.free(obj)
# Blender renames the bone's curves with it; the keyframes are the artist's as they were.
assert [(p.replace("Skull", "Head"), i, k) for p, i, k in artist_keys()] == keys
# Named back, the handle works again with its bind as it was; the bone chosen anew binds again.
bound = Matrix(top.bind_matrix)


def rename_bone(old, new):
    view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    rig.data.edit_bones[old].name = new
    bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = obj


rename_bone("Skull", "Head")
assert handles.notice(obj, top, scene) == ("", False) and Matrix(top.bind_matrix) == bound
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
rename_bone("Head", "Skull")
top.bone = "Skull"
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
mesh_io.remove_shape_keys(obj, [posing.POSE_KEY])
view_layer.objects.active = rig
bpy.ops.object.mode_set(mode="EDIT")
rig.data.edit_bones.remove(rig.data.edit_bones["Skull"])
bpy.ops.object.mode_set(mode="OBJECT")
view_layer.objects.active = obj
support.expect_error(bpy.ops.modal_deform.solve, "bone 'Skull' is not in armature 'Rig'")
assert support.mesh_state(obj) == before, "a refused handle changed the mesh"

# A scaled and sheared bone: the nearest rigid transform (the rotation of its polar decomposition,
# the handle's centre where the bone takes it).
top.bone = "Other"
other = rig.pose.bones["Other"]
rig.animation_data.action = None  # the pose set by hand stays
other.scale = (1.5, 1.0, 0.7)
other.rotation_quaternion = Quaternion((0.0, 0.0, 1.0), 0.3)
rig.scale = (1.0, 2.0, 1.0)  # with the bone's turn: a shear in the world
view_layer.update()
(resolved, _) = handles.resolve(obj, scene, V)
relative = (
    obj.matrix_world.inverted() @ bone_world(rig, "Other") @ Matrix(top.bind_matrix).inverted()
)
expected = mdc.nearest_rigid(np.array(relative), resolved[0].centre)
got = handles.transforms(obj, resolved)[0]
assert np.array_equal(got, expected) and np.allclose(got[:3, :3] @ got[:3, :3].T, np.eye(3))
assert bpy.ops.modal_deform.solve() == {"FINISHED"}

# The armature unlinked from the scene (deleted while still used): refused; removed for good: the
# handle is pinned, with a warning and a note in the panel.
view_layer.objects.active = rig
bpy.ops.object.select_all(action="DESELECT")
rig.select_set(True)
bpy.ops.object.delete()
view_layer.objects.active = obj
support.expect_error(bpy.ops.modal_deform.solve, "controller 'Rig' is not in the scene (deleted?)")
assert handles.notice(obj, top, scene)[1]
bpy.data.objects.remove(rig)
assert top.controller is None
assert handles.notice(obj, top, scene) == ("Controller 'Rig' is gone: the handle is pinned", False)
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
print("bone controllers: all checks passed")
