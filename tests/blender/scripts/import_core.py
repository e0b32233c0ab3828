"""modal_deform.core imports inside Blender's Python and computes on a Blender mesh."""

import bpy
import numpy as np
from support import blender as support

mdc = support.enable_addon("core")
bpy.ops.mesh.primitive_monkey_add()
mesh = bpy.context.object.data
V = np.empty(3 * len(mesh.vertices), np.float64)
mesh.vertices.foreach_get("co", V)
mesh.calc_loop_triangles()
F = np.empty(3 * len(mesh.loop_triangles), np.int32)
mesh.loop_triangles.foreach_get("vertices", F)
report = mdc.check(V.reshape(-1, 3), F.reshape(-1, 3))
assert report["vertices"] == 507 and report["components"] == 3, report
