"""Open the file painted_stiffness.py wrote: the painted basis is still fresh and poses as before; a
deleted stiffness group makes the basis stale and the bake refuse; its middle third, painted stiff,
stayed nearly rigid where a uniform bake bends it."""

import bpy
import numpy as np
from support import blender as support

posing, storage = support.enable_addon("pose.posing", "storage")

obj = bpy.data.objects["Bar"]
bpy.context.view_layer.objects.active = obj
settings = obj.modal_deform
V = support.positions(obj).astype(np.float64)
middle = (V[:, 2] > 2) & (V[:, 2] < 4)
assert storage.stale_reason(obj) == ""
assert np.array_equal(storage.load(obj).stiffness_weights, middle.astype(np.float64))


def middle_deviation():
    """RMS distance of the posed middle third from its best rigid motion (Kabsch)."""
    assert bpy.ops.modal_deform.solve() == {"FINISHED"}
    posed = support.key_positions(obj, posing.POSE_KEY).astype(np.float64)[middle]
    a, b = V[middle] - V[middle].mean(axis=0), posed - posed.mean(axis=0)
    U, _, Wt = np.linalg.svd(a.T @ b)
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Wt))])
    return np.sqrt(np.mean(np.sum((a @ U @ D @ Wt - b) ** 2, axis=1)))


painted = middle_deviation()
saved = np.load(support.tmp("painted_pose.npy"))
assert np.abs(support.key_positions(obj, posing.POSE_KEY) - saved).max() < 1e-4 * np.ptp(V)
obj.vertex_groups.remove(obj.vertex_groups["Stiff"])
assert storage.stale_reason(obj) == "stiffness group 'Stiff' was deleted", storage.stale_reason(obj)
support.expect_error(bpy.ops.modal_deform.solve, "was deleted): re-bake")
support.expect_error(bpy.ops.modal_deform.bake, "the stiffness vertex group 'Stiff' does not exist")
settings.stiffness_group = ""
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
uniform = middle_deviation()
assert painted < 0.2 * uniform, (painted, uniform)
