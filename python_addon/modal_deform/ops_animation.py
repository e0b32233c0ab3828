"""Bake animation: solve every frame of a range into its own shape key, keyed to show on its frame only.

The result plays back and renders without the add-on: frame f shows shape key "Modal Deform f"
(value 1 at f, 0 at f - 1 and f + 1, constant interpolation). Each frame starts from the previous
frame's solution (the solver keeps q and its inverse Hessian).
"""
import re

import bpy

from . import handles, mesh_io, posing
from .ops_bake import _mesh_poll
from .ops_pose import _FAILURES

_FRAME_KEY = re.compile(re.escape(posing.POSE_KEY) + r" -?\d{4,}")


def frame_key_name(frame):
    return f"{posing.POSE_KEY} {frame:04d}"


class AnimationJob:
    """Solves frames one at a time (step()); finish() or cancel() afterwards."""

    def __init__(self, context, obj, frames):
        self.pose = posing.Pose(context, obj)
        self.obj, self.scene, self.frames = obj, context.scene, list(frames)
        self.frame_before = self.scene.frame_current
        self.done = 0
        self.created = []  # (frame, key name as created: a new key may get a ".001" suffix)
        self.basis_created = obj.data.shape_keys is None
        self.unconverged = 0

    def step(self):
        """Solve the next frame into a new shape key; returns False when every frame is done."""
        if self.done == len(self.frames):
            return False
        frame = self.frames[self.done]
        self.scene.frame_set(frame)
        self.pose.follow_controllers()
        if not self.pose.converge()["converged"]:
            self.unconverged += 1
        mesh_io.ensure_reference_key(self.obj)
        block = self.obj.shape_key_add(name=frame_key_name(frame), from_mix=False)
        block.value = 0.0
        self.created.append((frame, block.name))
        self.pose.write(block)
        self.done += 1
        return True

    def finish(self):
        """Replace the keys of an earlier animation bake with the new ones and key their values."""
        obj = self.obj
        blocks = obj.data.shape_keys.key_blocks
        new_names = {name for _, name in self.created}
        old = [b.name for b in blocks if _FRAME_KEY.fullmatch(b.name) and b.name not in new_names]
        _remove_keys(obj, old)
        pose_block = blocks.get(posing.POSE_KEY)
        if pose_block is not None:
            pose_block.mute = True  # the frame keys take its place; it would add on top
        for frame, name in self.created:
            block = blocks[name]
            block.name = frame_key_name(frame)
            for f, value in ((frame - 1, 0.0), (frame, 1.0), (frame + 1, 0.0)):
                block.value = value
                block.keyframe_insert("value", frame=f)
            curve = _fcurves(obj.data.shape_keys.animation_data).find(block.path_from_id("value"))
            for point in curve.keyframe_points:
                point.interpolation = "CONSTANT"
        self.scene.frame_set(self.frame_before)

    def cancel(self):
        """Take away everything this job added."""
        names = [name for _, name in self.created]
        if self.basis_created and self.obj.data.shape_keys is not None:
            names.append(self.obj.data.shape_keys.reference_key.name)
        mesh_io.remove_shape_keys(self.obj, names)
        self.scene.frame_set(self.frame_before)


def _fcurves(animation_data):
    """The F-curves of an animation's action, None without one: on the action up to Blender 4.5, in
    the channel bag of the assigned slot from 5.0 (layered actions; Action.fcurves is gone)."""
    if animation_data is None or animation_data.action is None:
        return None
    if hasattr(animation_data.action, "fcurves"):
        return animation_data.action.fcurves
    from bpy_extras import anim_utils
    channelbag = anim_utils.animdata_get_channelbag_for_assigned_slot(animation_data)
    return None if channelbag is None else channelbag.fcurves


def _remove_keys(obj, names):
    """Remove shape keys and the curves that animate them."""
    keys = obj.data.shape_keys
    fcurves = _fcurves(keys.animation_data)
    for name in names:
        if fcurves is not None:
            curve = fcurves.find(keys.key_blocks[name].path_from_id("value"))
            if curve is not None:
                fcurves.remove(curve)
    mesh_io.remove_shape_keys(obj, names)


class MODAL_DEFORM_OT_bake_animation(bpy.types.Operator):
    """Solve every frame of the range with the controllers' animation into shape keys that play back and \
render without the add-on. Esc cancels"""
    bl_idname = "modal_deform.bake_animation"
    bl_label = "Bake Animation"
    bl_options = {"REGISTER", "UNDO"}

    frame_start: bpy.props.IntProperty(name="Start", description="First frame to solve (default: the scene's)")
    frame_end: bpy.props.IntProperty(name="End", description="Last frame to solve (default: the scene's)")

    poll = classmethod(_mesh_poll)

    def _job(self, context):
        scene = context.scene
        start = self.frame_start if self.properties.is_property_set("frame_start") else scene.frame_start
        end = self.frame_end if self.properties.is_property_set("frame_end") else scene.frame_end
        if end < start:
            raise ValueError(f"frame range: the end ({end}) is before the start ({start})")
        return AnimationJob(context, handles.owner(context.object), range(start, end + 1))

    def _finish(self, job):
        job.finish()
        message = f"Baked {len(job.frames)} frames into shape keys"
        if job.unconverged:
            self.report({"WARNING"}, f"{message}; {job.unconverged} did not converge")
        else:
            self.report({"INFO"}, message)
        return {"FINISHED"}

    def execute(self, context):
        try:
            job = self._job(context)
            while job.step():
                pass
        except _FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return self._finish(job)

    def invoke(self, context, event):
        try:
            self.job = self._job(context)
        except _FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, len(self.job.frames))
        self.timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _stop(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self.timer)
        wm.progress_end()
        context.workspace.status_text_set(None)

    def modal(self, context, event):
        job = self.job
        if event.type == "ESC" and event.value == "PRESS":
            self._stop(context)
            job.cancel()
            self.report({"WARNING"}, "Animation bake cancelled: nothing changed")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"RUNNING_MODAL"}
        try:
            more = job.step()
        except _FAILURES as error:
            self._stop(context)
            job.cancel()
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        if more:
            context.window_manager.progress_update(job.done)
            context.workspace.status_text_set(
                f"Modal Deform: baking animation, frame {job.done}/{len(job.frames)}   (Esc: cancel)")
            return {"RUNNING_MODAL"}
        self._stop(context)
        return self._finish(job)

    def cancel(self, context):
        self._stop(context)
        self.job.cancel()


CLASSES = (MODAL_DEFORM_OT_bake_animation,)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
