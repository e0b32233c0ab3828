"""Blend as Shapes exported for a frame range: a Mesh Cache file (PC2) holds each frame's blend bit
for bit; Export Shape Keys writes a key per frame that Blender's mix adds to the artist's keys to make
the blend, and turns Blend as Shapes off; the artist's keys and keyframes stay. Saves exported.blend
and the expected frames for shapes_exported.py."""

import struct

import bpy
import numpy as np
from support import blender as support
from support.shape_keys import bar_with_bend

blending, frame_keys = support.enable_addon("shapes.blending", "playback.frame_keys")
obj, V, F, bend = bar_with_bend()
scene = bpy.context.scene
block = obj.data.shape_keys.key_blocks["Bend"]
block.keyframe_insert("value", frame=1)
block.value = 1.0
block.keyframe_insert("value", frame=11)
# The object's own basis, baked first, is the space's (not baked again with the settings now).
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
obj.modal_deform.modes += 2
assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}
space = blending.load(obj)
assert space.base_dimension == obj.modal_deform.status.dimension == 12 + 20, space
scene.frame_set(3)
artist = support.mesh_state(obj)
frames = range(2, 10)
expected = {}
for f in frames:
    scene.frame_set(f)
    expected[f] = space.blend([block.value])

# Mesh Cache: the blend of each frame, bit for bit; the scene back at its frame.
scene.frame_set(3)
path = support.tmp("blend.pc2")
result = bpy.ops.modal_deform.export_blend_mesh_cache(
    filepath=path, file_format="PC2", frame_start=frames[0], frame_end=frames[-1]
)
assert result == {"FINISHED"} and scene.frame_current == 3
with open(path, "rb") as f:
    signature, version, points, start, rate, samples = struct.unpack("<12siiffi", f.read(32))
    data = np.frombuffer(f.read(), "<f4").reshape(samples, points, 3)
assert (points, start, samples) == (len(V), frames[0], len(frames))
for i, f in enumerate(frames):
    assert data[i].tobytes() == expected[f].tobytes(), f"frame {f} of the PC2 file"

# Shape keys: the keys' mix plays the blend; Blend as Shapes goes off; the artist's keys stay.
result = bpy.ops.modal_deform.export_blend_shape_keys(frame_start=frames[0], frame_end=frames[-1])
assert result == {"FINISHED"}
assert not obj.modal_deform.shapes.enabled and obj.modal_deform.shapes.space is not None
names = [b.name for b in obj.data.shape_keys.key_blocks]
assert names == ["Basis", "Bend"] + [frame_keys.frame_key_name(f) for f in frames], names
assert support.key_positions(obj, "Bend").tobytes() == artist["shape_keys"][1][3]
assert support.positions(obj).tobytes() == artist["co"]
size = np.ptp(V, axis=0).max()
errors = []
for f in frames:
    scene.frame_set(f)
    errors.append(np.abs(support.evaluated_positions(obj) - expected[f]).max())
print("EXPORT_ERROR", max(errors) / size)
assert max(errors) < 1e-5 * size, errors
assert block.value > 0 and not block.mute, "the artist's key changed"
np.save(support.tmp("expected.npy"), np.array([expected[f] for f in frames]))
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("exported.blend"))
