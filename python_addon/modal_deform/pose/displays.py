"""Where the interactive pose shows the pose while it runs: a display.

The vertex positions of a mesh without shape keys (PositionsDisplay), those of a copy without shape
keys standing in for a mesh whose only key that moves it is the "Modal Deform" one (StandInDisplay:
a mesh posed before), which Blender both evaluates without blending shape keys, or else the "Modal
Deform" shape key (ShapeKeyDisplay). Each offers array() (where the pose is written), shows_pose(),
and ends with the pose in the shape key (keep) or the mesh as it was (restore). The marks a display
leaves on a mesh (POSING_FLAG, STAND_IN_OF) let recovery.py repair a mesh written mid-pose.
"""

import bpy
import numpy as np

from .. import mesh_io
from . import posing

#: A mesh ID property: while it is set, the mesh's positions hold a pose and its rest is the
#: stored basis's. A file or undo step written mid-pose carries it, and recovery.py repairs them.
POSING_FLAG = "modal_deform_posing"
#: A mesh ID property of a stand-in (StandInDisplay): the artist's mesh it stands in for. An ID
#: property is a user, so that mesh is saved with a file written mid-pose, and recovery.py puts it back.
STAND_IN_OF = "modal_deform_stand_in_of"


class ShapeKeyState:
    """What the "Modal Deform" shape key of obj looks like now, to put it back exactly (Esc):
    whether the mesh had shape keys, the key's positions, value and mute, the active key and solo
    display."""

    def __init__(self, obj):
        self.obj, self.name = obj, posing.POSE_KEY
        keys = obj.data.shape_keys
        block = keys.key_blocks.get(posing.POSE_KEY) if keys else None
        self.co = None
        if block is not None:
            self.co = np.empty(3 * len(block.data), np.float32)
            block.data.foreach_get("co", self.co)
            self.value, self.mute = block.value, block.mute
        self.active_index = obj.active_shape_key_index
        self.show_only = obj.show_only_shape_key
        self.created = []

    def ensure(self):
        """The key, created if needed (posing.pose_key), shown at value 1."""
        block, self.created = posing.pose_key(self.obj)
        return block

    def restore(self):
        obj = self.obj
        mesh_io.remove_shape_keys(obj, self.created)
        if self.co is not None:
            block = obj.data.shape_keys.key_blocks[self.name]
            mesh_io.write_shape_key(obj.data, block, self.co)
            block.value, block.mute = self.value, self.mute
        obj.active_shape_key_index = self.active_index
        obj.show_only_shape_key = self.show_only
        obj.data.update()


def display(obj):
    """Where the interactive pose shows the pose of obj: the vertex positions of a mesh without
    shape keys, a stand-in's when only the "Modal Deform" key moves the mesh, else that key. A frame
    playback shows goes first (it would hide the pose)."""
    posing.uncover(obj)
    if obj.data.shape_keys is None:
        return PositionsDisplay(obj)
    return StandInDisplay(obj) if only_pose_key_moves(obj, obj.data) else ShapeKeyDisplay(obj)


def only_pose_key_moves(obj, mesh):
    """Whether what Blender shows of obj with `mesh` (which has shape keys) is the reference key
    moved by the "Modal Deform" key alone: relative keys, no key shown alone, the mesh used by obj
    only (a stand-in shows the pose on obj only), the pose key relative to the reference key and not
    limited to a vertex group, every other key muted or at 0."""
    keys = mesh.shape_keys
    if not keys.use_relative or obj.show_only_shape_key or mesh.users - mesh.use_fake_user != 1:
        return False
    for block in keys.key_blocks:
        if block.name == posing.POSE_KEY:
            if block.relative_key != keys.reference_key or block.vertex_group:
                return False
        elif block != keys.reference_key and not block.mute and block.value != 0.0:
            return False
    return True


class ShapeKeyDisplay:
    """The pose in the "Modal Deform" shape key (created if needed, at value 1) every update."""

    def __init__(self, obj):
        self.obj = obj
        self.state = ShapeKeyState(obj)
        self.name = self.state.ensure().name

    def array(self):
        mesh = self.obj.data
        return mesh_io.shape_key_co(mesh, mesh.shape_keys.key_blocks[self.name])

    def shows_pose(self):
        return True

    def keep(self, pose):
        """The pose stays in the key, where it is; returns the display that shows it from now on."""
        return self

    def restore(self):
        self.state.restore()


