"""The sidebar (View3D > N > Modal Deform): bake settings and status, handles, pose, animation, dynamics,
preview.

Every label fits the sidebar at its default width: short property labels beside their fields
(use_property_split), and sentences wrapped to the sidebar's width (wrapped_label)."""

import textwrap

import bpy

from . import handles, ops_common, ops_preview, storage
from .playback import frame_cache, timeline

# Width of a character of the interface font at scale 1, in pixels, for wrapping text (a little above
# the mean of Blender's font, so a wrapped line is never cut).
CHARACTER_WIDTH = 7.0


def wrapped_label(layout, context, text, icon="NONE"):
    """text as labels of as many lines as the region's width needs, the icon on the first."""
    scale = context.preferences.system.ui_scale
    characters = max(12, int((context.region.width - 50 * scale) / (CHARACTER_WIDTH * scale)))
    column = layout.column(align=True)
    for i, line in enumerate(textwrap.wrap(text, characters)):
        column.label(text=line, icon=icon if i == 0 else "BLANK1" if icon != "NONE" else "NONE")


class MODAL_DEFORM_UL_handles(bpy.types.UIList):
    """A row per handle: "group → controller" (or "group → armature: bone"), the vertex group it moves
    and the controller that moves it, or "group (pinned)"."""

    def draw_item(
        self, context, layout, data, item, icon, active_data, active_property, index=0, flt_flag=0
    ):
        if item.controller is not None:
            bone = f": {item.bone}" if item.bone and item.controller.type == "ARMATURE" else ""
            layout.label(text=f"{item.vertex_group} \u2192 {item.controller.name}{bone}")
        else:
            layout.label(text=f"{item.vertex_group} (pinned)")


def stale_reason(obj):
    """storage.stale_reason from the cache, or "" while obj is posed: the pose may be in its
    positions, and each update would make the panels hash the whole mesh again."""
    return "" if ops_common.is_posing(obj) else storage.stale_reason(obj, cached=True)


class _Panel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Modal Deform"

    @classmethod
    def poll(cls, context):
        return handles.owner(context.object) is not None


class VIEW3D_PT_modal_deform(_Panel, bpy.types.Panel):
    bl_label = "Modal Deform"

    def draw(self, context):
        obj = handles.owner(context.object)
        settings = obj.modal_deform
        layout = self.layout
        if settings.basis is None:
            wrapped_label(
                layout, context, "Not baked: set up the basis below, then Bake", icon="INFO"
            )
            return
        reason = stale_reason(obj)
        if reason:
            layout.alert = True
            wrapped_label(
                layout, context, f"Mesh changed since the bake ({reason}): re-bake", icon="ERROR"
            )
        else:
            layout.label(text="Ready to pose", icon="CHECKMARK")


class VIEW3D_PT_modal_deform_bake(_Panel, bpy.types.Panel):
    bl_label = "Basis"
    bl_parent_id = "VIEW3D_PT_modal_deform"

    def draw(self, context):
        obj = handles.owner(context.object)
        settings = obj.modal_deform
        layout = self.layout
        layout.use_property_split = True
        layout.use_property_decorate = False
        column = layout.column()
        column.prop(settings, "energy")
        column.prop(settings, "modes")
        row = column.row()
        row.enabled = settings.energy == "SHELLS"
        row.prop(settings, "derivatives")
        column.prop(settings, "ghost")
        dense = column.column(align=True)
        dense.prop(settings, "proxy_above")
        row = dense.row()
        row.enabled = settings.proxy_above > 0
        row.prop(settings, "proxy")
        shells = column.column(align=True)
        shells.enabled = settings.energy == "SHELLS"
        shells.prop(settings, "bending")
        shells.prop(settings, "membrane")
        # Laid out as Cloth's stiffness group: the group, then its Max.
        painted = column.column(align=True)
        painted.prop_search(settings, "stiffness_group", obj, "vertex_groups", text="Stiffness")
        row = painted.row()
        row.enabled = bool(settings.stiffness_group)
        row.prop(settings, "max_stiffness", text="Max")
        column.prop_search(settings, "region_group", obj, "vertex_groups", text="Region")

        box = layout.box()
        if settings.basis is None:
            box.label(text="Not baked", icon="INFO")
        else:
            status = settings.status
            lines = box.column(align=True)
            lines.label(
                text=f"{status.dimension} dimensions ({status.energy.title()})",
                icon="OUTLINER_DATA_LIGHTPROBE",
            )
            lines.label(
                text=f"{status.num_modes} modes, {status.num_derivatives} derivatives",
                icon="BLANK1",
            )
            lines.label(text=f"Ghost: {status.ghost_vertices:,} vertices", icon="BLANK1")
            if status.proxy_vertices:
                lines.label(text=f"Proxy: {status.proxy_vertices:,} vertices", icon="BLANK1")
            lines.label(text=f"Baked {status.baked_at}", icon="TIME")
            lines.label(text=f"in {status.seconds:.1f} s", icon="BLANK1")
            if status.num_floppy:
                wrapped_label(
                    box,
                    context,
                    f"{status.num_floppy} floppy modes: parts joined at a vertex",
                    icon="INFO",
                )
            reason = stale_reason(obj)
            if reason:
                row = box.row()
                row.alert = True
                wrapped_label(row, context, f"Stale ({reason}): re-bake", icon="ERROR")
        row = layout.row(align=True)
        row.operator(
            "modal_deform.bake", text="Re-bake" if settings.basis else "Bake", icon="RENDER_STILL"
        )
        row.operator("modal_deform.clear_basis", text="", icon="X")


