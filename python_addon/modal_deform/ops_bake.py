"""Bake: the basis of the active mesh, on a thread with progress and Esc (invoke) or at once (execute)."""

import bpy

from . import handles, storage
from .jobs import BakeJob
from .ops_common import JobOperator, mesh_poll


class MODAL_DEFORM_OT_bake(JobOperator, bpy.types.Operator):
    """Compute the deformation basis of the mesh (vibration modes, modal derivatives, ghost) and keep it in \
the file. Esc cancels"""

    bl_idname = "modal_deform.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(mesh_poll)

    def _job(self, context):
        return BakeJob(handles.owner(context.object))

    def _status(self):
        job = self.job
        action = "cancelling" if job.cancelling else f"{job.stage} {100 * job.fraction:.0f}%"
        return f"Modal Deform: baking '{job.object_name}': {action}"


class MODAL_DEFORM_OT_clear_basis(bpy.types.Operator):
    """Remove the baked basis from the object (posing needs a new bake)"""

    bl_idname = "modal_deform.clear_basis"
    bl_label = "Clear Basis"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return (
            mesh_poll(cls, context) and handles.owner(context.object).modal_deform.basis is not None
        )

    def execute(self, context):
        storage.clear(handles.owner(context.object))
        return {"FINISHED"}


CLASSES = (MODAL_DEFORM_OT_bake, MODAL_DEFORM_OT_clear_basis)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
