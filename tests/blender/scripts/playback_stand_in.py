"""While the timeline plays (Blender 4+), playback's display reads a stand-in (playback/frame_display.py):
the same frames bit for bit, the artist's mesh and shape keys untouched; it goes when playback stops,
before a file is saved, in Edit Mode and when the artist changes the mesh, and a file written
mid-playback, or an undo step, loads without it, showing the same frame."""

import sys

import bpy
import numpy as np
from support import blender as support

if not hasattr(bpy.app.handlers, "animation_playback_pre"):
    print("STAND_IN_UNSUPPORTED")
    sys.exit(0)

frame_cache, timeline, frame_display = support.enable_addon(
    "playback.frame_cache", "playback.timeline", "playback.frame_display"
)
obj, V, controller = support.keyed_suzanne(8, 12, 10, 300)
# Shape keys of the artist's (at rest, as a bake needs): the stand-in has none, the artist keeps them.
obj.shape_key_add(name="Basis")
smile = obj.shape_key_add(name="Smile")
smile.data[0].co.z += 0.2
obj.modal_deform.dynamics.enabled = True
scene = bpy.context.scene
scene.frame_start, scene.frame_end = 1, 8
scene.frame_set(1)


def playback_handler(name):
    """Call the add-on's handler that Blender calls when the timeline starts or stops playing."""
    handler = next(
        h for h in getattr(bpy.app.handlers, name) if h.__module__.endswith(".playback.timeline")
    )
    handler(scene, bpy.context.evaluated_depsgraph_get())


def frame(number):
    """The cached frame's positions x̄ + U q."""
    out = np.empty_like(V)
    timeline.player(obj, scene).positions(frame_cache.get(obj).state(number)[0], out)
    return out


def stand_ins():
    return [
        b.name
        for c in (bpy.data.objects, bpy.data.meshes, bpy.data.node_groups)
        for b in c
        if b.get(frame_display.STAND_IN)
    ]


def untouched():
    assert np.array_equal(support.positions(obj), V), "the artist's positions changed"
    assert np.array_equal(support.key_positions(obj, "Basis"), V), "the artist's Basis key changed"
    assert support.key_positions(obj, "Smile")[0, 2] == V[0, 2] + np.float32(0.2), (
        "the artist's key changed"
    )


# Frames simulated and read while playing show what the attribute shows, through the stand-in.
scene.frame_set(4)
timeline.set_frame(scene, 1)
frame_cache.get(obj).cut(2)
playback_handler("animation_playback_pre")
for number in (2, 3, 4, 5, 2, 3):
    scene.frame_set(number)
    assert frame_display.has_stand_in(obj), f"frame {number}: no stand-in while playing"
    assert support.evaluated_positions(obj).tobytes() == frame(number).tobytes(), (
        f"frame {number} differs"
    )
assert len(stand_ins()) == 3, stand_ins()
stand_in = next(o for o in bpy.data.objects if o.get(frame_display.STAND_IN))
assert stand_in.data.shape_keys is None and stand_in.users_scene == (), (
    "the stand-in is drawn or has keys"
)
untouched()

# The stand-in deleted by the artist (the Outliner's Blender File view shows it): the next frame has a new one.
bpy.data.objects.remove(stand_in)
scene.frame_set(2)
assert frame_display.has_stand_in(obj) and len(stand_ins()) == 3, stand_ins()
assert support.evaluated_positions(obj).tobytes() == frame(2).tobytes(), (
    "a deleted stand-in hides the frame"
)
scene.frame_set(3)

# Saving: the file holds the mesh once; the next frame played has the stand-in again.
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("saved.blend"), copy=True)
assert not stand_ins() and not frame_display.has_stand_in(obj)
assert support.evaluated_positions(obj).tobytes() == frame(3).tobytes(), (
    "saving changed the frame shown"
)
scene.frame_set(4)
assert frame_display.has_stand_in(obj)

# Edit Mode shows the mesh itself, and ends the stand-in; back in Object Mode it returns.
bpy.context.view_layer.objects.active = obj
bpy.ops.object.mode_set(mode="EDIT")
scene.frame_set(5)
assert not stand_ins(), "a stand-in in Edit Mode"
bpy.ops.object.mode_set(mode="OBJECT")
scene.frame_set(6)
assert frame_display.has_stand_in(obj)
assert support.evaluated_positions(obj).tobytes() == frame(6).tobytes()

