"""Blend as Shapes in the interface: a panel in the sidebar (View3D > N > Modal Deform > Blend as
Shapes) with the toggle, the bake's status, what keeps the blend from showing, Keep as Shape Key and
the exports; and the toggle with its status line under the list of the Shape Keys panel (Object
Data properties)."""

import bpy

from .. import handles
from ..ui import _Panel, wrapped_label
from . import blending


def draw_status(layout, context, obj):
    """The toggle and one line per thing the artist should know (stale, a problem, a note)."""
    settings = obj.modal_deform.shapes
    layout.operator(
        "modal_deform.blend_as_shapes",
        text="Blend as Shapes",
        icon="SHAPEKEY_DATA",
        depress=settings.enabled,
    )
    if settings.space is not None:
        reason = blending.stale_reason(obj)
        if reason:
            column = layout.column()
            column.alert = True
            wrapped_label(column, context, f"Stale ({reason}): re-bake", icon="ERROR")
            column.operator("modal_deform.bake_shapes", text="Re-bake", icon="RENDER_STILL")
    if not settings.enabled:
        return
    problem = blending.problems.get(obj.name)
    if problem:
        column = layout.column()
        column.alert = problem != blending.DYNAMICS_WINS
        wrapped_label(column, context, problem, icon="ERROR")
    note = blending.notes.get(obj.name)
    if note:
        wrapped_label(layout, context, note, icon="INFO")


class VIEW3D_PT_modal_deform_shapes(_Panel, bpy.types.Panel):
    bl_label = "Blend as Shapes"
    bl_parent_id = "VIEW3D_PT_modal_deform"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        obj = handles.owner(context.object)
        layout = self.layout
        if obj.data.shape_keys is None:
            wrapped_label(layout, context, "Add shape keys to blend them as shapes", icon="INFO")
            return
        draw_status(layout, context, obj)
        settings = obj.modal_deform.shapes
        if settings.space is not None:
            box = layout.box()
            lines = box.column(align=True)
            count = len(blending.space_names(obj))
            lines.label(text=f"{count} keys, {settings.dimension} dimensions", icon="SHAPEKEY_DATA")
            lines.label(text=f"Baked {settings.baked_at}", icon="TIME")
            lines.label(text=f"in {settings.seconds:.1f} s", icon="BLANK1")
            row = layout.row(align=True)
            row.operator("modal_deform.bake_shapes", text="Re-bake", icon="RENDER_STILL")
            row.operator("modal_deform.clear_shapes", text="", icon="X")
        column = layout.column(align=True)
        column.operator("modal_deform.keep_blend", icon="ADD")
        column.operator(
            "modal_deform.export_blend_shape_keys", text="Export Shape Keys", icon="SHAPEKEY_DATA"
        )
        column.operator(
            "modal_deform.export_blend_mesh_cache", text="Export Mesh Cache", icon="EXPORT"
        )


def _draw_in_shape_keys(self, context):
    obj = context.object
    if obj is None or obj.type != "MESH" or obj.data.shape_keys is None:
        return
    draw_status(self.layout, context, obj)


CLASSES = (VIEW3D_PT_modal_deform_shapes,)
_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    bpy.types.DATA_PT_shape_keys.append(_draw_in_shape_keys)


def unregister():
    bpy.types.DATA_PT_shape_keys.remove(_draw_in_shape_keys)
    _unregister_classes()
