"""Solve In-betweens: the operator that solves an object's in-betweens with a progress bar (Esc
cancels: the old motion stays), run by the artist or, when a key or a setting changed, by the
add-on itself (solve_in_background, from a depsgraph update or a frame shown)."""

import bpy

from .. import app_handlers, handles
from ..ops_common import FAILURES, JobOperator, mesh_poll
from ..playback import frame_cache, timeline
from . import motion


class MODAL_DEFORM_OT_solve_inbetweens(JobOperator, bpy.types.Operator):
    """Solve the motion through the controllers' keyed poses (the keyframes themselves) that needs the least \
force under the dynamics, into the cache; the motion cached so far plays until it is done. Esc cancels"""

    bl_idname = "modal_deform.solve_inbetweens"
    bl_label = "Solve In-betweens"
    bl_options = {"REGISTER"}

    object_name: bpy.props.StringProperty(
        name="Object",
        options={"HIDDEN", "SKIP_SAVE"},
        description="The mesh (default: the active one)",
    )

    @classmethod
    def poll(cls, context):
        if not mesh_poll(cls, context):
            return False
        if frame_cache.kind(handles.owner(context.object)) != "INBETWEEN":
            cls.poll_message_set("Turn on Dynamics and its In-betweens")
            return False
        return True

    def _object(self, context):
        found = bpy.data.objects.get(self.object_name) if self.object_name else None
        return found or handles.owner(context.object)

    def _job(self, context):
        obj = self._object(context)
        motion.refused.pop(obj.name, None)
        motion.running[obj.name] = None  # the keys read move the frame: not asked again meanwhile
        try:
            job = motion.InbetweenJob(obj, context.scene)
        except FAILURES as error:
            motion.failed(obj, context.scene, "ERROR", str(error))
            raise
        motion.running[obj.name] = job
        self.scene = context.scene
        return job

    def _status(self):
        job = self.job
        if job.stage == "frames":
            return f"Modal Deform: in-betweens, frame {int(job.fraction * len(job.frames))}/{len(job.frames)}"
        return f"Modal Deform: solving the in-betweens through {len(job.keys)} keys"

    def _finish(self):
        job = self.job
        motion.running.pop(job.object_name, None)
        level, message = job.finish()
        self.report({level}, message)
        obj = bpy.data.objects.get(job.object_name)
        if obj is not None and not job.written:
            motion.failed(obj, self.scene, level, message)
        elif obj is not None and timeline.wants_playback(obj):
            timeline.show(obj, self.scene)
        return {"FINISHED"} if job.written else {"CANCELLED"}

    def cancel(self, context):
        motion.running.pop(self.job.object_name, None)
        super().cancel(context)


def solve_in_background(obj, window):
    """Start Solve In-betweens on obj in `window`, from a timer (a handler cannot start a modal
    operator); its progress shows in the status bar."""
    name = obj.name
    motion.running[name] = None  # asked: not asked again meanwhile

    def start():  # the operator's job takes the place of None, unless it does not start
        if bpy.data.objects.get(name) is not None and window.screen is not None:
            with bpy.context.temp_override(window=window, screen=window.screen):
                bpy.ops.modal_deform.solve_inbetweens("INVOKE_DEFAULT", object_name=name)
        if motion.running.get(name, False) is None:
            del motion.running[name]

    bpy.app.timers.register(start, first_interval=0.0)


def _keys_changed(scene, depsgraph=None):
    """A key moved, added or deleted, or a setting changed, with the timeline still: solve again."""
    if bpy.app.background:
        return
    for obj in scene.objects:
        if frame_cache.kind(obj) != "INBETWEEN" or not timeline.wants_playback(obj):
            continue
        try:
            cache = frame_cache.get(obj)
            if cache is None or not motion.is_fresh(cache, motion.freshness(obj, scene)):
                motion.request(obj, scene)
        except FAILURES:  # a damaged cache: the frame shown says so
            continue


_HANDLERS = (("depsgraph_update_post", _keys_changed), ("load_post", motion.forget))
CLASSES = (MODAL_DEFORM_OT_solve_inbetweens,)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    app_handlers.register(_HANDLERS)


def unregister():
    app_handlers.unregister(_HANDLERS)
    _unregister_classes()
    motion.forget()
