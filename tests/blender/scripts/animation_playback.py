"""Without the add-on: the evaluated mesh at each frame is the shape key baked for it."""

import addon_utils
import bpy
import numpy as np
from support import blender as support

assert not addon_utils.check("modal_deform")[1], "the add-on must not be enabled here"
obj = bpy.data.objects["Suzanne"]
scene = bpy.context.scene
rest = np.load(support.tmp("rest.npy"))
for frame in (1, 5, 10):
    scene.frame_set(frame)
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    expected = np.load(support.tmp(f"frame{frame}.npy"))
    assert np.abs(co.reshape(-1, 3) - expected).max() < 1e-6, (
        f"frame {frame} does not show its shape key"
    )
moved = np.abs(np.load(support.tmp("frame10.npy")) - rest).max()
assert moved > 0.3, f"the animated handle did not move the mesh ({moved})"
