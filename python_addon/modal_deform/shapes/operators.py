"""Blend as Shapes's operators: the toggle (baking the shape space first when there is none that
fits, on a thread with progress, Esc cancels), Re-bake, Clear, Keep as Shape Key, and the exports
of a frame range for machines without the add-on (shape keys, a Mesh Cache file)."""

import bpy
import numpy as np

from .. import core as mdc
from .. import handles, mesh_io, storage
from ..jobs import BakeJob
from ..ops_common import FAILURES, JobOperator, mesh_poll
from ..playback import timeline
from ..playback.frame_keys import AnimationJob
from ..playback.operators import ExportMeshCache
from . import blending, keys

#: The name of the key Keep as Shape Key writes (Blender adds ".001" to a second one).
KEPT_KEY = "Blended Shape"


class ShapesJob(BakeJob):
    """The bake of obj's shape space (read on the calling thread): on obj's stored basis when it fits
    the basis key and was baked with Discrete Shells on the whole mesh, else on a basis baked here
    with obj's bake settings (Discrete Shells, no region). finish() stores it and turns Blend as
    Shapes on."""

    thread_name = "modal_deform shape space"

    def __init__(self, obj):
        keys.check(obj)
        if timeline.plays(obj):
            raise ValueError(blending.DYNAMICS_WINS)
        super().__init__(obj)
        settings = obj.modal_deform
        self.V = keys.basis(obj)
        self.names = keys.names(obj)
        self.shapes = keys.shapes(obj, self.V, self.names)
        self.digest = keys.digest(obj, self.names)
        self.options.pop("region")
        self.options.update(energy="shells", derivatives=settings.derivatives)
        self.reused = None
        status = settings.status
        if (
            settings.basis is not None
            and status.energy == "SHELLS"
            and not status.region_group
            and not storage.stale_reason(obj)
        ):
            try:
                basis = storage.load(obj)
            except storage.NotReady:
                basis = None
            if basis is not None and np.array_equal(basis.rest, self.V):
                self.reused = basis
        self.space = None

    @property
    def overall(self):
        return 0.5 if self.reused is not None else super().overall

    def _work(self):
        options = {} if self.reused is not None else self.options
        self.space = mdc.ShapeSpace(
            self.V, self.F, self.shapes, basis=self.reused, progress=self._progress, **options
        )

    def finish(self):
        obj, report = self._finished_object(
            "Shape space bake",
            f"'{self.object_name}' changed during the bake: the result was discarded, bake again",
        )
        if report:
            return report
        try:
            changed = keys.names(obj) != self.names or keys.digest(obj, self.names) != self.digest
        except (KeyError, ValueError):
            changed = True
        if changed:
            return "WARNING", (
                f"The shape keys of '{obj.name}' changed during the bake: the result was "
                f"discarded, bake again"
            )
        blending.store(obj, self.space, self.digest, self.names, self.seconds)
        obj.modal_deform.shapes.enabled = True
        self.written = True
        on = "the object's basis" if self.reused is not None else "a basis baked for it"
        return "INFO", (
            f"Baked the shapes of {len(self.names)} keys of '{obj.name}' in {self.seconds:.1f} s "
            f"({self.space.dimension} dimensions, on {on})"
        )


def shapes_poll(cls, context):
    """A mesh operator's poll, on a mesh with shape keys."""
    if not mesh_poll(cls, context):
        return False
    if handles.owner(context.object).data.shape_keys is None:
        cls.poll_message_set("The mesh has no shape keys")
        return False
    return True


def blend_poll(cls, context):
    """shapes_poll, with Blend as Shapes on."""
    if not shapes_poll(cls, context):
        return False
    if not handles.owner(context.object).modal_deform.shapes.enabled:
        cls.poll_message_set("Turn Blend as Shapes on first")
        return False
    return True


class _BakeShapes(JobOperator):
    def _job(self, context):
        return ShapesJob(handles.owner(context.object))

    def _status(self):
        job = self.job
        action = "cancelling" if job.cancelling else f"{job.stage} {100 * job.overall:.0f}%"
        return f"Modal Deform: baking the shapes of '{job.object_name}': {action}"


class MODAL_DEFORM_OT_blend_as_shapes(_BakeShapes, bpy.types.Operator):
    """Blend the shape keys as shapes: parts that turn between the basis and a key turn in between and \
keep their size. Bakes the keys first when needed (Esc cancels); again: back to Blender's mix"""

    bl_idname = "modal_deform.blend_as_shapes"
    bl_label = "Blend as Shapes"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(shapes_poll)

    def _toggled(self, context):
        """Turn off, or on with the stored space when it fits: the operator's result; None when a
        bake is needed. Refused while Dynamics plays on the object (it would show instead)."""
        obj = handles.owner(context.object)
        settings = obj.modal_deform.shapes
        if settings.enabled:
            settings.enabled = False
            return {"FINISHED"}
        if timeline.plays(obj):
            self.report({"ERROR"}, blending.DYNAMICS_WINS)
            return {"CANCELLED"}
        try:
            blending.ready(obj)
        except storage.NotReady:
            return None
        settings.enabled = True
        return {"FINISHED"}

    def execute(self, context):
        return self._toggled(context) or super().execute(context)

    def invoke(self, context, event):
        return self._toggled(context) or super().invoke(context, event)


