"""Blend as Shapes on a bar with a 90° bend key (shapes/): enabling bakes and shows the blend, which
at 0.5 is the core's and not Blender's linear mix; a keyframed value plays, the same bits however
the frame is reached (and through the stand-in while the timeline plays); Keep as Shape Key;
disabling restores the mesh exactly; the file is saved for shapes_reload.py."""

import bpy
import numpy as np
from support import blender as support

mdc, blending, frame_display, timeline = support.enable_addon(
    "core", "shapes.blending", "playback.frame_display", "playback.timeline"
)
from support.shape_keys import bar_with_bend  # noqa: E402

obj, V, F, bend = bar_with_bend()
scene = bpy.context.scene
before = support.mesh_state(obj)


def shown():
    return support.evaluated_positions(obj)


# Enabling bakes (here at once; from the panel on a thread with a progress bar) and shows the blend.
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}
settings = obj.modal_deform.shapes
assert settings.enabled and settings.space is not None and settings.key_names == "Bend"
assert obj.modal_deform.basis is None, "the space baked its own basis: the object had none"
space = blending.load(obj)
block = obj.data.shape_keys.key_blocks["Bend"]
block.value = 0.5
bpy.context.view_layer.update()  # depsgraph_update_post: the value moved in the panel
assert obj.modifiers[0].name == frame_display.MODIFIER
X = shown()
core = mdc.ShapeSpace(V, F, [bend], modes=12, derivatives=20, ghost=300).blend([0.5])
linear = 0.5 * (V + bend)
size = np.ptp(V, axis=0).max()
assert np.abs(X - space.blend([0.5])).max() == 0, "the mesh shows another blend than the space's"
assert np.abs(X - core).max() < 1e-4 * size, np.abs(X - core).max()
assert np.abs(X - linear).max() > 0.05 * size, "the blend at 0.5 is the linear mix"


def length(P):
    """The length of the bar's centre line: mean of its vertices per ring, along the bar."""
    rings = np.round(V[:, 2], 5)
    centres = np.array([P[rings == z].mean(axis=0) for z in np.unique(rings)])
    return np.linalg.norm(np.diff(centres, axis=0), axis=1).sum()


print(f"LENGTH rest {length(V):.4f} blend {length(X):.4f} linear {length(linear):.4f}")
assert abs(length(X) - length(V)) < 0.5 * abs(length(linear) - length(V))

# A keyframed value plays; a frame is the same bits however it is reached.
block.value = 0.0
block.keyframe_insert("value", frame=1)
block.value = 1.0
block.keyframe_insert("value", frame=11)
scene.frame_set(6)
at6 = shown()
w6 = block.value
assert 0.3 < w6 < 0.7 and np.array_equal(at6, space.blend([w6])), w6
scene.frame_set(11)
assert np.abs(shown() - bend).max() < 1e-3 * size, "weight 1 does not show the key"
for start in (1, 10, 6):
    scene.frame_set(start)
    scene.frame_set(6)
    assert shown().tobytes() == at6.tobytes(), f"frame 6 from frame {start} differs"

# Playing (Blender 4+): through the stand-in, the same bits.
playback = [
    h
    for name in ("animation_playback_pre", "animation_playback_post")
    for h in getattr(bpy.app.handlers, name, [])
    if h.__module__.endswith(".playback.timeline")
]
if playback:
    playback[0](scene, bpy.context.evaluated_depsgraph_get())
    scene.frame_set(5)
    scene.frame_set(6)
    assert frame_display.has_stand_in(obj), "no stand-in while playing"
    assert shown().tobytes() == at6.tobytes(), "the stand-in shows another frame 6"
    playback[1](scene, bpy.context.evaluated_depsgraph_get())
    assert not frame_display.has_stand_in(obj)
    assert shown().tobytes() == at6.tobytes()

# A driven value reaches the keys in Blender's evaluation: the blend for it shows after it.
scene["Weight"] = 0.25
fcurve = block.driver_add("value")
fcurve.driver.type = "AVERAGE"
variable = fcurve.driver.variables.new()
variable.targets[0].id_type = "SCENE"
variable.targets[0].id = scene
variable.targets[0].data_path = '["Weight"]'
for weight in (0.25, 0.75, 0.5):
    scene["Weight"] = weight
    scene.update_tag()
    bpy.context.view_layer.update()
    # The driver's value as Blender computes it (in float32 in 5.x: 0.2499999850988388 for 0.25).
    keys = obj.data.shape_keys.evaluated_get(bpy.context.evaluated_depsgraph_get())
    driven = keys.key_blocks["Bend"].value
    assert abs(driven - weight) < 1e-6, (driven, weight)
    assert shown().tobytes() == space.blend([driven]).tobytes(), f"driven to {weight}"
block.driver_remove("value")
scene.frame_set(6)
assert shown().tobytes() == at6.tobytes()

# Keep as Shape Key: the blend shown, a new key at 0 relative to the basis.
assert bpy.ops.modal_deform.keep_blend() == {"FINISHED"}
kept = obj.data.shape_keys.key_blocks["Blended Shape"]
assert kept.value == 0 and kept.relative_key == obj.data.shape_keys.reference_key
assert support.key_positions(obj, kept.name).tobytes() == at6.tobytes()
assert shown().tobytes() == at6.tobytes() and not blending.problems, blending.problems
# A key added after the bake at a weight: refused with a message, Blender's mix shows.
kept.value = 1.0
bpy.context.view_layer.update()
assert "came after the bake" in blending.problems[obj.name], blending.problems
assert not frame_display.shows(obj)
kept.value = 0.0
bpy.context.view_layer.update()
assert shown().tobytes() == at6.tobytes() and obj.name not in blending.problems

# Disabling restores the mesh exactly (the kept key aside); enabling again needs no bake.
bake_id = settings.space["bake_id"]
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"} and not settings.enabled
assert not frame_display.shows(obj) and not any(m.type == "NODES" for m in obj.modifiers)
obj.shape_key_remove(kept)
after = support.mesh_state(obj)
for name in ("co", "polygons", "loops", "vertex_groups"):
    assert after[name] == before[name], name
assert [k[3] for k in after["shape_keys"]] == [k[3] for k in before["shape_keys"]]
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"} and settings.enabled
assert settings.space["bake_id"] == bake_id, "enabling again baked again"
scene.frame_set(6)
assert shown().tobytes() == at6.tobytes()
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("shapes.blend"))
print("SAVED", w6)
