"""Quads and n-gons are triangulated for the energy without touching the faces; mode preview."""

import math

import bpy
import numpy as np
from support import blender as support

ops_preview, storage = support.enable_addon("ops_preview", "storage")

# A closed tube: 24 x 20 quads around, and a 24-gon at each end.
around, rings = 24, 21
angles = 2 * math.pi * np.arange(around) / around
V = [(math.cos(a), math.sin(a), 4.0 * r / (rings - 1)) for r in range(rings) for a in angles]
quads = [
    (
        r * around + i,
        r * around + (i + 1) % around,
        (r + 1) * around + (i + 1) % around,
        (r + 1) * around + i,
    )
    for r in range(rings - 1)
    for i in range(around)
]
caps = [tuple(reversed(range(around))), tuple((rings - 1) * around + i for i in range(around))]
obj = support.mesh_object("Tube", np.array(V), quads + caps)
mesh = obj.data
polygons_before = [tuple(p.vertices) for p in mesh.polygons]
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 12, 20, 200
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
assert [tuple(p.vertices) for p in mesh.polygons] == polygons_before, "the bake changed the faces"

rest = support.positions(obj)
top = support.add_handle(obj, rest[:, 2] > 3.9)
support.add_handle(obj, rest[:, 2] < 0.1).controller = None
top.controller.location.x += 1.0
bpy.context.view_layer.update()
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
pose = support.key_positions(obj, "Modal Deform")
assert abs(pose[rest[:, 2] > 3.9, 0].mean() - rest[rest[:, 2] > 3.9, 0].mean() - 1.0) < 0.02
assert [tuple(p.vertices) for p in mesh.polygons] == polygons_before, "posing changed the faces"
assert support.positions(obj).tobytes() == rest.tobytes()

# Mode preview: the first vibration mode at 10% of the size, shown in its own key; and gone again.
settings = obj.modal_deform
settings.preview_vector = settings.status.num_rigid
settings.preview_amplitude = 0.1
assert bpy.ops.modal_deform.preview_mode() == {"FINISHED"}
assert ops_preview.showing(obj)
preview = support.key_positions(obj, ops_preview.PREVIEW_KEY)
largest = np.linalg.norm(preview - rest, axis=1).max()
assert abs(largest - 0.1 * 4.0) < 1e-4, largest
basis = storage.load(obj)
u = basis.vectors[:, settings.status.num_rigid].reshape(-1, 3)
assert np.allclose(preview - rest, u * (0.4 / np.linalg.norm(u, axis=1).max()), atol=1e-5)
settings.preview_amplitude = -0.2  # the key follows the slider
assert (
    abs(
        np.linalg.norm(support.key_positions(obj, ops_preview.PREVIEW_KEY) - rest, axis=1).max()
        - 0.8
    )
    < 1e-4
)
assert bpy.ops.modal_deform.preview_mode() == {"FINISHED"}
assert not ops_preview.showing(obj)
