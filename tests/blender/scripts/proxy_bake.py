"""A dense mesh through the same Bake button: baked on a proxy (small thresholds here), the proxy
size in the status the Basis panel shows, the proxy basis and its prolongation stored and read back
bit for bit after a reload, posed into the fine shape key, and a mode previewed on every vertex."""

import bpy
import numpy as np
from support import blender as support

ops_preview, posing, storage = support.enable_addon("ops_preview", "pose.posing", "storage")

obj = support.suzanne(2)  # 7,958 vertices
settings = obj.modal_deform
settings.modes, settings.derivatives, settings.ghost = 12, 10, 300
settings.proxy_above, settings.proxy = 5000, 2000
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
status = settings.status
n = len(obj.data.vertices)
assert status.num_vertices == n and 1800 <= status.proxy_vertices <= 2200, (
    n,
    status.proxy_vertices,
)
basis = storage.load(obj)
assert basis.on_proxy and basis.vectors.shape == (3 * status.proxy_vertices, status.dimension)
assert settings.basis["prolongation_weights"].typecode == "f"
arrays = basis.to_arrays()

rest = support.positions(obj)
axis = int(np.argmax(np.ptp(rest, axis=0)))
low, high = np.quantile(rest[:, axis], [0.15, 0.85])
moved = support.add_handle(obj, rest[:, axis] > high)
support.add_handle(obj, rest[:, axis] < low).controller = None
name = obj.name
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("proxy.blend"))
bpy.ops.wm.open_mainfile(filepath=support.tmp("proxy.blend"))
obj = bpy.data.objects[name]
bpy.context.view_layer.objects.active = obj
settings = obj.modal_deform
for name, a in storage.load(obj).to_arrays().items():
    assert a.tobytes() == arrays[name].tobytes(), f"{name} differs after reload"

size = np.ptp(rest, axis=0).max()
moved = settings.handles[0]
moved.controller.location[(axis + 1) % 3] += 0.1 * size
bpy.context.view_layer.update()
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
pose = support.key_positions(obj, posing.POSE_KEY)
assert pose.shape == (n, 3) and support.positions(obj).tobytes() == rest.tobytes()
shift = (pose - rest)[rest[:, axis] > high, (axis + 1) % 3].mean()
assert abs(shift - 0.1 * size) < 0.01 * size, shift / size

settings.preview_vector = settings.status.num_rigid
settings.preview_amplitude = 0.1
assert bpy.ops.modal_deform.preview_mode() == {"FINISHED"}
preview = support.key_positions(obj, ops_preview.PREVIEW_KEY)
assert abs(np.linalg.norm(preview - rest, axis=1).max() - 0.1 * size) < 1e-3 * size
print(n, "vertices posed through a proxy of", settings.status.proxy_vertices)
