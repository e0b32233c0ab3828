"""An animation as shape keys: one key per frame, keyed to show on its frame only, so the result
plays back and renders without the add-on. Frame f shows shape key "Modal Deform f" (value 1 at f, 0
at f - 1 and f + 1, constant interpolation). AnimationJob writes them, a frame per tick, from its
own refined solves (the refined animation bake) or from the per-frame cache (frame_cache.py, the
shape key export); refined, each frame starts from the previous frame's refined answer.
"""

import re

import numpy as np

from .. import mesh_io
from ..jobs import FrameJob
from ..pose import posing

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


class AnimationJob(FrameJob):
    """Writes the frames one per tick() into new shape keys: each frame's pose refined on the full
    mesh (Newton's method from the reduced pose, then from the previous frame's answer), or with
    `positions` (frame -> #V by 3 float32) what it gives (the cache's frames); finish() keys them,
    cancel() (or a failure) takes them away."""

    def __init__(self, context, obj, frames, positions=None):
        super().__init__(frames)
        self.positions = positions
        self.action = "Animation bake" if positions is None else "Shape key export"
        self.pose = posing.Pose(context, obj) if positions is None else None
        self.triangles = mesh_io.triangles(obj.data) if positions is None else None
        self.refined = None
        self.obj, self.scene = obj, context.scene
        self.frame_before = self.scene.frame_current
        self.created = []  # (frame, key name as created: a new key may get a ".001" suffix)
        self.basis_created = obj.data.shape_keys is None
        self.unconverged = 0

    def _frame(self, frame):
        """Solve (or take) the frame's positions into a new shape key."""
        if self.positions is None:
            self.scene.frame_set(frame)
            self.pose.follow_controllers()
            self.pose.converge()
            self.refined, stats = self.pose.solver.refine(self.triangles, initial=self.refined)
            if not stats["converged"]:
                self.unconverged += 1
            co = self.refined.astype(np.float32)
        else:
            co = self.positions(frame)
        mesh_io.ensure_reference_key(self.obj)
        block = self.obj.shape_key_add(name=frame_key_name(frame), from_mix=False)
        block.value = 0.0
        self.created.append((frame, block.name))
        mesh_io.write_shape_key(self.obj.data, block, co)

    def finish(self):
        """Replace the keys of an earlier animation bake with the new ones and key their values.
        Returns (level, message) for a report."""
        if self.cancelling:
            return "WARNING", f"{self.action} cancelled: nothing changed"
        if self.error is not None:
            return "ERROR", f"{self.action} failed: {self.error}"
        obj = self.obj
        blocks = obj.data.shape_keys.key_blocks
        new_names = {name for _, name in self.created}
        old = [b.name for b in blocks if is_frame_key(b.name) and b.name not in new_names]
        remove_keys(obj, old)
        pose_block = blocks.get(posing.POSE_KEY)
        if pose_block is not None:
            pose_block.mute = True  # the frame keys take its place; it would add on top
        for frame, name in self.created:
            block = blocks[name]
            block.name = frame_key_name(frame)
            show_on_its_frame(obj, block, frame)
        self.scene.frame_set(self.frame_before)
        self.written = True
        message = (
            f"{'Exported' if self.positions else 'Baked'} {len(self.frames)} frames into shape keys"
        )
        if self.unconverged:
            return "WARNING", f"{message}; {self.unconverged} did not converge"
        return "INFO", message

    def _take_back(self):
        names = [name for _, name in self.created]
        if self.basis_created and self.obj.data.shape_keys is not None:
            names.append(self.obj.data.shape_keys.reference_key.name)
        mesh_io.remove_shape_keys(self.obj, names)
        self.created = []
        self.scene.frame_set(self.frame_before)
