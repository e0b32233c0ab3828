"""Handles: the vertices of a vertex group, moved rigidly by a controller: an object, or a bone of
an armature (the armature object and the handle's `bone`, as Constraint.subtarget names a bone).

A handle's transform is its controller's matrix in the mesh object's space relative to that
matrix when the controller was assigned (the bind matrix): moving the mesh object with its
controllers deforms nothing. A bone's matrix is the armature object's world matrix times the pose
bone's (armature space, after its parents and constraints): the bone in Pose Mode moves the handle,
and so does the armature object, unless the mesh moves with it. Controllers (bones too) may be
scaled or sheared; only the rotation (polar decomposition) and the motion of the handle's centre
are kept, as the solver takes rigid motions. A handle without a controller is pinned where it is.
"""

import collections

import numpy as np
from mathutils import Matrix

from . import core as mdc
from . import mesh_io
from .playback import rig

Handle = collections.namedtuple(
    "Handle",
    "name indices weight controller bind_inverse bind_skinning centre bone",
    defaults=("",),
)


class HandleError(Exception):
    """A handle that cannot be used, with what is wrong and which handle."""


def owner(obj):
    """The mesh object whose Modal Deform settings apply while `obj` is active: obj itself when it
    is a mesh, or the mesh whose handle it controls (so the sidebar and the operators stay with the
    mesh while the artist selects and moves a controller); None otherwise."""
    if obj is None:
        return None
    if obj.type == "MESH":
        return obj
    parent = obj.parent
    if (
        parent is not None
        and parent.type == "MESH"
        and any(h.controller == obj for h in parent.modal_deform.handles)
    ):
        return parent
    if obj.type == "ARMATURE":  # a rig the mesh is parented to, posed in Pose Mode
        for child in obj.children:
            if child.type == "MESH" and any(
                h.controller == obj for h in child.modal_deform.handles
            ):
                return child
    return None


def pose_bone(item):
    """The pose bone a handle's controller names (`item`: a ModalDeformHandle or a Handle), None
    for an object controller (no bone named, or not an armature) or a bone the armature lacks."""
    controller = item.controller
    if controller is None or not item.bone or controller.type != "ARMATURE":
        return None
    return controller.pose.bones.get(item.bone)


def world_matrix(controller, bone):
    """The controller's world matrix: the object's, or for a pose bone of it (pose_bone) the
    armature object's times the bone's armature-space matrix."""
    return controller.matrix_world if bone is None else controller.matrix_world @ bone.matrix


def bind(obj, handle):
    """Make the controller's current placement the handle's rest, in obj's space (obj's matrix may
    be singular: then its closest inverse), and record the skinning of the handle's vertices by
    obj's rig now (rig.bind_skinning: Follow Rig counts the controller's motion from there); called
    when the controller or its bone is assigned."""
    handle.bind_skinning = Matrix.Identity(4)
    if handle.controller is None:
        handle.bind_matrix = Matrix.Identity(4)
        handle.bound_controller = ""
    else:
        handle.bind_matrix = obj.matrix_world.inverted_safe() @ world_matrix(
            handle.controller, pose_bone(handle)
        )
        handle.bound_controller = handle.controller.name
        indices = mesh_io.group_vertices(obj, handle.vertex_group) if handle.vertex_group else None
        if indices is not None and indices.size:
            handle.bind_skinning = Matrix(rig.bind_skinning(obj, indices).tolist())


def skinning_modifier(obj, armature):
    """The Armature modifier of obj that deforms it by `armature` (its name), or "Armature
    parent" for a mesh parented with armature deform; "" when none does."""
    for modifier in obj.modifiers:
        if modifier.type == "ARMATURE" and modifier.object == armature:
            return modifier.name
    if obj.parent == armature and obj.parent_type == "ARMATURE":
        return "Armature parent"
    return ""


def controller_problem(obj, item):
    """What makes a handle's controller unusable, for the panel and the operators ("" when
    nothing): a bone its armature lacks (deleted or renamed), or the armature that skins obj
    chosen as a whole (obj would move twice: by its Armature modifier and by the handle)."""
    controller = item.controller
    if controller is None or controller.type != "ARMATURE":
        return ""
    if item.bone:
        if controller.pose is None or controller.pose.bones.get(item.bone) is None:
            return (
                f"bone '{item.bone}' is not in armature '{controller.name}' (deleted or renamed?): "
                f"name it back, or choose a bone again (the handle then binds to where that bone is)"
            )
        return ""
    skinning = skinning_modifier(obj, controller)
    if skinning:
        return (
            f"armature '{controller.name}' skins '{obj.name}' ({skinning}), so the whole armature "
            f"cannot also move a handle: choose one of its bones"
        )
    return ""


def notice(obj, item, scene):
    """What the Handles panel says of a handle's controller: (text, is_error), ("", False) when
    all is well: a problem that refuses the handle (a controller out of the scene,
    controller_problem) or a controller deleted since it was assigned (the handle is pinned)."""
    controller = item.controller
    if controller is None:
        if item.bound_controller:
            return f"Controller '{item.bound_controller}' is gone: the handle is pinned", False
        return "", False
    if scene.objects.get(controller.name) != controller:
        return f"Controller '{controller.name}' is not in the scene (deleted?)", True
    problem = controller_problem(obj, item)
    return (problem[0].upper() + problem[1:], True) if problem else ("", False)


