"""The per-frame cache's operators: bake it (a frame per timer tick, progress, Esc restores the cache
as it was), free it, and export it for machines without the add-on (shape keys, or a PC2 / MDD file
for Blender's Mesh Cache modifier)."""

import os

import bpy
import numpy as np

from .. import handles
from ..jobs import FrameJob
from ..ops_common import FAILURES, JobOperator, mesh_poll
from . import frame_cache, point_cache, rig, timeline
from .frame_keys import AnimationJob


class CacheJob(FrameJob):
    """Computes the cache of obj from its first frame to `end`, a frame per tick(), in a new
    datablock; finish() keeps it in place of the old cache, cancel() (or a failure) puts the old one
    back. Static (dynamics off): the frames from `start`; dynamics on: from the dynamics' start."""

    def __init__(self, context, obj, start, end):
        self.obj, self.scene = obj, context.scene
        dynamics = obj.modal_deform.dynamics
        if dynamics.enabled:
            start = dynamics.frame_start
        if end < start:
            raise ValueError(f"frame range: the end ({end}) is before the start ({start})")
        super().__init__(range(start, end + 1))
        self.player = timeline.player(
            obj, self.scene
        )  # raises for the artist before anything changes
        self.frame_before = self.scene.frame_current
        self.old = dynamics.cache
        dynamics.cache = None  # kept (0 users) until finish() or cancel()
        self.cache = frame_cache.create(obj, self.scene, start)

    def _frame(self, frame):
        timeline.set_frame(self.scene, frame)
        timeline.fill(self.obj, self.scene, self.cache, frame, self.player)

    def finish(self):
        if self.cancelling:
            return "WARNING", "Cache bake cancelled: the cache is as it was"
        if self.error is not None:
            return "ERROR", f"Cache bake failed: {self.error}"
        self._drop(self.old)
        timeline.set_frame(self.scene, self.frame_before)
        timeline.show(self.obj, self.scene)
        self.written = True
        what = "simulation" if self.cache.kind == "DYNAMIC" else "animation"
        return "INFO", (
            f"Cached the {what} of {len(self.frames)} frames ({self.frames[0]} to {self.frames[-1]}) in "
            f"{self.cache.nbytes() / 1024:.1f} KB"
        )

    def _take_back(self):
        dynamics = self.obj.modal_deform.dynamics
        new = dynamics.cache
        dynamics.cache = self.old
        self._drop(new)
        self.scene.frame_set(self.frame_before)

    @staticmethod
    def _drop(block):
        if block is not None and block.users == 0:
            bpy.data.palettes.remove(block)


def cache_poll(cls, context):
    """A mesh operator's poll, with a cache to act on."""
    if not mesh_poll(cls, context):
        return False
    if handles.owner(context.object).modal_deform.dynamics.cache is None:
        cls.poll_message_set("No cache: play the timeline with Dynamics on, or Bake")
        return False
    return True


def cached_frames(obj):
    """The frames of obj's cache, refused when there are none."""
    cache = frame_cache.get(obj)
    if cache is None or not len(cache):
        raise ValueError(f"'{obj.name}' has no cached frames: play the timeline or Bake first")
    return range(cache.start, cache.end + 1)


def cached_positions(obj, scene, space="REST"):
    """frame -> #V by 3 float32 positions of obj's cached frame (the mesh must still fit its basis).
    On a rig, `space`: "REST", the mesh before its Armature modifier (the base mesh plus the
    offset), or "SKINNED", after it (linear blend skinning at the frame's cached rig, in the mesh
    object's space, without the shape keys)."""
    cache = frame_cache.get(obj)
    player = timeline.player(obj, scene)
    out = np.empty((len(obj.data.vertices), 3), np.float32)
    skinned = space == "SKINNED" and player.rig is not None

    def positions(frame):
        player.positions(cache.state(frame)[0], out)
        if skinned:
            rig_frame = cache.array("rig")[cache.row(frame)].reshape(-1, 4, 4)
            out[...] = player.rig.skinned(out, rig_frame)
        return out

    return positions


class MODAL_DEFORM_OT_free_cache(bpy.types.Operator):
    """Forget the cached frames (the animation or simulation computes again when played)"""

    bl_idname = "modal_deform.free_cache"
    bl_label = "Free Cache"
    bl_options = {"REGISTER", "UNDO"}

    poll = classmethod(cache_poll)

    def execute(self, context):
        timeline.free(handles.owner(context.object))
        return {"FINISHED"}


#: Where a rig's frames are exported (cached_positions).
SPACES = (
    (
        "REST",
        "Rest Space",
        "The mesh before its Armature modifier: the rig skins the export as it skins the mesh",
    ),
    (
        "SKINNED",
        "Skinned",
        "The mesh after its Armature modifier (linear blend skinning, shape keys left out): turn the "
        "Armature modifier off to play it",
    ),
)


