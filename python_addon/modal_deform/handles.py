"""Handles: the vertices of a vertex group, moved rigidly by a controller object.

A handle's transform is its controller's matrix in the mesh object's space relative to that
matrix when the controller was assigned (the bind matrix): moving the mesh object with its
controllers deforms nothing. Controllers may be scaled or sheared; only the rotation (polar
decomposition) and the motion of the handle's centre are kept, as the solver takes rigid motions.
A handle without a controller is pinned where it is.
"""

import collections

import numpy as np
from mathutils import Matrix

from . import core as mdc
from . import mesh_io

Handle = collections.namedtuple("Handle", "name indices weight controller bind_inverse centre")


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
    return None


def object_space(obj, other):
    """other's world matrix in obj's space (obj's matrix may be singular: then its closest inverse)."""
    return obj.matrix_world.inverted_safe() @ other.matrix_world


def bind(obj, handle):
    """Make the controller's current placement the handle's rest (called when it is assigned)."""
    if handle.controller is None:
        handle.bind_matrix = Matrix.Identity(4)
        handle.bound_controller = ""
    else:
        handle.bind_matrix = object_space(obj, handle.controller)
        handle.bound_controller = handle.controller.name


def resolve(obj, scene, rest, region=None):
    """The usable handles of obj as Handle tuples, and warnings (overlaps, vanished controllers).

    rest: #V by 3 rest positions (for the handles' centres); region: the sorted vertices a region
    bake lets move (None or empty: all). Raises HandleError naming the first handle that cannot be
    used: no vertex group, a missing or empty group, a group covering every vertex (nothing left to
    deform) or reaching outside the region, a controller no longer in the scene.
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
                rest[indices].mean(axis=0),
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
            relative = world_inverse @ handle.controller.matrix_world @ handle.bind_inverse
            result.append(mdc.nearest_rigid(relative, handle.centre))
    return result


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
