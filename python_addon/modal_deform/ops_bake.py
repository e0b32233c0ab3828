"""Bake: the basis of the active mesh, on a thread with progress and Esc (invoke) or at once (execute)."""
import bpy

from . import handles, storage
from .jobs import BakeJob
from .ops_common import mesh_poll


class MODAL_DEFORM_OT_bake(bpy.types.Operator):
    """Compute the deformation basis of the mesh (vibration modes, modal derivatives, ghost) and keep it in \
the file. Esc cancels"""
    bl_idname = "modal_deform.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(mesh_poll)

    def execute(self, context):
        job = BakeJob(handles.owner(context.object))
        job.run()
        level, message = job.finish()
        self.report({level}, message)
        return {"FINISHED"} if level == "INFO" else {"CANCELLED"}

    def invoke(self, context, event):
        self.job = BakeJob(handles.owner(context.object))
        self.job.start()
        wm = context.window_manager
        self.timer = wm.event_timer_add(0.1, window=context.window)
        wm.progress_begin(0, 1000)
        wm.modal_handler_add(self)
        self._show(context)
        return {"RUNNING_MODAL"}

    def _show(self, context):
        job = self.job
        context.window_manager.progress_update(int(1000 * job.overall))
        action = "cancelling" if job.cancelling else f"{job.stage} {100 * job.fraction:.0f}%"
        context.workspace.status_text_set(f"Modal Deform: baking '{job.object_name}': {action}   (Esc: cancel)")

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            self.job.cancel()
        if event.type != "TIMER":
            return {"RUNNING_MODAL"} if event.type == "ESC" else {"PASS_THROUGH"}
        if not self.job.done:
            self._show(context)
            return {"RUNNING_MODAL"}
        self._stop(context)
        level, message = self.job.finish()
        self.report({level}, message)
        for area in context.screen.areas:
            area.tag_redraw()
        return {"FINISHED"} if level == "INFO" else {"CANCELLED"}


    def _stop(self, context):
        wm = context.window_manager
        wm.event_timer_remove(self.timer)
        wm.progress_end()
        if context.workspace is not None:
            context.workspace.status_text_set(None)

    def cancel(self, context):
        """Blender ends the operator (file loaded, window closed): the bake stops, nothing is stored."""
        self.job.cancel()
        self._stop(context)


class MODAL_DEFORM_OT_clear_basis(bpy.types.Operator):
    """Remove the baked basis from the object (posing needs a new bake)"""
    bl_idname = "modal_deform.clear_basis"
    bl_label = "Clear Basis"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return mesh_poll(cls, context) and handles.owner(context.object).modal_deform.basis is not None

    def execute(self, context):
        storage.clear(handles.owner(context.object))
        return {"FINISHED"}


CLASSES = (MODAL_DEFORM_OT_bake, MODAL_DEFORM_OT_clear_basis)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
