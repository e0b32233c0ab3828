"""An animation as shape keys: one key per frame, keyed to show on its frame only, so the result
plays back and renders without the add-on. Frame f shows shape key "Modal Deform f" (value 1 at f, 0
at f - 1 and f + 1, constant interpolation). The refined animation bake (jobs.AnimationJob) writes
them, from its own solves or from the per-frame cache (playback/frame_cache.py).
"""

import re

from . import mesh_io, posing

_FRAME_KEY = re.compile(re.escape(posing.POSE_KEY) + r" -?\d{4,}")


def frame_key_name(frame):
    return f"{posing.POSE_KEY} {frame:04d}"


def is_frame_key(name):
    """Whether `name` is a frame key's (frame_key_name), as an earlier animation bake left it."""
    return _FRAME_KEY.fullmatch(name) is not None


def show_on_its_frame(obj, block, frame):
    """Key the value of the shape key `block` of obj to 1 at `frame` and 0 on the frames either side,
    with constant interpolation."""
    for f, value in ((frame - 1, 0.0), (frame, 1.0), (frame + 1, 0.0)):
        block.value = value
        block.keyframe_insert("value", frame=f)
    curve = action_fcurves(obj.data.shape_keys.animation_data).find(block.path_from_id("value"))
    for point in curve.keyframe_points:
        point.interpolation = "CONSTANT"


def action_fcurves(animation_data):
    """The F-curves of an animation's action, None without one: on the action up to Blender 4.5, in
    the channel bag of the assigned slot from 5.0 (layered actions; Action.fcurves is gone)."""
    if animation_data is None or animation_data.action is None:
        return None
    if hasattr(animation_data.action, "fcurves"):
        return animation_data.action.fcurves
    from bpy_extras import anim_utils

    channelbag = anim_utils.animdata_get_channelbag_for_assigned_slot(animation_data)
    return None if channelbag is None else channelbag.fcurves


def remove_keys(obj, names):
    """Remove shape keys and the curves that animate them."""
    keys = obj.data.shape_keys
    fcurves = action_fcurves(keys.animation_data)
    for name in names:
        if fcurves is not None:
            curve = fcurves.find(keys.key_blocks[name].path_from_id("value"))
            if curve is not None:
                fcurves.remove(curve)
    mesh_io.remove_shape_keys(obj, names)
