"""Mode preview: the mesh displaced along one basis vector (the paper's Fig. 1/6), in a shape key of its own."""

import bpy
import numpy as np

from . import handles, mesh_io, storage
from .ops_common import mesh_poll

PREVIEW_KEY = "Modal Deform Preview"


def showing(obj):
    keys = obj.data.shape_keys
    return keys is not None and PREVIEW_KEY in keys.key_blocks


def describe(status, index):
    """What basis vector `index` is, in words."""
    if index < status.num_rigid:
        return "rigid motion"
    if index < status.num_rigid + status.num_floppy:
        return "zero mode (floppy)"
    if index < status.num_modes:
        return "vibration mode"
    return "modal derivative"


def displaced(basis, index, amplitude):
    """#V by 3 float32: rest positions plus basis vector `index` scaled so that the largest vertex
    displacement is `amplitude` times the longest bounding-box edge."""
    u = basis.fine_vectors([index]).reshape(-1, 3).astype(np.float64)
    largest = np.sqrt((u * u).sum(axis=1)).max()
    size = np.ptp(basis.rest, axis=0).max()
    scale = amplitude * size / largest if largest > 0 else 0.0
    return (basis.rest + scale * u).astype(np.float32)


def refresh(obj):
    """Redraw the preview key for the current vector and amplitude (nothing when it is off or the
    basis cannot be used: the panel says why)."""
    if not showing(obj):
        return
    settings = obj.modal_deform
    try:
        basis = storage.ready_basis(obj)
    except storage.NotReady:
        return
    index = min(settings.preview_vector, basis.dimension - 1)
    block = obj.data.shape_keys.key_blocks[PREVIEW_KEY]
    mesh_io.write_shape_key(obj.data, block, displaced(basis, index, settings.preview_amplitude))


class MODAL_DEFORM_OT_preview_mode(bpy.types.Operator):
    """Show or hide the mesh deformed along one basis vector, to judge a bake at a glance"""

    bl_idname = "modal_deform.preview_mode"
    bl_label = "Preview Mode"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(mesh_poll)

    def execute(self, context):
        obj = handles.owner(context.object)
        if showing(obj):
            mesh_io.remove_shape_keys(obj, [PREVIEW_KEY])
            return {"FINISHED"}
        try:
            storage.ready_basis(obj)
        except storage.NotReady as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        block, _ = mesh_io.shape_key(obj, PREVIEW_KEY)
        block.value = 1.0
        refresh(obj)
        return {"FINISHED"}


CLASSES = (MODAL_DEFORM_OT_preview_mode,)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