class VIEW3D_PT_modal_deform_handles(_Panel, bpy.types.Panel):
    bl_label = "Handles"
    bl_parent_id = "VIEW3D_PT_modal_deform"

    def draw(self, context):
        obj = handles.owner(context.object)
        settings = obj.modal_deform
        layout = self.layout
        # The list spans the sidebar (its buttons below it) so that a row has room for both names.
        layout.template_list(
            "MODAL_DEFORM_UL_handles", "", settings, "handles", settings, "active_handle", rows=3
        )
        row = layout.row(align=True)
        row.operator("modal_deform.add_handle", icon="ADD")
        row.operator("modal_deform.remove_handle", text="", icon="REMOVE")
        if 0 <= settings.active_handle < len(settings.handles):
            item = settings.handles[settings.active_handle]
            column = layout.column()
            column.use_property_split = True
            column.use_property_decorate = False
            column.prop_search(item, "vertex_group", obj, "vertex_groups", text="Group")
            column.prop(item, "controller")
            controller = item.controller
            if controller is not None and controller.type == "ARMATURE":
                column.prop_search(item, "bone", controller.data, "bones", text="Bone")
            column.prop(item, "weight")
            text, is_error = handles.notice(obj, item, context.scene)
            if text:
                column = layout.column()
                column.alert = is_error
                wrapped_label(column, context, text, icon="ERROR" if is_error else "INFO")
        layout.use_property_split = True
        layout.use_property_decorate = False
        layout.prop(settings, "stiffness")


class VIEW3D_PT_modal_deform_pose(_Panel, bpy.types.Panel):
    bl_label = "Pose"
    bl_parent_id = "VIEW3D_PT_modal_deform"

    def draw(self, context):
        settings = handles.owner(context.object).modal_deform
        layout = self.layout
        column = layout.column()
        column.use_property_split = True
        column.use_property_decorate = False
        column.prop(settings, "budget")
        row = layout.row(align=True)
        row.operator("modal_deform.pose", icon="PLAY")
        row.operator("modal_deform.solve", icon="CHECKMARK")
        row.operator("modal_deform.refine", icon="SHADERFX")
        layout.operator("modal_deform.reset", icon="LOOP_BACK")
        column = layout.column(align=True)
        column.operator("modal_deform.bake_animation", icon="RENDER_ANIMATION")
        column.operator(
            "modal_deform.bake_animation", text="Bake Refined Animation", icon="SHADERFX"
        ).refine = True


