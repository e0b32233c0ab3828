"""Open the file inbetweens.py saved: the in-betweens are in it bit for bit and play the frames shown
before the save without solving anything; with the argument FRAME, only that frame is shown, as
`blender -b file.blend -f FRAME` renders it in a fresh process, and it is the timeline's frame."""

import bpy
import numpy as np
from support import blender as support

frame_cache, motion = support.enable_addon("playback.frame_cache", "inbetweens.motion")
obj = bpy.data.objects["Suzanne"]
scene = bpy.context.scene
cache = frame_cache.get(obj)
with open(support.tmp("digest.txt")) as f:
    assert frame_cache.digest(cache) == f.read(), "the in-betweens did not reload bit for bit"
shown = np.load(support.tmp("inbetweens.npy"))


def solving(*args):
    raise AssertionError("the in-betweens were solved again: the file's cache was not used")


motion.InbetweenJob = solving
frames = [int(a) for a in support.arguments()] or [20, 1, 40, 7, 33]
for frame in frames:
    scene.frame_set(frame)
    assert support.evaluated_positions(obj).tobytes() == shown[frame - 1].tobytes(), frame
print("frames", frames, "are the timeline's")