class _TransientDisplay:
    """A display that shows the pose where no result is kept (the vertex positions) and hands it to
    the "Modal Deform" shape key when kept."""

    def keep(self, pose):
        """The mesh as it was, then the pose into the "Modal Deform" shape key; returns the
        ShapeKeyDisplay that shows it from now on. Edit Mode and Sculpt Mode take the mesh's
        positions for their own copy when entered: left for Object Mode first, and entered again
        after, they take the rest and the key."""
        mode = self.obj.mode
        if mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        self.restore()
        shown = ShapeKeyDisplay(self.obj)
        pose.write(shown.array())
        if mode != "OBJECT":
            bpy.ops.object.mode_set(mode=mode)
        return shown


class PositionsDisplay(_TransientDisplay):
    """The pose in the vertex positions of a mesh without shape keys: with no shape keys to blend,
    Blender evaluates a dense mesh many times faster (bench/results/bpy_pose.json, "evaluate" of
    "positions" against "shape_key").
    The rest positions are kept to put back; the mesh carries POSING_FLAG meanwhile, so a file or
    undo step written mid-pose is repaired (recovery.recover) instead of taking the pose for the rest."""

    def __init__(self, obj):
        self.obj = obj
        self.rest = mesh_io.vertex_positions(obj.data).copy()
        obj.data[POSING_FLAG] = True

    def array(self):
        return mesh_io.vertex_positions(self.obj.data)

    def shows_pose(self):
        """False once the artist added shape keys mid-pose: Blender then shows them, not the positions."""
        return self.obj.data.shape_keys is None

    def restore(self):
        put_rest_back(self.obj.data, self.rest)


class StandInDisplay(_TransientDisplay):
    """The pose in the vertex positions of a copy of the mesh without its shape keys, standing in for
    the mesh on obj while posing, when only the "Modal Deform" key moves it (only_pose_key_moves; a
    mesh posed and kept before): Blender evaluates any mesh with shape keys, even all muted, far
    slower than a mesh without them (bench/results/bpy_pose.json, "evaluate" of "stand_in" against
    "shape_key"). The artist's mesh, its keys and their animation are not touched until the pose is
    kept; restore() puts it back on obj."""

    def __init__(self, obj):
        self.obj, self.mesh = obj, obj.data
        self.stand_in = (
            self.mesh.copy()
        )  # materials, attributes, vertex groups, UVs: what modifiers read
        self.stand_in.name = f"{self.mesh.name} (posing)"
        self.stand_in[STAND_IN_OF] = self.mesh
        copied_keys = self.stand_in.shape_keys.name
        obj.data = self.stand_in
        obj.shape_key_clear()
        left = bpy.data.shape_keys.get(copied_keys)
        if (
            left is not None
        ):  # Blender 3.4 and 4.5 count the copy's Key twice and keep it (4.5 then refuses to save)
            bpy.data.batch_remove([left])

    def array(self):
        return mesh_io.vertex_positions(self.stand_in)

    def shows_pose(self):
        """False once the artist added shape keys to the stand-in, or the mesh's other keys started
        to move it (animated values): the pose then goes on in the "Modal Deform" key."""
        return self.stand_in.shape_keys is None and only_pose_key_moves(self.obj, self.mesh)

    def restore(self):
        put_mesh_back(self.obj, self.stand_in)


def put_mesh_back(obj, stand_in):
    """The artist's mesh back on obj in place of `stand_in` (a StandInDisplay's), which goes, with
    the shape keys the artist added to it mid-pose carried over as the same offsets from the mesh's
    reference key (the stand-in's own reference copied the posed positions)."""
    mesh = stand_in[STAND_IN_OF]
    obj.data = mesh
    added = stand_in.shape_keys
    if added is not None:
        start = mesh_io.shape_key_co(stand_in, added.reference_key)
        rest = mesh_io.shape_key_co(mesh, mesh.shape_keys.reference_key)
        for block in added.key_blocks:
            if block != added.reference_key:
                carried = obj.shape_key_add(name=block.name, from_mix=False)
                carried.value, carried.mute = block.value, block.mute
                mesh_io.write_shape_key(
                    mesh, carried, rest + (mesh_io.shape_key_co(stand_in, block) - start)
                )
    bpy.data.meshes.remove(stand_in)
    mesh.update()


def put_rest_back(mesh, rest):
    """The rest (#V by 3) back into the positions of a mesh posed by a PositionsDisplay, and into its
    reference shape key if the artist added shape keys mid-pose (the first one copies the positions,
    which held the pose); the flag goes."""
    mesh_io.vertex_positions(mesh)[...] = rest
    if mesh.shape_keys is not None:
        mesh_io.shape_key_co(mesh, mesh.shape_keys.reference_key)[...] = rest
    del mesh[POSING_FLAG]
    mesh.update()