class VIEW3D_PT_modal_deform_preview(_Panel, bpy.types.Panel):
    bl_label = "Mode Preview"
    bl_parent_id = "VIEW3D_PT_modal_deform"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        obj = handles.owner(context.object)
        settings = obj.modal_deform
        layout = self.layout
        column = layout.column()
        column.use_property_split = True
        column.use_property_decorate = False
        column.prop(settings, "preview_vector")
        column.prop(settings, "preview_amplitude")
        status = settings.status
        if settings.basis is not None:
            index = min(settings.preview_vector, status.dimension - 1)
            wrapped_label(
                layout,
                context,
                f"Vector {index} of {status.dimension}: {ops_preview.describe(status, index)}",
            )
        showing = ops_preview.showing(obj)
        layout.operator(
            "modal_deform.preview_mode",
            text="Hide Preview" if showing else "Show Preview",
            icon="HIDE_OFF" if showing else "HIDE_ON",
            depress=showing,
        )


# Dynamics and the per-frame cache.
class VIEW3D_PT_modal_deform_dynamics(_Panel, bpy.types.Panel):
    bl_label = "Dynamics"
    bl_parent_id = "VIEW3D_PT_modal_deform"

    def draw_header(self, context):
        self.layout.prop(handles.owner(context.object).modal_deform.dynamics, "enabled", text="")

    def draw(self, context):
        obj = handles.owner(context.object)
        dynamics = obj.modal_deform.dynamics
        layout = self.layout
        column = layout.column()
        column.use_property_split = True
        column.use_property_decorate = False
        column.active = dynamics.enabled
        column.prop(dynamics, "period")
        column.prop(dynamics, "damping")
        column.prop(dynamics, "substeps")
        column.prop(dynamics, "frame_start")
        _draw_rig(layout, context, obj)
        box = layout.box()
        try:
            cache = frame_cache.get(obj)
        except ValueError as error:
            cache, problem = None, str(error)
        else:
            problem = timeline.problems.get(obj.name)
        if cache is None or not len(cache):
            wrapped_label(box, context, "Cache empty: play or Bake", icon="INFO")
        else:
            what = "Simulation" if cache.kind == "DYNAMIC" else "Animation"
            box.label(text=f"{what}: frames {cache.start}-{cache.end}", icon="FILE_CACHE")
            box.label(text=f"{cache.nbytes() / 1024:.1f} KB in the file")
        if problem:
            column = box.column()
            column.alert = True
            wrapped_label(column, context, problem, icon="ERROR")
        row = layout.row(align=True)
        row.operator("modal_deform.bake_animation", text="Bake", icon="RENDER_ANIMATION")
        row.operator("modal_deform.free_cache", text="Free", icon="TRASH")
        column = layout.column(align=True)
        column.operator(
            "modal_deform.export_shape_keys", text="Export Shape Keys", icon="SHAPEKEY_DATA"
        )
        column.operator("modal_deform.export_mesh_cache", text="Export Mesh Cache", icon="EXPORT")


def _draw_rig(layout, context, obj):
    """Follow Rig's settings in the Dynamics panel: the switch, the Attach group and its fill, and
    what the rig's Player warns of (playback/rig.py)."""
    dynamics = obj.modal_deform.dynamics
    column = layout.column()
    column.use_property_split = True
    column.use_property_decorate = False
    column.active = dynamics.enabled
    column.prop(dynamics, "follow_rig")
    if not dynamics.follow_rig:
        return
    row = column.row(align=True)
    row.prop_search(dynamics, "attach_group", obj, "vertex_groups", text="Attach")
    row.operator("modal_deform.fill_attach", text="", icon="BONE_DATA")
    for text in timeline.rig_warnings(obj):
        wrapped_label(layout, context, text, icon="INFO")
    row = layout.row(align=True)  # the buttons below the box export in rest space
    row.label(text="Export Skinned:")
    row.operator("modal_deform.export_shape_keys", text="", icon="SHAPEKEY_DATA").space = "SKINNED"
    row.operator("modal_deform.export_mesh_cache", text="", icon="EXPORT").space = "SKINNED"


CLASSES = (
    MODAL_DEFORM_UL_handles,
    VIEW3D_PT_modal_deform,
    VIEW3D_PT_modal_deform_bake,
    VIEW3D_PT_modal_deform_handles,
    VIEW3D_PT_modal_deform_pose,
    VIEW3D_PT_modal_deform_dynamics,
    VIEW3D_PT_modal_deform_preview,
)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