def resolve(obj, scene, rest, region=None):
    """The usable handles of obj as Handle tuples, and warnings (overlaps, vanished controllers).

    rest: #V by 3 rest positions (for the handles' centres); region: the sorted vertices a region
    bake lets move (None or empty: all). Raises HandleError naming the first handle that cannot be
    used: no vertex group, a missing or empty group, a group covering every vertex (nothing left to
    deform) or reaching outside the region, a controller no longer in the scene, a bone its
    armature lacks, the armature that skins obj as a whole (controller_problem).
    """
    items = obj.modal_deform.handles
    if not items:
        raise HandleError(
            f"'{obj.name}' has no handles: in Edit Mode select vertices and Add Handle"
        )
    handles, warnings = [], []
    for item in items:
        label = f"handle '{item.name}'"
        if not item.vertex_group:
            raise HandleError(f"{label} has no vertex group")
        indices = mesh_io.group_vertices(obj, item.vertex_group)
        if indices is None:
            raise HandleError(f"{label}: vertex group '{item.vertex_group}' does not exist")
        if indices.size == 0:
            raise HandleError(
                f"{label}: vertex group '{item.vertex_group}' has no vertices (none with a weight above 0)"
            )
        if indices.size == len(rest):
            raise HandleError(
                f"{label}: vertex group '{item.vertex_group}' holds every vertex, so nothing is left "
                f"to deform"
            )
        if region is not None and region.size:
            outside = indices[~np.isin(indices, region, assume_unique=True)]
            if outside.size:
                raise HandleError(
                    f"{label}: vertex group '{item.vertex_group}' has {outside.size} vertices outside "
                    f"the region the basis was baked with (vertex {outside[0]} first), which alone "
                    f"moves: keep the handle inside the region, or re-bake with a region that holds it"
                )
        controller = item.controller
        if controller is not None and scene.objects.get(controller.name) != controller:
            raise HandleError(
                f"{label}: controller '{controller.name}' is not in the scene (deleted?): assign "
                f"another or clear it to pin the handle"
            )
        problem = controller_problem(obj, item)
        if problem:
            raise HandleError(f"{label}: {problem}")
        if controller is None and item.bound_controller:
            warnings.append(
                f"{label}: its controller '{item.bound_controller}' is gone, so the handle is pinned"
            )
        bind_inverse = Matrix(item.bind_matrix).inverted_safe()
        handles.append(
            Handle(
                item.name,
                indices,
                item.weight,
                controller,
                bind_inverse,
                np.array(Matrix(item.bind_skinning), np.float64),
                rest[indices].mean(axis=0),
                item.bone if pose_bone(item) is not None else "",
            )
        )
    for i, a in enumerate(handles):
        for b in handles[i + 1 :]:
            shared = np.intersect1d(a.indices, b.indices, assume_unique=True).size
            if shared:
                warnings.append(
                    f"handles '{a.name}' and '{b.name}' share {shared} vertices: they settle between "
                    f"both targets by weight"
                )
    return handles, warnings


def transforms(obj, handles):
    """One rigid 4x4 float64 transform per handle of its rest positions (object space), from where
    its controller is now."""
    world_inverse = obj.matrix_world.inverted_safe()
    result = []
    for handle in handles:
        if handle.controller is None:
            result.append(np.eye(4))
        else:
            bone = pose_bone(handle)
            if handle.bone and bone is None:  # renamed or deleted since resolve()
                raise HandleError(
                    f"handle '{handle.name}': bone '{handle.bone}' is not in armature "
                    f"'{handle.controller.name}' any more (deleted or renamed?)"
                )
            relative = world_inverse @ world_matrix(handle.controller, bone) @ handle.bind_inverse
            result.append(mdc.nearest_rigid(relative, handle.centre))
    return result


def restore(obj, item):
    """Put a handle's controller back where it was assigned (Reset Pose): the object, or the pose
    bone (its armature left where it is); nothing for a linked or unusable controller."""
    controller = item.controller
    if controller is None or controller.library is not None or controller_problem(obj, item):
        return
    target = obj.matrix_world @ Matrix(item.bind_matrix)
    bone = pose_bone(item)
    if bone is None:
        controller.matrix_world = target
    else:
        bone.matrix = controller.matrix_world.inverted_safe() @ target


def add_controller(context, obj, name, centre, size):
    """An Empty of display size `size` at `centre` (obj's space), parented to obj so that moving obj
    carries it, like Ctrl+H > Hook to New Object."""
    import bpy

    empty = bpy.data.objects.new(name, None)
    empty.empty_display_type = "SPHERE"
    empty.empty_display_size = size
    for collection in obj.users_collection or (context.scene.collection,):
        collection.objects.link(empty)
    empty.parent = obj
    empty.matrix_parent_inverse = Matrix.Identity(4)  # so the Empty's location is in obj's space
    empty.location = centre
    return empty
