"""Crash and undo recovery of the interactive pose. A file saved mid-pose first moves the pose into
the "Modal Deform" shape key (save_pre); after undo, redo or a file loaded, the pose under way ends
and meshes written mid-pose (they carry a display's marks, displays.py) are repaired (recover).
"""

import bpy

from .. import app_handlers, mesh_io, ops_common, storage
from . import displays, posing


def recover():
    """Meshes written mid-pose by a PositionsDisplay or a StandInDisplay (an undo step of a
    controller's move, autosave, a crash file, a file saved by a path without save handlers) hold
    the pose in their positions: their rest comes back (from the stored basis, or the artist's mesh
    in place of the stand-in) and the pose goes into the "Modal Deform" shape key, as if the pose
    had been kept. Meshes without a usable basis keep the flag and are reported."""
    for obj in bpy.data.objects:
        mesh = obj.data
        if obj.type != "MESH" or mesh.library is not None or ops_common.is_posing(obj):
            continue
        if mesh.get(displays.STAND_IN_OF) is not None:
            pose = mesh_io.vertex_positions(mesh).copy()
            displays.put_mesh_back(obj, mesh)
            mesh_io.write_shape_key(obj.data, posing.pose_key(obj)[0], pose)
        elif mesh.get(displays.POSING_FLAG) is not None:
            _recover_positions(obj)


def _recover_positions(obj):
    """recover() for a mesh posed by a PositionsDisplay."""
    mesh = obj.data
    try:
        rest = storage.load(obj).rest
    except storage.NotReady as error:
        print(f"Modal Deform: '{obj.name}' was saved while posing and cannot be repaired: {error}")
        return
    if len(rest) != len(mesh.vertices):
        print(
            f"Modal Deform: '{obj.name}' was saved while posing and its mesh no longer fits its basis"
        )
        return
    pose = mesh_io.vertex_positions(mesh).copy()
    displays.put_rest_back(mesh, rest)
    mesh_io.write_shape_key(mesh, posing.pose_key(obj)[0], pose)


def _keep_before_save(*args):
    """A file saved mid-pose holds the rest mesh and the pose in its shape key: a pose shown in the
    vertex positions moves into the key first, and the pose goes on there."""
    if ops_common.running is not None:
        try:
            ops_common.running.keep_in_shape_key()
        except ReferenceError:  # its object went away: the pose ends at its next event
            pass


def _recover_after_undo_or_load(*args):
    """Undo, redo or a file loaded replaced the data: a pose under way ends (its next event) and
    meshes written mid-pose are repaired (recover)."""
    if ops_common.running is not None:
        ops_common.running.request_end("CANCEL")
    recover()


_HANDLERS = (
    ("save_pre", _keep_before_save),
    ("undo_post", _recover_after_undo_or_load),
    ("redo_post", _recover_after_undo_or_load),
    ("load_post", _recover_after_undo_or_load),
)


def register():
    app_handlers.register(_HANDLERS)


def unregister():
    app_handlers.unregister(_HANDLERS)
