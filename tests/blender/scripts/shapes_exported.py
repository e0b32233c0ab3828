"""exported.blend (shapes_export.py) without the add-on: Blender's mix of the artist's key and the
exported keys plays the blend of each frame."""

import bpy
import numpy as np
from support import blender as support

obj = bpy.data.objects["Bar"]
expected = np.load(support.tmp("expected.npy"))
size = np.ptp(expected[0], axis=0).max()
assert not any(m.type == "NODES" for m in obj.modifiers)
for i, f in enumerate(range(2, 10)):
    bpy.context.scene.frame_set(f)
    error = np.abs(support.evaluated_positions(obj) - expected[i]).max()
    assert error < 1e-5 * size, (f, error)
print("PLAYS")
