"""Bake: the basis of the active mesh, on a thread with progress and Esc (invoke) or at once (execute)."""
import threading
import time

import bpy

from . import core as mdc
from . import handles, mesh_io, storage


# The bake's stages in order (cpp/reduction/bake.h), for one bar over the whole bake.
STAGES = ("attachment", "hessian", "factorisation", "modes", "third derivatives", "derivative solves",
          "orthonormalisation", "assembly", "ghost")


class BakeJob:
    """One bake of obj's mesh as it is now, run by run() here or on a thread by start().

    The mesh is read on the calling thread; the native bake releases the GIL, so Blender stays
    responsive. cancel() makes the next progress report stop the bake (Cancelled).
    """

    def __init__(self, obj):
        settings = obj.modal_deform
        self.object_name = obj.name
        self.energy = settings.energy
        self.V = mesh_io.positions(obj.data)
        self.F = mesh_io.triangles(obj.data)
        self.fingerprint = storage.fingerprint(obj.data)
        self.options = dict(modes=settings.modes, derivatives=settings.derivatives if self.energy == "SHELLS" else 0,
                            ghost=settings.ghost, energy=self.energy.lower(), bending=settings.bending,
                            membrane=settings.membrane)
        self.stage, self.fraction = "starting", 0.0
        self.basis = self.error = None
        self.seconds = 0.0
        self.cancelling = False
        self._thread = None

    def _progress(self, stage, fraction):
        self.stage, self.fraction = stage, fraction
        return not self.cancelling

    @property
    def overall(self):
        """Fraction of the whole bake done, counting each stage alike (their costs vary by mesh)."""
        if self.stage not in STAGES:
            return 0.0
        return (STAGES.index(self.stage) + self.fraction) / len(STAGES)

    def run(self):
        start = time.perf_counter()
        try:
            self.basis = mdc.bake(self.V, self.F, progress=self._progress, **self.options)
        except Exception as error:  # reported on the main thread (Cancelled included)
            self.error = error
        self.seconds = time.perf_counter() - start

    def start(self):
        self._thread = threading.Thread(target=self.run, name="modal_deform bake", daemon=True)
        self._thread.start()

    def cancel(self):
        self.cancelling = True

    @property
    def done(self):
        return self._thread is None or not self._thread.is_alive()

    def finish(self):
        """Store the basis on the object (main thread). Returns (level, message) for a report."""
        if isinstance(self.error, mdc.Cancelled):
            return "WARNING", "Bake cancelled: nothing changed"
        if self.error is not None:
            return "ERROR", f"Bake failed: {self.error}"
        obj = bpy.data.objects.get(self.object_name)
        if obj is None or obj.type != "MESH" or storage.fingerprint(obj.data) != self.fingerprint:
            return "WARNING", f"'{self.object_name}' changed during the bake: the result was discarded, bake again"
        storage.store(obj, self.basis, self.fingerprint, self.seconds, self.energy)
        basis = self.basis
        message = (f"Baked '{obj.name}' in {self.seconds:.1f} s: {basis.dimension} dimensions, ghost "
                   f"{len(basis.ghost_vertices)} vertices")
        if basis.num_floppy:
            message += (f"; {basis.num_floppy} zero modes besides the rigid motions (flaps at non-manifold edges "
                        f"or vertices) came on top of the modes")
        return "INFO", message


def _mesh_poll(cls, context):
    obj = handles.owner(context.object)
    if obj is None:
        cls.poll_message_set("Select a mesh object (or a controller of one)")
        return False
    if obj.mode != "OBJECT":
        cls.poll_message_set("Switch to Object Mode")
        return False
    if obj.library is not None or obj.data.library is not None:
        cls.poll_message_set("The object is linked from a library")
        return False
    return True


class MODAL_DEFORM_OT_bake(bpy.types.Operator):
    """Compute the deformation basis of the mesh (vibration modes, modal derivatives, ghost) and keep it in \
the file. Esc cancels"""
    bl_idname = "modal_deform.bake"
    bl_label = "Bake"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(_mesh_poll)

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
        return _mesh_poll(cls, context) and handles.owner(context.object).modal_deform.basis is not None

    def execute(self, context):
        storage.clear(handles.owner(context.object))
        return {"FINISHED"}


CLASSES = (MODAL_DEFORM_OT_bake, MODAL_DEFORM_OT_clear_basis)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
