"""Where the interactive pose shows the pose, and what it leaves behind: a mesh without shape keys
is posed in its vertex positions (Blender blends no keys), kept into the "Modal Deform" key with
the rest restored bit for bit, and looks the same through its modifiers either way; a shape key
added mid-pose (a copy of the posed positions) gets the rest as its reference; a mesh with
the artist's shape keys is posed in the key and gets them back untouched; a mesh written mid-pose
by a path without save handlers (an undo step of a controller's move, autosave, a crash file) is
repaired after undo and after loading: rest from the stored basis, pose into the key."""
import os
import sys

sys.path.insert(0, os.path.dirname(__file__))
import bpy  # noqa: E402
import numpy as np  # noqa: E402
from mathutils import Matrix  # noqa: E402
import support  # noqa: E402
from headless import evaluated_positions  # noqa: E402

posing, storage = support.enable_addon("posing", "storage")

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


# No shape keys: posed in the vertex positions, the mesh flagged meanwhile; Esc restores exactly.
shown = posing.display(obj)
assert type(shown) is posing.PositionsDisplay
pose_shown(shown)
assert obj.data.shape_keys is None and obj.data.get(posing.POSING_FLAG)
assert np.abs(support.positions(obj) - rest).max() > 0.05, "the pose is not in the vertex positions"
shown.restore()
assert support.positions(obj).tobytes() == rest.tobytes() and obj.data.get(posing.POSING_FLAG) is None

# Kept: the rest back in the base mesh and in "Basis", the pose in the key, the same through the
# modifiers as it was shown.
shown = posing.display(obj)
pose = pose_shown(shown)
posed = support.positions(obj)
bpy.context.view_layer.update()
shown_through_modifiers = evaluated_positions(obj)
shown = shown.keep(pose)
assert type(shown) is posing.ShapeKeyDisplay
assert support.positions(obj).tobytes() == rest.tobytes()
assert support.key_positions(obj, "Basis").tobytes() == rest.tobytes()
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
assert obj.data.get(posing.POSING_FLAG) is None
bpy.context.view_layer.update()
difference = np.abs(evaluated_positions(obj) - shown_through_modifiers).max()
assert difference < 1e-5, f"the kept pose looks different through the modifiers ({difference})"

# The artist adds a shape key mid-pose: the first one copies the positions, which hold the pose;
# kept, the reference key holds the rest again.
obj.shape_key_clear()
shown = posing.display(obj)
pose = pose_shown(shown)
posed = support.positions(obj)
obj.shape_key_add(name="Basis")
assert not shown.shows_pose()
shown = shown.keep(pose)
assert support.positions(obj).tobytes() == rest.tobytes()
assert support.key_positions(obj, "Basis").tobytes() == rest.tobytes()
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
print("POSITIONS_OK")

# The artist's own shape key: posed in the key, the artist's key and the mesh as they were after Esc.
obj.shape_key_clear()
obj.shape_key_add(name="Basis")
smile = obj.shape_key_add(name="Smile")
smile.data[0].co.z += 0.1
smile.value = 0.5
before = support.mesh_state(obj)
shown = posing.display(obj)
assert type(shown) is posing.ShapeKeyDisplay
pose_shown(shown)
assert support.positions(obj).tobytes() == rest.tobytes()
shown.restore()
assert support.mesh_state(obj) == before, "the artist's shape keys changed"
obj.shape_key_clear()
print("SHAPE_KEYS_OK")

# An undo step taken mid-pose (a controller's move pushes one) holds the pose in the positions:
# undoing to it after the pose was kept repairs it.
bpy.ops.ed.undo_push(message="before posing")
shown = posing.display(obj)
pose = pose_shown(shown)
posed = support.positions(obj)
bpy.ops.ed.undo_push(message="controller moved while posing")
shown.keep(pose)
bpy.ops.ed.undo_push(message="pose kept")
assert bpy.ops.ed.undo() == {"FINISHED"}
obj = bpy.data.objects["Suzanne"]  # undo re-reads the data
assert obj.data.get(posing.POSING_FLAG) is None, "undo left a posed mesh"
assert support.positions(obj).tobytes() == rest.tobytes(), "undo left the pose in the base mesh"
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
obj.shape_key_clear()
print("UNDO_OK")

# A file written mid-pose without save handlers (autosave, a crash file; here a plain save with no
# interactive pose running to move the pose first): loading it repairs the mesh.
shown = posing.display(obj)
pose_shown(shown)
posed = support.positions(obj)
path = support.tmp("saved_mid_pose.blend")
bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)
shown.restore()
bpy.ops.wm.open_mainfile(filepath=path)
obj = bpy.data.objects["Suzanne"]
assert obj.data.get(posing.POSING_FLAG) is None
assert support.positions(obj).tobytes() == rest.tobytes(), "loading left the pose in the base mesh"
assert support.key_positions(obj, posing.POSE_KEY).tobytes() == posed.tobytes()
assert storage.stale_reason(obj) == "", "the repaired mesh does not fit its basis"
print("LOAD_OK")