# A change of the artist's mesh (a painted attribute) ends the stand-in: the change shows.
paint = obj.data.attributes.new("paint", "FLOAT_COLOR", "POINT")
paint.data[0].color = (1.0, 0.0, 0.0, 1.0)
obj.data.update()
bpy.context.view_layer.update()
assert not stand_ins(), "the artist's change hides behind the stand-in"
evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
assert tuple(evaluated.attributes["paint"].data[0].color) == (1.0, 0.0, 0.0, 1.0)
assert support.evaluated_positions(obj).tobytes() == frame(6).tobytes()

# A modifier the artist puts before the display's acts on the mesh the frame is set on: no stand-in then
# (it would replace that modifier's result), and again once the modifier goes.
solidify = obj.modifiers.new("Artist's Solidify", "SOLIDIFY")
bpy.ops.object.modifier_move_to_index(modifier=solidify.name, index=0)
scene.frame_set(7)
assert not stand_ins() and len(support.evaluated_positions(obj)) == 2 * len(V), (
    "the stand-in hides a modifier"
)
obj.modifiers.remove(solidify)
scene.frame_set(6)
assert frame_display.has_stand_in(obj)
assert support.evaluated_positions(obj).tobytes() == frame(6).tobytes()

# Stopping: the stand-in goes (the object renamed meanwhile), the attribute holds the frame last shown.
scene.frame_set(7)
assert frame_display.has_stand_in(obj)
obj.name = "Renamed Suzanne"
playback_handler("animation_playback_post")
assert not stand_ins() and support.evaluated_positions(obj).tobytes() == frame(7).tobytes()
assert frame_display.modifier_of(obj).node_group.name == frame_display.NODE_GROUP
scene.frame_set(8)
assert not stand_ins(), "a stand-in with the timeline still"
untouched()

# Undone to a step written mid-playback, with the timeline still: no stand-in, that step's frame
# shows, and the next frame plays (the objects undo read back are not the ones before it).
playback_handler("animation_playback_pre")
scene.frame_set(4)
bpy.ops.ed.undo_push(message="mid-playback")
scene.frame_set(5)
bpy.ops.ed.undo_push(message="later")
playback_handler("animation_playback_post")
name = obj.name
assert bpy.ops.ed.undo() == {"FINISHED"}
obj, scene = bpy.data.objects[name], bpy.context.scene
assert scene.frame_current == 4 and not stand_ins(), stand_ins()
assert support.evaluated_positions(obj).tobytes() == frame(4).tobytes(), (
    "the undo step's frame does not show"
)
scene.frame_set(6)
assert support.evaluated_positions(obj).tobytes() == frame(6).tobytes(), (
    "no frame plays after an undo"
)

# Free mid-playback takes the display away, stand-in and all.
playback_handler("animation_playback_pre")
scene.frame_set(5)
assert frame_display.has_stand_in(obj)
bpy.context.view_layer.objects.active = obj
assert bpy.ops.modal_deform.free_cache() == {"FINISHED"}
assert not stand_ins() and not frame_display.shows(obj), stand_ins()
playback_handler("animation_playback_post")

# A file written mid-playback without save_pre (a crash's autosave) holds the stand-in; loaded, it
# shows the same frame through the attribute, with no stand-in left.
playback_handler("animation_playback_pre")
scene.frame_set(5)
shown = support.evaluated_positions(obj)
saving = next(h for h in bpy.app.handlers.save_pre if h.__module__.endswith(".playback.timeline"))
bpy.app.handlers.save_pre.remove(saving)
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("autosaved.blend"), copy=True)
bpy.app.handlers.save_pre.append(saving)
bpy.ops.wm.open_mainfile(filepath=support.tmp("autosaved.blend"))
obj = bpy.data.objects[name]
assert not stand_ins() and not frame_display.has_stand_in(obj), stand_ins()
assert support.evaluated_positions(obj).tobytes() == shown.tobytes(), (
    "the loaded file shows another frame"
)
assert np.array_equal(support.positions(obj), V)
