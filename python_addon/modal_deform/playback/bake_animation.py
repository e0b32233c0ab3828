"""Bake animation: every frame of a range into the per-frame cache (operators.CacheJob: the pose
of each frame, or the simulation with dynamics on), or refined on the full mesh into a shape key per
frame (frame_keys.AnimationJob), a frame per timer tick."""

import bpy

from .. import handles
from ..ops_common import JobOperator, mesh_poll
from .frame_keys import AnimationJob
from .operators import CacheJob


class MODAL_DEFORM_OT_bake_animation(JobOperator, bpy.types.Operator):
    """Solve every frame of the range with the controllers' animation (with Dynamics on: simulate from its \
start) into the cache kept in the file, which plays back at the cost of a pose update; refined: into shape \
keys. Esc cancels"""

    bl_idname = "modal_deform.bake_animation"
    bl_label = "Bake Animation"
    bl_options = {"REGISTER", "UNDO"}

    frame_start: bpy.props.IntProperty(
        name="Start", description="First frame to solve (default: the scene's)"
    )
    frame_end: bpy.props.IntProperty(
        name="End", description="Last frame to solve (default: the scene's)"
    )
    refine: bpy.props.BoolProperty(
        name="Refine",
        default=False,
        description="Polish every frame on the full mesh (Newton's method, from the "
        "previous frame's answer) into a shape key per frame: exact shapes, "
        "seconds per frame",
    )

    poll = classmethod(mesh_poll)

    def _job(self, context):
        scene = context.scene
        start = (
            self.frame_start
            if self.properties.is_property_set("frame_start")
            else scene.frame_start
        )
        end = self.frame_end if self.properties.is_property_set("frame_end") else scene.frame_end
        if end < start:
            raise ValueError(f"frame range: the end ({end}) is before the start ({start})")
        obj = handles.owner(context.object)
        if self.refine:
            return AnimationJob(context, obj, range(start, end + 1))
        return CacheJob(context, obj, start, end)

    def _status(self):
        job = self.job
        return f"Modal Deform: baking animation, frame {job.frames_done}/{len(job.frames)}"


CLASSES = (MODAL_DEFORM_OT_bake_animation,)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
