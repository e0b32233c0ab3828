"""Handle list operators: add from the selected vertices (Edit Mode) or a vertex group, remove."""

import bmesh
import bpy
import numpy as np

from . import handles


def _mesh(context):
    obj = handles.owner(context.object)
    return obj if obj is not None and obj.library is None else None


class MODAL_DEFORM_OT_add_handle(bpy.types.Operator):
    """Add a handle. Edit Mode: a vertex group of the selected vertices with an Empty at their centre \
that moves them (like Hook to New Object). Object Mode: a pinned handle on the active vertex group"""

    bl_idname = "modal_deform.add_handle"
    bl_label = "Add Handle"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if _mesh(context) is None:
            cls.poll_message_set("Select a mesh object of this file")
            return False
        if _mesh(context).mode not in {"EDIT", "OBJECT"}:
            cls.poll_message_set("Switch to Edit Mode (select vertices) or Object Mode")
            return False
        return True

    def execute(self, context):
        obj = _mesh(context)
        if obj.mode == "EDIT":
            return self._from_selection(context, obj)
        group = obj.vertex_groups.active
        if group is None:
            self.report(
                {"ERROR"},
                "No vertex group: select vertices in Edit Mode, or add a vertex group first",
            )
            return {"CANCELLED"}
        self._append(obj, group.name, None)
        return {"FINISHED"}

    def _from_selection(self, context, obj):
        bm = bmesh.from_edit_mesh(obj.data)
        layer = (
            bm.verts.layers.deform.verify()
        )  # first: adding the layer invalidates vertex references
        selected = [v for v in bm.verts if v.select]
        if not selected:
            self.report({"ERROR"}, "No vertex selected: select the vertices the handle moves")
            return {"CANCELLED"}
        group = obj.vertex_groups.new(name="Handle")
        for v in selected:
            v[layer][group.index] = 1.0
        bmesh.update_edit_mesh(obj.data)
        centre = np.mean([tuple(v.co) for v in selected], axis=0)
        size = 0.05 * max(np.ptp(np.array(obj.bound_box), axis=0).max(), 1e-6)
        empty = handles.add_controller(context, obj, f"{obj.name} {group.name}", centre, size)
        context.view_layer.update()  # the Empty's world matrix, which the bind reads
        self._append(obj, group.name, empty)
        self.report(
            {"INFO"}, f"Handle '{group.name}': {len(selected)} vertices, moved by '{empty.name}'"
        )
        return {"FINISHED"}

    @staticmethod
    def _append(obj, group_name, controller):
        settings = obj.modal_deform
        item = settings.handles.add()
        item.name = group_name
        item.vertex_group = group_name
        item.controller = controller  # binds (properties._controller_changed)
        settings.active_handle = len(settings.handles) - 1


class MODAL_DEFORM_OT_remove_handle(bpy.types.Operator):
    """Remove the active handle from the list (its vertex group and controller stay)"""

    bl_idname = "modal_deform.remove_handle"
    bl_label = "Remove Handle"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        obj = _mesh(context)
        return obj is not None and 0 <= obj.modal_deform.active_handle < len(
            obj.modal_deform.handles
        )

    def execute(self, context):
        settings = _mesh(context).modal_deform
        settings.handles.remove(settings.active_handle)
        settings.active_handle = min(settings.active_handle, len(settings.handles) - 1)
        return {"FINISHED"}


CLASSES = (MODAL_DEFORM_OT_add_handle, MODAL_DEFORM_OT_remove_handle)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
