"""Open the file blender_scripts/pose.py saved: the pose is in the "Modal Deform" shape key, the base
mesh is as bake_and_save.py left it, and with the controllers where they were bound the pose is rest.

Arguments: DIMENSION, the basis's."""

import bpy
import numpy as np
from support import blender as support

posing = support.enable_addon("pose.posing")

(dimension,) = support.arguments()
obj = next(o for o in bpy.data.objects if o.type == "MESH")
rest = np.load(support.tmp("rest.npy"))
assert support.positions(obj).tobytes() == rest.tobytes(), "the base mesh changed"
pose = support.key_positions(obj, posing.POSE_KEY)
drift = np.abs(pose - rest).max() / np.ptp(rest, axis=0).max()
assert drift < 1e-3, f"controllers at rest, yet the pose moved by {drift:.2%} of the size"
assert obj.modal_deform.status.dimension == int(dimension), obj.modal_deform.status.dimension
