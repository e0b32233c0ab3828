"""A region bake through the Basis panel (issue 24): Suzanne's left ear as the Region Group, its tip
pulled up; every vertex outside the ear stays exactly where it was. The ear alone has more vertices
than Proxy Above, so it is baked on a proxy of its own faces. Stale when the region is
painted anew; a handle outside the region is refused. Saves TEST_TMP/region.blend for
region_reload.py."""

import bpy
import numpy as np
from mathutils import Matrix
from support import blender as support

posing, storage = support.enable_addon("pose.posing", "storage")

obj = support.suzanne(1)
settings = obj.modal_deform
settings.modes, settings.derivatives, settings.ghost = 12, 20, 300
V = support.positions(obj)
ear = V[:, 0] > 0.75
group = obj.vertex_groups.new(name="Ear")
group.add([int(i) for i in np.flatnonzero(ear)], 1.0, "REPLACE")
settings.region_group = "Ear"
settings.proxy_above, settings.proxy = int(ear.sum()) // 2, int(ear.sum()) // 3
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
basis = storage.load(obj)
np.testing.assert_array_equal(basis.region, np.flatnonzero(ear))
assert (
    basis.num_rigid == 0
    and basis.on_proxy
    and settings.status.proxy_vertices == basis.num_basis_vertices
)

# A handle outside the ear: refused, naming the region.
outside = support.add_handle(obj, V[:, 2] < -0.7)
outside.controller = None
support.expect_error(
    bpy.ops.modal_deform.solve, "vertices outside the region the basis was baked with"
)
bpy.ops.modal_deform.remove_handle()
tip = support.add_handle(obj, V[:, 0] > 1.25)
tip.controller.matrix_world = Matrix.Translation((0.0, 0.0, 0.3)) @ tip.controller.matrix_world
bpy.context.view_layer.update()
assert bpy.ops.modal_deform.solve() == {"FINISHED"}
pose = support.key_positions(obj, posing.POSE_KEY)
assert pose[~ear].tobytes() == V[~ear].tobytes(), "a vertex outside the region moved"
assert pose[V[:, 0] > 1.25, 2].mean() - V[V[:, 0] > 1.25, 2].mean() > 0.2

# The region painted anew: stale until painted back.
group.add([int(np.flatnonzero(~ear)[0])], 1.0, "REPLACE")
assert storage.stale_reason(obj) == "region weights painted anew", storage.stale_reason(obj)
group.remove([int(np.flatnonzero(~ear)[0])])
assert storage.stale_reason(obj) == ""
np.save(support.tmp("region_pose.npy"), pose)
bpy.ops.wm.save_as_mainfile(filepath=support.tmp("region.blend"))