class MODAL_DEFORM_OT_fill_attach(bpy.types.Operator):
    """Fill the Attach group (made when there is none) with the vertices near the deforming bones of the mesh's Armature modifier, at rest: the vertices the rig holds, which you can then paint"""

    bl_idname = "modal_deform.fill_attach"
    bl_label = "Fill Attach from Armature"
    bl_options = {"REGISTER", "UNDO"}

    reach: bpy.props.FloatProperty(
        name="Reach",
        default=rig.ATTACH_REACH,
        min=0.0,
        soft_max=2.0,
        description="How far from a bone a vertex is attached, as a fraction of the bone's length",
    )

    poll = classmethod(mesh_poll)

    def execute(self, context):
        obj = handles.owner(context.object)
        try:
            count = rig.fill_attach(obj, self.reach)
        except rig.RigError as error:
            self.report({"ERROR"}, str(error))
            return {"CANCELLED"}
        group = obj.modal_deform.dynamics.attach_group
        if not count:
            self.report(
                {"WARNING"},
                f"No vertex within {self.reach:g} bone lengths of a bone: '{group}' is empty",
            )
        else:
            self.report({"INFO"}, f"Attached {count} vertices near the bones in '{group}'")
        return {"FINISHED"}


class MODAL_DEFORM_OT_export_shape_keys(JobOperator, bpy.types.Operator):
    """Write the cached frames into shape keys, one per frame keyed to show on its frame only, that play \
back and render without the add-on; the cache is then freed, as the keys take its place. Esc cancels"""

    bl_idname = "modal_deform.export_shape_keys"
    bl_label = "Export Shape Keys"
    bl_options = {"REGISTER", "UNDO"}

    space: bpy.props.EnumProperty(name="Space", items=SPACES, options={"SKIP_SAVE"})

    poll = classmethod(cache_poll)

    def _job(self, context):
        obj = handles.owner(context.object)
        positions = cached_positions(obj, context.scene, self.space)
        return AnimationJob(context, obj, cached_frames(obj), positions=positions)

    def _status(self):
        return f"Modal Deform: exporting shape keys, frame {self.job.frames_done}/{len(self.job.frames)}"

    def _finish(self):
        result = super()._finish()
        if self.job.written:
            timeline.free(self.job.obj)
            if rig.follows(self.job.obj):  # the keys carry the offset the rig's playback added
                self.job.obj.modal_deform.dynamics.enabled = False
        return result


class ExportMeshCache:
    """An export to a point-cache file: the file's path and format, the file browser, the writing.
    What is exported comes from _frames(obj, scene) and _positions(obj, scene) (frame -> positions,
    called once per frame in order): the cached frames (MODAL_DEFORM_OT_export_mesh_cache), or
    others (shapes.operators)."""

    bl_label = "Export Mesh Cache"
    bl_options = {"REGISTER"}

    filepath: bpy.props.StringProperty(subtype="FILE_PATH", options={"SKIP_SAVE"})
    file_format: bpy.props.EnumProperty(
        name="Format",
        default="PC2",
        items=(
            (
                "PC2",
                "PC2",
                "Point Cache 2 (3ds Max, Blender's Mesh Cache): positions with the first frame",
            ),
            (
                "MDD",
                "MDD",
                "LightWave's MDD (Blender's Mesh Cache): positions with the time of each frame",
            ),
        ),
    )

    def invoke(self, context, event):
        obj = handles.owner(context.object)
        if not self.filepath:
            blend = bpy.data.filepath
            folder = os.path.dirname(blend) if blend else os.path.expanduser("~")
            self.filepath = os.path.join(
                folder, f"{bpy.path.clean_name(obj.name)}.{self.file_format.lower()}"
            )
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        obj = handles.owner(context.object)
        scene = context.scene
        path = bpy.path.abspath(self.filepath)
        if not path:
            self.report({"ERROR"}, "No file to write: choose a file path")
            return {"CANCELLED"}
        try:
            frames = self._frames(obj, scene)
            point_cache.write(
                path,
                self.file_format,
                len(obj.data.vertices),
                frames,
                scene.render.fps / scene.render.fps_base,
                self._positions(obj, scene),
            )
        except (OSError, *FAILURES) as error:
            self.report({"ERROR"}, f"Export failed: {error}")
            return {"CANCELLED"}
        self.report(
            {"INFO"},
            f"Wrote {len(frames)} frames ({frames[0]} to {frames[-1]}) to {path}: add a Mesh Cache "
            f"modifier with Frame Start {frames[0]} to play it",
        )
        return {"FINISHED"}


class MODAL_DEFORM_OT_export_mesh_cache(ExportMeshCache, bpy.types.Operator):
    """Write the cached frames into a point-cache file (PC2 or MDD) that Blender's Mesh Cache modifier \
and other packages read, for machines without the add-on"""

    bl_idname = "modal_deform.export_mesh_cache"

    space: bpy.props.EnumProperty(name="Space", items=SPACES, options={"SKIP_SAVE"})

    poll = classmethod(cache_poll)

    def _frames(self, obj, scene):
        return cached_frames(obj)

    def _positions(self, obj, scene):
        return cached_positions(obj, scene, self.space)


CLASSES = (
    MODAL_DEFORM_OT_fill_attach,
    MODAL_DEFORM_OT_free_cache,
    MODAL_DEFORM_OT_export_shape_keys,
    MODAL_DEFORM_OT_export_mesh_cache,
)


register, unregister = bpy.utils.register_classes_factory(CLASSES)
