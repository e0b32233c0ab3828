"""How playback shows a frame (playback/frame_display.py): the frame x̄ + U q through a Geometry Nodes
modifier first in the stack (the artist's modifiers act on it), the artist's positions and shape keys
untouched, the rest in Edit Mode; a copy of the mesh is not written through; without the attribute
the mesh shows its rest; a pose (Solve, the interactive pose) takes the display away, as do dynamics
turned off, a cache that no longer fits and disabling the add-on."""

import addon_utils
import bpy
import numpy as np
from mathutils import Matrix
from support import blender as support

package = support.enable_addon()
frame_cache, mesh_io, timeline, frame_display, displays, posing = support.enable_addon(
    "playback.frame_cache",
    "mesh_io",
    "playback.timeline",
    "playback.frame_display",
    "pose.displays",
    "pose.posing",
)
obj, V, controller = support.keyed_suzanne(8, 12, 10, 300)
artist = obj.modifiers.new("Artist's Displace", "DISPLACE")
scene = bpy.context.scene
assert bpy.ops.modal_deform.bake_animation(frame_start=1, frame_end=8) == {"FINISHED"}


def frame(number):
    """The cached frame's positions x̄ + U q."""
    out = np.empty_like(V)
    timeline.player(obj, scene).positions(frame_cache.get(obj).state(number)[0], out)
    return out


def shown():
    return support.evaluated_positions(obj)


def attribute(mesh):
    return mesh_io.attribute_co(mesh, mesh.attributes[frame_display.ATTRIBUTE])


# The frame, before the artist's modifier (which then moves it by its strength along the normals).
scene.frame_set(6)
assert [m.name for m in obj.modifiers] == [frame_display.MODIFIER, artist.name], list(obj.modifiers)
modifier = obj.modifiers[0]
assert not modifier.show_in_editmode and modifier.node_group.name == frame_display.NODE_GROUP
assert np.abs(shown() - frame(6)).max() > 0.4, "the artist's modifier does not act on the frame"
artist.show_viewport = False
assert shown().tobytes() == frame(6).tobytes(), "the evaluated mesh is not the cached frame"
assert np.abs(frame(6) - V).max() > 0.3, "the controller did not move the mesh"
assert np.array_equal(support.positions(obj), V) and obj.data.shape_keys is None, (
    "the artist's mesh changed"
)

# One node group per file, reused by every object that plays.
other = bpy.data.objects.new("Second Suzanne", obj.data.copy())
scene.collection.objects.link(other)
frame_display.positions(other)[...] = V
assert (
    other.modifiers[0].node_group == modifier.node_group
    and len([g for g in bpy.data.node_groups if g.name.startswith(frame_display.NODE_GROUP)]) == 1
)
bpy.data.objects.remove(other)
# Renamed by the artist, the modifier and its group are still the display's (no second one).
modifier.name, modifier.node_group.name = "Renamed", "Renamed too"
scene.frame_set(5)
assert len(obj.modifiers) == 2 and shown().tobytes() == frame(5).tobytes()

# A copy of the mesh (Blender 4+ shares the attribute's array with it until written) keeps its values
# when the original's are written.
copy = obj.data.copy()
copied = attribute(copy).copy()
scene.frame_set(3)
assert shown().tobytes() == frame(3).tobytes()
assert attribute(copy).tobytes() == copied.tobytes(), "writing the frame changed a copy"
bpy.data.meshes.remove(copy)

# Edit Mode shows the mesh being edited (the modifier is hidden there).
bpy.context.view_layer.objects.active = obj
bpy.ops.object.mode_set(mode="EDIT")
assert shown().tobytes() == V.tobytes(), "Edit Mode shows the frame"
bpy.ops.object.mode_set(mode="OBJECT")
assert shown().tobytes() == frame(3).tobytes()

# Without the attribute (and in Blender 3.4 its selection), the modifier leaves the positions alone.
for name in (frame_display.ATTRIBUTE, frame_display.SHOWN):
    if name in obj.data.attributes:
        obj.data.attributes.remove(obj.data.attributes[name])
assert shown().tobytes() == V.tobytes(), "the modifier moved the mesh without its attribute"
scene.frame_set(4)
assert shown().tobytes() == frame(4).tobytes()

# A pose in the "Modal Deform" key (Solve) shows instead of the frame; the next frame played shows
# the frame again.
controller.matrix_world = Matrix.Translation((0.0, 0.0, 0.3)) @ controller.matrix_world
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
assert not frame_display.shows(obj)
assert np.abs(shown() - support.key_positions(obj, posing.POSE_KEY)).max() < 1e-6, (
    "the frame hides the solved pose"
)
scene.frame_set(5)
assert shown().tobytes() == frame(5).tobytes()
# The interactive pose's display, likewise (the mesh has shape keys now: the pose shows in the key).
display = displays.display(obj)
assert not frame_display.shows(obj)
display.restore()

# A cache that no longer fits (a vertex moved since the bake): the mesh shows as it is.
scene.frame_set(6)
assert frame_display.shows(obj)
obj.data.vertices[0].co.x += 0.1
obj.data.shape_keys.reference_key.data[0].co.x += 0.1
scene.frame_set(7)
assert timeline.problems.get(obj.name) and not frame_display.shows(obj), timeline.problems
assert np.abs(shown() - support.key_positions(obj, posing.POSE_KEY)).max() < 1e-6
obj.data.vertices[0].co.x -= 0.1
obj.data.shape_keys.reference_key.data[0].co.x -= 0.1

# Dynamics turned on then off: the cache goes (a setting changed), and the frame with it.
scene.frame_set(2)
assert frame_display.shows(obj)
obj.modal_deform.dynamics.enabled = True
obj.modal_deform.dynamics.enabled = False
scene.frame_set(3)
assert frame_cache.get(obj) is None and not frame_display.shows(obj)

# Disabling the add-on takes the display off every object, and the node group with it.
obj.modal_deform.dynamics.enabled = True
scene.frame_set(4)
assert frame_display.shows(obj)
addon_utils.disable(package.__name__, default_set=True)
assert [m.name for m in obj.modifiers] == [
    artist.name
] and frame_display.ATTRIBUTE not in obj.data.attributes
assert not [g for g in bpy.data.node_groups if g.get(frame_display.MARK)]
assert np.abs(shown() - support.key_positions(obj, posing.POSE_KEY)).max() < 1e-6
