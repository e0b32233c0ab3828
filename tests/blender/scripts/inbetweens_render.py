"""Run before `-f FRAME` on the file inbetweens.py saved (`blender -b inbetweens.blend --python
inbetweens_render.py -f 17`, a fresh process): enables the add-on so that the render's frame change
shows the in-betweens from the file's cache (solving is refused: nothing is solved), and after the
render writes the positions it rendered to render.npy, for the test to compare with the timeline's."""

import bpy
import numpy as np
from support import blender as support

motion = support.enable_addon("inbetweens.motion")


def solving(*args):
    raise AssertionError("the in-betweens were solved again: the file's cache was not used")


motion.InbetweenJob = solving


@bpy.app.handlers.persistent
def rendered(scene, *args):
    obj = bpy.data.objects["Suzanne"]
    np.save(support.tmp("render.npy"), support.evaluated_positions(obj))
    with open(support.tmp("render.txt"), "w") as f:
        f.write(str(scene.frame_current))


bpy.app.handlers.render_post.append(rendered)
