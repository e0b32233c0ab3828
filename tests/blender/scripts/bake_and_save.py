"""Bake a mesh through the operator, add two handles, pose, save the file and what a reload must find.

Arguments: suzanne | dragon PATH. Writes TEST_TMP/baked.blend, TEST_TMP/basis.npz (the basis as
baked) and TEST_TMP/rest.npy (the base mesh's positions).
"""

import bpy
import numpy as np
from support import blender as support

mdc, posing, storage = support.enable_addon("core", "pose.posing", "storage")

args = support.arguments()
if args[0] == "suzanne":
    obj = support.suzanne(2)  # 7,958 vertices, quads
else:
    V, F = mdc.read_mesh(args[1])
    obj = support.mesh_object("Dragon", V, F)
settings = obj.modal_deform
settings.ghost = 500
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
assert storage.stale_reason(obj) == ""
assert settings.basis.name.startswith("."), settings.basis.name
assert settings.status.dimension >= 20 + 52, settings.status.dimension

V = support.positions(obj)
axis = int(np.argmax(np.ptp(V, axis=0)))  # the longest axis: handles at both ends
low, high = np.quantile(V[:, axis], [0.1, 0.9])
support.add_handle(obj, V[:, axis] > high)
support.add_handle(obj, V[:, axis] < low)
assert [h.controller is not None for h in settings.handles] == [True, True]
# Posed before saving (the first controller moved sideways by 5% of the model's size), then the
# controller put back: the file keeps the pose's shape key, the scripts reading it find rest handles.
controller = settings.handles[0].controller
start = controller.location.copy()
controller.location[(axis + 1) % 3] += 0.05 * np.ptp(V, axis=0).max()
bpy.context.view_layer.update()
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
assert (
    np.abs(support.key_positions(obj, posing.POSE_KEY) - V).max() > 0.01 * np.ptp(V, axis=0).max()
), "no pose"
controller.location = start

np.savez(support.tmp("basis.npz"), **storage.load(obj).to_arrays())
np.save(support.tmp("rest.npy"), support.positions(obj))
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("baked.blend"))
print("BAKED", obj.name, settings.status.dimension, len(V))
