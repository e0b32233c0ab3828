"""Open the file bake_and_save.py wrote: the basis must be bit for bit what was baked; then move
one controller, solve, and check the pose (handles on target, base mesh untouched)."""

import math

import bpy
import numpy as np
from mathutils import Matrix
from support import blender as support

handles, posing, storage = support.enable_addon("handles", "pose.posing", "storage")

obj = next(o for o in bpy.data.objects if o.type == "MESH")
bpy.context.view_layer.objects.active = obj
settings = obj.modal_deform
assert storage.stale_reason(obj) == ""
saved = np.load(support.tmp("basis.npz"))
loaded = storage.load(obj).to_arrays()
assert sorted(saved.files) == sorted(loaded), (saved.files, list(loaded))
for name in saved.files:
    assert saved[name].dtype == loaded[name].dtype, name
    assert saved[name].tobytes() == loaded[name].tobytes(), f"{name} differs after reload"
# Stored as raw arrays of their own dtype: the vectors are float32 ID properties.
assert settings.basis["vectors"].typecode == "f"

rest = np.load(support.tmp("rest.npy"))
moved, pinned = settings.handles
pinned.controller = None  # pinned where it is
size = np.ptp(rest, axis=0).max()
turn = Matrix.Rotation(math.radians(30), 4, "X")
moved.controller.matrix_world = (
    Matrix.Translation((0.0, 0.1 * size, 0.05 * size)) @ moved.controller.matrix_world @ turn
)
bpy.context.view_layer.update()
assert bpy.ops.modal_deform.solve() == {"FINISHED"}

pose = support.key_positions(obj, posing.POSE_KEY)
assert obj.data.shape_keys.key_blocks[posing.POSE_KEY].value == 1.0
assert support.positions(obj).tobytes() == rest.tobytes(), "the base mesh changed"
resolved, _ = handles.resolve(obj, bpy.context.scene, rest.astype(np.float64))
for handle, T in zip(resolved, handles.transforms(obj, resolved)):
    target = rest[handle.indices] @ T[:3, :3].T + T[:3, 3]
    error = np.linalg.norm(pose[handle.indices] - target, axis=1).mean() / size
    assert error < 0.01, (
        f"handle {handle.name} misses its target by {error:.2%} of the model's size"
    )
print(obj.name, "posed: moved by", np.abs(pose - rest).max() / size, "of its size")
