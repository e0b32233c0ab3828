"""Bake animation: solve every frame of a range into its own shape key, keyed to show on its frame only
(jobs.AnimationJob does the work a frame per timer tick)."""
import bpy

from . import handles
from .jobs import AnimationJob
from .ops_common import FAILURES, mesh_poll


class MODAL_DEFORM_OT_bake_animation(bpy.types.Operator):
    """Solve every frame of the range with the controllers' animation into shape keys that play back and \
render without the add-on. Esc cancels"""
    bl_idname = "modal_deform.bake_animation"
    bl_label = "Bake Animation"
    bl_options = {"REGISTER", "UNDO"}

    frame_start: bpy.props.IntProperty(name="Start", description="First frame to solve (default: the scene's)")
    frame_end: bpy.props.IntProperty(name="End", description="Last frame to solve (default: the scene's)")
    refine: bpy.props.BoolProperty(name="Refine", default=False,
                                   description="Polish every frame on the full mesh (Newton's method, from the "
                                               "previous frame's answer): exact shapes, seconds per frame")

    poll = classmethod(mesh_poll)

    def _job(self, context):
        scene = context.scene
        start = self.frame_start if self.properties.is_property_set("frame_start") else scene.frame_start
        end = self.frame_end if self.properties.is_property_set("frame_end") else scene.frame_end
        if end < start:
            raise ValueError(f"frame range: the end ({end}) is before the start ({start})")
        return AnimationJob(context, handles.owner(context.object), range(start, end + 1), refine=self.refine)

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
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        return self._finish(job)

    def invoke(self, context, event):
        try:
            self.job = self._job(context)
        except FAILURES as error:
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
        except FAILURES as error:
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
