"""The keys of the in-betweens, read from the controllers' keyframes themselves (not from their
curves' interpolation between them).

A handle is keyed at every frame where one of its controller's transform F-curves has a keyframe
point (for a bone: those of the bone, its parent bones and its armature object), at the
controller's transform evaluated at exactly that frame (constraints and parents included); at a
frame where only other handles are keyed it is None (a partial key: free there). A handle whose
controller has no transform keyframes holds its placement: at its bind it is a spring at rest
throughout (as a pinned handle), elsewhere it is keyed where it stands at every key frame. Keys on
no whole frame, before frame 0, more than MAX_KEYS or spanning more than MAX_SPAN frames are
refused with a message; so is having none.
"""

import numpy as np

from .. import handles as handles_
from ..core.inbetween import MAX_KEYS as MAX_INBETWEEN_KEYS
from ..playback import frame_cache, timeline
from ..playback.frame_keys import action_fcurves

#: Keyframes a motion takes at most (the core's limit): a controller keyed on most frames is an
#: animation already, for Dynamics to follow.
MAX_KEYS = MAX_INBETWEEN_KEYS
#: Frames from the first key to the last at most: the solve's time and memory grow with them (every
#: substep between is an unknown).
MAX_SPAN = 2000
#: The last components of the data paths that move an object or a bone.
TRANSFORM_PATHS = (
    "location",
    "rotation_euler",
    "rotation_quaternion",
    "rotation_axis_angle",
    "scale",
    "delta_location",
    "delta_rotation_euler",
    "delta_rotation_quaternion",
    "delta_scale",
)


def transform_curves(handle):
    """The F-curves that move a handle's controller (a handles.Handle), [] without a controller."""
    controller = handle.controller
    if controller is None:
        return []
    moves = frame_cache.moves_bone(handles_.pose_bone(handle))
    curves = action_fcurves(controller.animation_data) or ()
    return [
        c
        for c in curves
        if moves(c.data_path) and c.data_path.rsplit(".", 1)[-1] in TRANSFORM_PATHS
    ]


def key_frames(handle):
    """The frames a handle is keyed at, sorted ints. Raises ValueError for a key between frames."""
    frames = set()
    for curve in transform_curves(handle):
        for point in curve.keyframe_points:
            x = point.co.x
            if abs(x - round(x)) > 1e-3:
                raise ValueError(
                    f"handle '{handle.name}': controller '{handle.controller.name}' has a key at "
                    f"frame {x:g}, between two frames ({curve.data_path}): in-betweens take keys on "
                    f"whole frames (Key > Snap > Selection to Nearest Frame)"
                )
            frames.add(int(round(x)))
    return sorted(frames)


def read(obj, scene, handles):
    """The keys of obj's handles (handles.Handle, resolved), as core.Inbetween takes them: a list
    of (frame, one 4x4 or None per handle). The scene goes to each key frame and back."""
    per_handle = [key_frames(h) for h in handles]
    frames = sorted(set().union(*per_handle))
    if not frames:
        raise ValueError(
            f"'{obj.name}' has no keys: key the controllers (I over the viewport) at the poses "
            f"that matter, at least one"
        )
    if frames[0] < 0:
        raise ValueError(f"a key at frame {frames[0]}: in-betweens take keys from frame 0 on")
    if len(frames) > MAX_KEYS:
        raise ValueError(
            f"{len(frames)} keyed frames (from {frames[0]} to {frames[-1]}): in-betweens take at "
            f"most {MAX_KEYS}; key only the poses that matter (a motion keyed on most frames plays "
            f"with Dynamics alone, In-betweens off)"
        )
    if frames[-1] - frames[0] > MAX_SPAN:
        raise ValueError(
            f"keys from frame {frames[0]} to {frames[-1]}: in-betweens span at most {MAX_SPAN} "
            f"frames; split the shot, or move the stray key"
        )
    here = scene.frame_current
    keys = []
    try:
        for frame in frames:
            timeline.set_frame(scene, frame)
            placed = handles_.transforms(obj, handles)
            keys.append(
                (frame, [T if frame in mine else None for T, mine in zip(placed, per_handle)])
            )
    finally:
        timeline.set_frame(scene, here)
    for h, (handle, mine) in enumerate(zip(handles, per_handle)):
        if mine or handle.controller is None:
            continue
        placed = handles_.transforms(obj, [handle])[0]
        if not np.allclose(placed, np.eye(4), rtol=0.0, atol=1e-6):
            for _, transforms in keys:
                transforms[h] = placed
    return keys
