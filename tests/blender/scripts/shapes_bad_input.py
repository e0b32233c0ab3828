"""Blend as Shapes on bad input: each refused with a message naming what is wrong (in the operator's
report or the panel's problems), the mesh showing Blender's mix meanwhile, the artist's mesh and keys
never changed, never a crash. And the decisions on Blender's key settings: Relative To another key,
muted keys, weights outside [0, 1], Dynamics on the same object."""

import time

import bpy
import numpy as np
from support import blender as support
from support.shape_keys import add_key, bar_with_bend, bend, draw_panels

blending, operators, frame_display = support.enable_addon(
    "shapes.blending", "shapes.operators", "playback.frame_display"
)
obj, V, F, bent = bar_with_bend()
scene = bpy.context.scene
keys = obj.data.shape_keys
size = np.ptp(V, axis=0).max()


def shown():
    return support.evaluated_positions(obj)


def update():
    bpy.context.view_layer.update()


def problem():
    return blending.problems.get(obj.name, "")


def refused(text):
    """The toggle refuses (an ERROR report, CANCELLED) with `text` in its message; nothing changed."""
    before = support.mesh_state(obj)
    try:
        result = bpy.ops.modal_deform.blend_as_shapes()
    except RuntimeError as error:  # Blender raises the ERROR report of an operator run from Python
        assert text in str(error), error
    else:
        raise AssertionError(f"not refused ({result}): expected {text!r}")
    assert not obj.modal_deform.shapes.enabled and support.mesh_state(obj) == before


# The bake on a thread (the toggle's invoke, with a progress bar): cancelled, nothing changes;
# run to its end, it stores the space and turns Blend as Shapes on.
before = support.mesh_state(obj)
job = operators.ShapesJob(obj)
job.cancel()
job.start()
while job.tick():
    time.sleep(0.01)
level, message = job.finish()
assert level == "WARNING" and "cancelled" in message, message
assert support.mesh_state(obj) == before and obj.modal_deform.shapes.space is None
job = operators.ShapesJob(obj)
job.start()
progress = [job.overall]
while job.tick():
    progress.append(job.overall)
    time.sleep(0.01)
level, message = job.finish()
assert level == "INFO" and obj.modal_deform.shapes.enabled, message
assert progress == sorted(progress), progress
print("JOB", message, len(progress), progress[-1])
assert bpy.ops.modal_deform.clear_shapes() == {"FINISHED"}
assert obj.modal_deform.shapes.space is None and not frame_display.shows(obj)
assert support.mesh_state(obj) == before

# Absolute keys and a key with a vertex group are refused.
keys.use_relative = False
refused("absolute")
keys.use_relative = True
keys.key_blocks["Bend"].vertex_group = "Group"  # a name alone: refused before Blender reads it
refused("vertex group")
keys.key_blocks["Bend"].vertex_group = ""

# A key equal to the basis, a key relative to another key, a key that folds the bar flat.
same = add_key(obj, "Same", V)
half = add_key(obj, "Half", 0.5 * (V + bent))
tip = add_key(obj, "Tip", 0.5 * (V + bent) + [0.0, 0.0, 0.5] * (V[:, 2:] > 3.9))
tip.relative_key = half  # adds (Tip − Half): the tip stretched by 0.5
flat = V.copy()
flat[:, 0] = 0.5
add_key(obj, "Flat", flat)
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}
assert obj.modal_deform.shapes.key_names.split("\n") == ["Bend", "Same", "Half", "Tip", "Flat"]
space = blending.load(obj)


def weights(**values):
    for block in keys.key_blocks[1:]:
        block.value = values.get(block.name, 0.0)
    update()


weights(Same=1.0)
assert np.abs(shown() - V).max() < 1e-4 * size, "a key equal to the basis does not show the basis"
weights(Tip=1.0)  # Blender's mix: V + (Tip − Half), so the blend at weight 1 is that shape
relative_shape = V + (support.key_positions(obj, "Tip") - support.key_positions(obj, "Half"))
assert np.abs(shown() - relative_shape).max() < 1e-3 * size
weights(Flat=0.5)
assert np.isfinite(shown()).all() and not problem(), problem()
print("FOLD", blending.notes.get(obj.name, "converged"))
# Muted keys weigh 0; a weight beyond the slider's [0, 1] passes through.
weights(Bend=1.0)
keys.key_blocks["Bend"].mute = True
update()
assert np.abs(shown() - V).max() < 1e-4 * size, "a muted key is blended"
keys.key_blocks["Bend"].mute = False
keys.key_blocks["Bend"].slider_max = 2.0
weights(Bend=1.5)
assert shown().tobytes() == space.blend([1.5, 0, 0, 0, 0]).tobytes()
assert np.isfinite(shown()).all()

# A weight that is not a number (a script gone wrong; Blender keeps a driver's nan out itself):
# refused in the panel, Blender's mix shows; a number again, the blend again.
weights(Bend=0.5)
at_half = shown()
state = support.mesh_state(obj)
keys.key_blocks["Bend"].value = float("nan")
update()
assert "has the weight nan" in problem(), problem()
assert "has the weight nan" in draw_panels(obj), draw_panels(obj)
assert not frame_display.shows(obj)
weights(Bend=0.5)
assert not problem() and shown().tobytes() == at_half.tobytes()
assert support.mesh_state(obj) == state

# Dynamics on the same object wins: the blend waits, the panel says why; off again, the blend shows.
obj.modal_deform.dynamics.enabled = True
scene.frame_set(3)
assert problem() == blending.DYNAMICS_WINS, problem()
obj.modal_deform.dynamics.enabled = False
scene.frame_set(4)
assert not problem() and shown().tobytes() == at_half.tobytes(), problem()
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}  # off
obj.modal_deform.dynamics.enabled = True
refused("Dynamics")
obj.modal_deform.dynamics.enabled = False

# A key removed after the bake: stale, named.
obj.shape_key_remove(keys.key_blocks["Flat"])
assert "'Flat'" in blending.stale_reason(obj), blending.stale_reason(obj)

# 200 keys: bends of the bar about other axes and angles.
for block in list(keys.key_blocks)[1:]:
    obj.shape_key_remove(block)
angles = np.linspace(-np.pi / 2, np.pi / 2, 200)
for i, angle in enumerate(angles):
    X = V.copy()
    X[:, :2] -= 0.5
    c, s = np.cos(i), np.sin(i)
    X[:, :2] = X[:, :2] @ np.array([[c, -s], [s, c]])
    X = bend(X + [0.5, 0.5, 0.0], angle if angle else 0.1)
    add_key(obj, f"Key {i}", X)
start = time.perf_counter()
assert bpy.ops.modal_deform.bake_shapes() == {"FINISHED"}
print(f"KEYS200 bake {time.perf_counter() - start:.2f} s")
keys.key_blocks["Key 7"].value = 0.5
keys.key_blocks["Key 150"].value = 0.3
start = time.perf_counter()
update()
print(f"KEYS200 blend {1000 * (time.perf_counter() - start):.1f} ms")
assert np.isfinite(shown()).all() and frame_display.shows(obj) and not problem(), problem()
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}  # off: the mesh is the artist's
assert not frame_display.shows(obj) and np.array_equal(support.positions(obj), V)
print("BAD_INPUT_DONE")
