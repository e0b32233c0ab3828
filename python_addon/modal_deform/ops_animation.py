"""Bake animation: solve every frame of a range into its own shape key, keyed to show on its frame only
(jobs.AnimationJob does the work, a frame per timer tick)."""
import bpy

from . import handles
from .jobs import AnimationJob
from .ops_common import JobOperator, mesh_poll


class MODAL_DEFORM_OT_bake_animation(JobOperator, bpy.types.Operator):
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

    def _status(self):
        job = self.job
        return f"Modal Deform: baking animation, frame {job.frames_done}/{len(job.frames)}"


CLASSES = (MODAL_DEFORM_OT_bake_animation,)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
