"""Where the interactive pose shows the pose, and what it leaves behind: a mesh without shape keys
is posed in its vertex positions (Blender blends no keys), kept into the "Modal Deform" key with
the rest restored bit for bit, and looks the same through its modifiers either way; a shape key
added mid-pose (a copy of the posed positions) gets the rest as its reference; a mesh with
the artist's shape keys is posed in the key and gets them back untouched; a mesh written mid-pose
by a path without save handlers (an undo step of a controller's move, autosave, a crash file) is
repaired after undo and after loading: rest from the stored basis, pose into the key."""

import bpy
import numpy as np
from mathutils import Matrix
from support import blender as support
from support.blender import evaluated_positions

posing, displays, storage = support.enable_addon("pose.posing", "pose.displays", "storage")

obj, rest = support.baked_suzanne(1, 12, 10, 300)
support.top_and_bottom_handles(obj, rest)
controller = obj.modal_deform.handles[0].controller
controller.matrix_world = Matrix.Translation((0.3, 0.0, 0.2)) @ controller.matrix_world
obj.modifiers.new("Subdivision", "SUBSURF").levels = 1
bpy.context.view_layer.objects.active = obj
bpy.context.view_layer.update()


def pose_shown(shown):
    """A pose solved and written where `shown` shows it, as the operator's ticks do; returns it."""
    pose = posing.Pose(bpy.context, obj)
    pose.follow_controllers()
    pose.converge()
    pose.write(shown.array())
    return pose


def keep_as_shown(shown, pose):
    """shown.keep(pose), checked to look the same through the modifiers as the pose shown did."""
    bpy.context.view_layer.update()
    shown_through_modifiers = evaluated_positions(obj)
    kept = shown.keep(pose)
    bpy.context.view_layer.update()
    difference = np.abs(evaluated_positions(obj) - shown_through_modifiers).max()
    assert difference < 1e-5, f"the kept pose looks different through the modifiers ({difference})"
    return kept


def undone_to_mid_pose(display):
    """A pose shown by a new display (of type `display`), an undo step pushed mid-pose (a
    controller's move pushes one), the pose kept, then undone to that step; returns the object as
    undo read it again and the pose."""
    bpy.ops.ed.undo_push(message="before posing")
    shown = displays.display(obj)
    assert type(shown) is display
    pose = pose_shown(shown)
    posed = support.positions(obj)
    bpy.ops.ed.undo_push(message="controller moved while posing")
    shown.keep(pose)
    bpy.ops.ed.undo_push(message="pose kept")
    assert bpy.ops.ed.undo() == {"FINISHED"}
    return bpy.data.objects["Suzanne"], posed


def artists_key(value):
    """The artist's own shape key "Smile" (one vertex raised), at `value`."""
    smile = obj.shape_key_add(name="Smile")
    smile.data[0].co.z += 0.1
    smile.value = value
    return smile


# No shape keys: posed in the vertex positions, the mesh flagged meanwhile; Esc restores exactly.
shown = displays.display(obj)
assert type(shown) is displays.PositionsDisplay
pose_shown(shown)
assert obj.data.shape_keys is None and obj.data.get(displays.POSING_FLAG)
assert np.abs(support.positions(obj) - rest).max() > 0.05, "the pose is not in the vertex positions"
shown.restore()
assert (
    support.positions(obj).tobytes() == rest.tobytes()
    and obj.data.get(displays.POSING_FLAG) is None
)

# Kept: the rest back in the base mesh and in "Basis", the pose in the key, the same through the
# modifiers as it was shown.
shown = displays.display(obj)
pose = pose_shown(shown)
posed = support.positions(obj)
shown = keep_as_shown(shown, pose)
assert type(shown) is displays.ShapeKeyDisplay
assert support.positions(obj).tobytes() == rest.tobytes()
assert support.key_positions(obj, "Basis").tobytes() == rest.tobytes()
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
assert obj.data.get(displays.POSING_FLAG) is None

# The artist adds a shape key mid-pose: the first one copies the positions, which hold the pose;
# kept, the reference key holds the rest again.
obj.shape_key_clear()
shown = displays.display(obj)
pose = pose_shown(shown)
posed = support.positions(obj)
obj.shape_key_add(name="Basis")
assert not shown.shows_pose()
shown = shown.keep(pose)
assert support.positions(obj).tobytes() == rest.tobytes()
assert support.key_positions(obj, "Basis").tobytes() == rest.tobytes()
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()

# The artist's own shape key: posed in the key, the artist's key and the mesh as they were after Esc.
obj.shape_key_clear()
obj.shape_key_add(name="Basis")
artists_key(0.5)
before = support.mesh_state(obj)
shown = displays.display(obj)
assert type(shown) is displays.ShapeKeyDisplay
pose_shown(shown)
assert support.positions(obj).tobytes() == rest.tobytes()
shown.restore()
assert support.mesh_state(obj) == before, "the artist's shape keys changed"
obj.shape_key_clear()