class MODAL_DEFORM_OT_bake_shapes(_BakeShapes, bpy.types.Operator):
    """Bake the shape keys as shapes again (after editing a key) and blend them. Esc cancels"""

    bl_idname = "modal_deform.bake_shapes"
    bl_label = "Re-bake Shapes"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(shapes_poll)


class MODAL_DEFORM_OT_clear_shapes(bpy.types.Operator):
    """Forget the baked shapes and show Blender's mix of the shape keys"""

    bl_idname = "modal_deform.clear_shapes"
    bl_label = "Clear Shapes"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return (
            mesh_poll(cls, context)
            and handles.owner(context.object).modal_deform.shapes.space is not None
        )

    def execute(self, context):
        blending.clear(handles.owner(context.object))
        return {"FINISHED"}


class MODAL_DEFORM_OT_keep_blend(bpy.types.Operator):
    """Keep the blend shown as a new shape key (value 0, relative to the basis), which works without the \
add-on"""

    bl_idname = "modal_deform.keep_blend"
    bl_label = "Keep as Shape Key"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(blend_poll)

    def execute(self, context):
        obj = handles.owner(context.object)
        try:
            space = blending.ready(obj)
            co = blending.blend(obj, space, blending.weights(obj))
        except FAILURES as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        reference = obj.data.shape_keys.reference_key
        block = obj.shape_key_add(name=KEPT_KEY, from_mix=False)
        block.relative_key = reference
        block.value = 0.0
        mesh_io.write_shape_key(obj.data, block, co)
        self.report({"INFO"}, f"Kept the blend as the shape key '{block.name}'")
        return {"FINISHED"}


def _frame_range(operator, scene):
    """The operator's frame_start and frame_end, the scene's range where they are not set."""
    start = operator.frame_start if operator.properties.is_property_set("frame_start") else None
    end = operator.frame_end if operator.properties.is_property_set("frame_end") else None
    start = scene.frame_start if start is None else start
    end = scene.frame_end if end is None else end
    if end < start:
        raise ValueError(f"frame range: the end ({end}) is before the start ({start})")
    return range(start, end + 1)


def _blend_at(obj, scene, correction):
    """frame -> #V by 3 float32: the blend at that frame (the scene goes there), or with `correction`
    what a shape key adds to Blender's mix to make it the blend: basis + (blend − mix)."""
    space = blending.ready(obj)

    def positions(frame):
        scene.frame_set(frame)
        w = blending.weights(obj)
        X = blending.blend(obj, space, w)
        if not correction:
            return X
        return (keys.basis(obj) + (X - blending.linear(obj, w))).astype(np.float32)

    return positions


class _FrameRange:
    frame_start: bpy.props.IntProperty(
        name="Start", description="First frame to export (unset: the scene's)"
    )
    frame_end: bpy.props.IntProperty(
        name="End", description="Last frame to export (unset: the scene's)"
    )


class MODAL_DEFORM_OT_export_blend_shape_keys(_FrameRange, JobOperator, bpy.types.Operator):
    """Write the blend of each frame of the range into a shape key keyed to show on its frame only: the \
difference from Blender's mix, so that the mesh plays and renders the blend without the add-on; Blend \
as Shapes is then turned off, as the keys take its place. Esc cancels"""

    bl_idname = "modal_deform.export_blend_shape_keys"
    bl_label = "Export Shape Keys"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(blend_poll)

    def _job(self, context):
        obj = handles.owner(context.object)
        frames = _frame_range(self, context.scene)
        return AnimationJob(
            context, obj, frames, positions=_blend_at(obj, context.scene, correction=True)
        )

    def _status(self):
        return f"Modal Deform: exporting shape keys, frame {self.job.frames_done}/{len(self.job.frames)}"

    def _finish(self):
        result = super()._finish()
        if self.job.written:
            self.job.obj.modal_deform.shapes.enabled = False
        return result


class MODAL_DEFORM_OT_export_blend_mesh_cache(_FrameRange, ExportMeshCache, bpy.types.Operator):
    """Write the blend of each frame of the range into a point-cache file (PC2 or MDD) that Blender's \
Mesh Cache modifier and other packages read, for machines without the add-on"""

    bl_idname = "modal_deform.export_blend_mesh_cache"

    poll = classmethod(blend_poll)

    def _frames(self, obj, scene):
        self.frame_before = scene.frame_current
        return _frame_range(self, scene)

    def _positions(self, obj, scene):
        return _blend_at(obj, scene, correction=False)

    def execute(self, context):
        try:
            return super().execute(context)
        finally:
            if getattr(self, "frame_before", None) is not None:
                context.scene.frame_set(self.frame_before)


CLASSES = (
    MODAL_DEFORM_OT_blend_as_shapes,
    MODAL_DEFORM_OT_bake_shapes,
    MODAL_DEFORM_OT_clear_shapes,
    MODAL_DEFORM_OT_keep_blend,
    MODAL_DEFORM_OT_export_blend_shape_keys,
    MODAL_DEFORM_OT_export_blend_mesh_cache,
)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