# An undo step taken mid-pose (a controller's move pushes one) holds the pose in the positions:
# undoing to it after the pose was kept repairs it.
obj, posed = undone_to_mid_pose(displays.PositionsDisplay)
assert obj.data.get(displays.POSING_FLAG) is None, "undo left a posed mesh"
assert support.positions(obj).tobytes() == rest.tobytes(), "undo left the pose in the base mesh"
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
obj.shape_key_clear()

# A file written mid-pose without save handlers (autosave, a crash file; here a plain save with no
# interactive pose running to move the pose first): loading it repairs the mesh.
shown = displays.display(obj)
pose_shown(shown)
posed = support.positions(obj)
path = support.tmp("saved_mid_pose.blend")
bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)
shown.restore()
bpy.ops.wm.open_mainfile(filepath=path)
obj = bpy.data.objects["Suzanne"]
assert obj.data.get(displays.POSING_FLAG) is None
assert support.positions(obj).tobytes() == rest.tobytes(), "loading left the pose in the base mesh"
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
assert storage.stale_reason(obj) == "", "the repaired mesh does not fit its basis"

# A mesh posed and kept before (here just repaired: "Basis" and "Modal Deform"), with an artist's
# key at 0: posed in a stand-in without shape keys, the artist's mesh untouched; Esc puts it back.
mesh = obj.data
controller = obj.modal_deform.handles[0].controller
smile = artists_key(0.0)
before = support.mesh_state(obj)
shown = displays.display(obj)
assert type(shown) is displays.StandInDisplay
assert (
    obj.data != mesh and obj.data.shape_keys is None and obj.data.get(displays.STAND_IN_OF) == mesh
)
controller.matrix_world = Matrix.Translation((0.0, 0.2, 0.0)) @ controller.matrix_world
bpy.context.view_layer.update()
pose = pose_shown(shown)
assert support.mesh_state(obj) != before
shown.restore()
assert obj.data == mesh and support.mesh_state(obj) == before, (
    "Esc did not put the artist's mesh back"
)
assert not [m for m in bpy.data.meshes if m.get(displays.STAND_IN_OF)], (
    "the stand-in is left behind"
)

# Kept: the pose in the key, the artist's keys and the rest as they were, the same through the
# modifiers as it was shown.
shown = displays.display(obj)
pose = pose_shown(shown)
posed = support.positions(obj)
shown = keep_as_shown(shown, pose)
assert type(shown) is displays.ShapeKeyDisplay and obj.data == mesh
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
for name in ("Basis", "Smile"):
    assert (
        support.key_positions(obj, name).tobytes()
        == dict((n, c) for n, _, _, c in before["shape_keys"])[name]
    ), f"keeping the pose changed '{name}'"

# The artist's key shown (at 0.5): posed in the key, as before.
smile.value = 0.5
shown = displays.display(obj)
assert type(shown) is displays.ShapeKeyDisplay
shown.restore()
smile.value = 0.0

# Mid-pose, the artist's key starts to show (an animated value): the pose goes on in the key. A
# key added to the stand-in is carried over to the mesh as the same offset from its reference.
shown = displays.display(obj)
pose = pose_shown(shown)
smile.value = 0.3
assert not shown.shows_pose()
smile.value = 0.0
assert shown.shows_pose()
obj.shape_key_add(name="Basis")
frown = obj.shape_key_add(name="Frown")
frown.data[0].co.x += 0.2
frown.value = 0.7
assert not shown.shows_pose()
shown = shown.keep(pose)
assert obj.data == mesh and obj.data.shape_keys.key_blocks["Frown"].value == np.float32(0.7)
offset = support.key_positions(obj, "Frown") - support.key_positions(obj, "Basis")
expected = np.zeros_like(offset)
expected[0, 0] = 0.2
assert np.abs(offset - expected).max() < 1e-5, "the key added mid-pose was not carried over"
obj.shape_key_remove(obj.data.shape_keys.key_blocks["Frown"])

# An undo step and a file written mid-pose hold the stand-in on the object: the artist's mesh comes
# back on undo and on loading, with the pose in the key.
obj, posed = undone_to_mid_pose(displays.StandInDisplay)
assert obj.data.name == "Suzanne" and obj.data.get(displays.STAND_IN_OF) is None, (
    "undo left the stand-in"
)
assert not [m for m in bpy.data.meshes if m.get(displays.STAND_IN_OF)]
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
shown = displays.display(obj)
pose_shown(shown)
posed = support.positions(obj)
bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)
shown.restore()
bpy.ops.wm.open_mainfile(filepath=path)
obj = bpy.data.objects["Suzanne"]
assert obj.data.name == "Suzanne" and not [
    m for m in bpy.data.meshes if m.get(displays.STAND_IN_OF)
]
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
assert support.positions(obj).tobytes() == rest.tobytes()
assert storage.stale_reason(obj) == "", "the mesh put back does not fit its basis"
