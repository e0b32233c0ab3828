"""Settings on the object (``Object.modal_deform``): basis options, handles, bake status, posing.

The baked arrays are not here: they live in a separate datablock (storage.py) that ``basis``
points to, so the object itself stays small for Blender's copy-on-write.
"""

import math

import bpy
from bpy.props import (
    BoolProperty,
    CollectionProperty,
    EnumProperty,
    FloatProperty,
    FloatVectorProperty,
    IntProperty,
    PointerProperty,
    StringProperty,
)

from . import core as mdc

IDENTITY = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def _limits(option, **ui):
    """A property's default and hard limits from the core's option (its closed bounds: an open one
    is the UI's to set, e.g. with `min`), with the UI's own soft limits and overrides `ui`."""
    limits = {"default": option.default}
    number = type(option.default)  # an IntProperty takes int limits only (Blender 3.4)
    if option.min > -math.inf and not option.min_open:
        limits["min"] = number(option.min)
    if option.max < math.inf and not option.max_open:
        limits["max"] = number(option.max)
    return {**limits, **ui}


_BAKE = mdc.BAKE_OPTIONS
_SIMULATION = mdc.SIMULATION_OPTIONS


def _controller_changed(handle, context):
    from . import handles

    controller = handle.controller
    if handle.bone and (
        controller is None
        or controller.type != "ARMATURE"
        or controller.pose.bones.get(handle.bone) is None
    ):
        handle.bone = ""  # binds (_bone_changed)
    handles.bind(handle.id_data, handle)


def _bone_changed(handle, context):
    from . import handles

    handles.bind(handle.id_data, handle)


def _controller_poll(handle, obj):
    return obj is not handle.id_data


def _preview_changed(settings, context):
    from . import ops_preview

    ops_preview.refresh(settings.id_data)


class ModalDeformHandle(bpy.types.PropertyGroup):
    """One handle: the vertices of a vertex group, moved rigidly by a controller object or bone."""

    # `name` (the label in the list) comes with PropertyGroup.
    vertex_group: StringProperty(
        name="Vertex Group",
        description="The vertices this handle grabs: every vertex with a weight above 0 in this group",
    )
    controller: PointerProperty(
        type=bpy.types.Object,
        name="Controller",
        poll=_controller_poll,
        update=_controller_changed,
        description="The object you move to move the handle's vertices (usually the Empty Add Handle made), or "
        "an armature whose bone moves them: they follow its moves and turns, not its scale. Empty: the "
        "vertices stay where they are (pinned)",
    )
    bone: StringProperty(
        name="Bone",
        update=_bone_changed,
        description="The bone of the controller armature that moves the handle's vertices as you pose it: they "
        "follow its moves and turns, not its scale or shear. Empty: the armature object itself moves "
        "them",
    )
    weight: FloatProperty(
        name="Weight",
        default=1.0,
        min=1e-3,
        soft_max=10.0,
        description="How strongly this handle pulls compared with the other handles: where handles share "
        "vertices, those settle between the handles' targets in proportion to their weights",
    )
    bound_controller: StringProperty(
        name="Bound Controller",
        options={"HIDDEN"},
        description="Name of the controller when it was assigned, to tell a deleted controller from none",
    )
    bind_matrix: FloatVectorProperty(
        name="Bind Matrix",
        size=(4, 4),
        subtype="MATRIX",
        default=IDENTITY,
        options={"HIDDEN"},
        description="The controller's matrix (its bone's, for a bone) in the mesh object's space when it was "
        "assigned: the rest pose of the handle",
    )
    bind_skinning: FloatVectorProperty(
        name="Bind Skinning",
        size=(4, 4),
        subtype="MATRIX",
        default=IDENTITY,
        options={"HIDDEN"},
        description="How the mesh's Armature modifier placed the handle's vertices (in the mesh object's "
        "space) when the controller was assigned: Follow Rig holds them there until the controller moves",
    )


class ModalDeformBakeStatus(bpy.types.PropertyGroup):
    """What the stored basis is and which mesh it was baked from (read-only in the UI)."""

    dimension: IntProperty(
        name="Dimension", description="Basis vectors: the number of reduced coordinates"
    )
    num_rigid: IntProperty(
        name="Rigid", description="Rigid motions in the basis (6 per simulated part)"
    )
    num_modes: IntProperty(
        name="Modes", description="Vibration modes in the basis, rigid motions included"
    )
    num_derivatives: IntProperty(name="Derivatives", description="Modal derivatives in the basis")
    num_floppy: IntProperty(
        name="Floppy", description="Zero modes besides the rigid motions (mechanisms)"
    )
    ghost_vertices: IntProperty(
        name="Ghost Vertices", description="Vertices of the coarse mesh used while posing"
    )
    proxy_vertices: IntProperty(
        name="Proxy Vertices",
        description="Vertices of the proxy a dense mesh was baked on (0: baked as it is)",
    )
    energy: StringProperty(name="Energy", description="The energy the basis was baked with")
    baked_at: StringProperty(name="Baked At", description="Local date and time of the bake")
    seconds: FloatProperty(name="Seconds", description="Wall time of the bake")
    num_vertices: IntProperty(name="Vertices", description="Vertex count of the mesh at the bake")
    topology_hash: StringProperty(name="Topology Hash", description="Faces of the mesh at the bake")
    rest_hash: StringProperty(
        name="Rest Hash", description="Vertex positions of the mesh at the bake"
    )
    stiffness_group: StringProperty(
        name="Stiffness Group", description="The stiffness vertex group of the bake"
    )
    stiffness_group_hash: StringProperty(
        name="Stiffness Hash",
        description="Weights of the stiffness vertex group at the bake (empty: uniform)",
    )
    region_group: StringProperty(
        name="Region Group", description="The region vertex group of the bake"
    )
    region_group_hash: StringProperty(
        name="Region Hash",
        description="Weights of the region vertex group at the bake (empty: the whole mesh)",
    )


# Secondary motion and the per-frame cache: playback/frame_cache.py, playback/timeline.py,
# playback/operators.py.
def _dynamics_changed(dynamics, context):
    from .playback import frame_cache

    frame_cache.settings_changed(dynamics.id_data)


class ModalDeformDynamics(bpy.types.PropertyGroup):
    """Secondary motion: the mesh follows its controllers with inertia, and the per-frame cache of
    its reduced state (static animation or simulation) that plays back."""

    enabled: BoolProperty(
        name="Dynamics",
        default=False,
        update=_dynamics_changed,
        description="The mesh follows its controllers with inertia: parts away from the handles overshoot and "
        "settle when the controllers stop, played live on the timeline and cached per frame",
    )
    period: FloatProperty(
        name="Period",
        **_limits(_SIMULATION["period"], soft_max=100.0),
        update=_dynamics_changed,
        description="Frames one swing of the softest part takes (the slowest wobble): more frames make the "
        "mesh heavier and lazier, fewer make it snappier",
    )
    damping: FloatProperty(
        name="Damping",
        **_limits(_SIMULATION["damping"]),
        update=_dynamics_changed,
        description=f"How quickly the swinging dies down: {_SIMULATION['damping'].min:g} swings on forever, "
        f"{_SIMULATION['damping'].default:g} settles in a few swings, {_SIMULATION['damping'].max:g} "
        f"settles without overshooting",
    )
    substeps: IntProperty(
        name="Substeps",
        **_limits(_SIMULATION["substeps"]),
        update=_dynamics_changed,
        description="Simulation steps per frame: more follow fast controllers more closely and cost more per "
        "frame",
    )
    frame_start: IntProperty(
        name="Start",
        default=1,
        update=_dynamics_changed,
        description="Frame the simulation starts on, at rest in the pose of the controllers there; before it "
        "the mesh holds that pose",
    )
    # On a rig: playback/rig.py.
    follow_rig: BoolProperty(
        name="Follow Rig",
        default=False,
        update=_dynamics_changed,
        description="The mesh's Armature modifier drives the dynamics: parts not attached to the bones lag, "
        "overshoot and settle as the rig moves, shown before the Armature modifier so that its skinning "
        "and your corrective shape keys still apply; with the rig still the mesh is exactly the "
        "Armature modifier's",
    )
    attach_group: StringProperty(
        name="Attach",
        update=_dynamics_changed,
        description="Vertex group of the vertices held where the rig puts them (weight above 0.5), as Cloth's "
        "Pin Group: Fill Attach from Armature makes it from the vertices near the bones, then paint it",
    )
    cache: PointerProperty(
        type=bpy.types.Palette,
        name="Cache",
        description="Datablock holding the cached frames (hidden: its name starts with a dot)",
    )


# Shape keys blended as shapes: shapes/.
def _shapes_changed(shapes, context):
    from .shapes import blending

    blending.refresh(shapes.id_data)


class ModalDeformShapes(bpy.types.PropertyGroup):
    """Blend as Shapes: the mesh shows the rotation-aware blend of its shape keys (shapes/), from
    the shape space baked of them (kept in ``space``, storage.write_arrays) and the keys' values."""

    enabled: BoolProperty(
        name="Blend as Shapes",
        default=False,
        update=_shapes_changed,
        description="Show the shape keys blended as shapes: where a part turns between the basis and a key "
        "(a jaw opening, a finger curling) the in-between turns too and keeps its size, where "
        "Blender's linear mix cuts through and shrinks it. The keys' values (keyframed, driven or "
        "moved) are the weights",
    )
    space: PointerProperty(
        type=bpy.types.Palette,
        name="Shape Space",
        description="Datablock holding the baked shape space (hidden: its name starts with a dot)",
    )
    key_names: StringProperty(
        name="Keys", description="The shape keys of the space, one per line, in the mesh's order"
    )
    keys_digest: StringProperty(
        name="Keys Digest",
        description="Faces, basis and keys (coordinates and Relative To) at the bake",
    )
    dimension: IntProperty(name="Dimension", description="Reduced coordinates of the space")
    baked_at: StringProperty(name="Baked At", description="Local date and time of the bake")
    seconds: FloatProperty(name="Seconds", description="Wall time of the bake")


class ModalDeformSettings(bpy.types.PropertyGroup):
    modes: IntProperty(
        name="Modes",
        **_limits(_BAKE["modes"], soft_min=7, soft_max=60),
        description="How many natural ways of bending the mesh the bake finds (its vibration modes, 6 of them "
        "just move and turn it): more let poses take more shapes, and make the bake and posing slower",
    )
    derivatives: IntProperty(
        name="Derivatives",
        **_limits(_BAKE["derivatives"], soft_max=200),
        description="Extra shapes that let large bends and twists keep the mesh's volume instead of shrinking it "
        "(modal derivatives, Discrete Shells only): more make strong poses better and cost bake and "
        "posing time",
    )
    ghost: IntProperty(
        name="Ghost Size",
        **_limits(_BAKE["ghost"], soft_min=200, soft_max=5000),
        description="Vertices of the coarse copy of the mesh (the ghost) that posing weighs the deformation on: "
        "more follow the full mesh more closely, fewer make posing faster",
    )
    proxy: IntProperty(
        name="Proxy Size",
        **_limits(_BAKE["proxy"], soft_min=10000, soft_max=150000),
        description="A dense mesh (more vertices than Proxy Over) is baked on a simplified copy of about this "
        "many vertices, which every vertex follows with its own detail: fewer bake faster",
    )
    proxy_above: IntProperty(
        name="Proxy Over",
        **_limits(_BAKE["proxy_above"], soft_max=500000),
        description="Meshes with more vertices than this are baked on a simplified copy of Proxy Size vertices, "
        "which bakes much faster (0: never)",
    )
    energy: EnumProperty(
        name="Energy",
        default=_BAKE["energy"].default.upper(),
        items=(
            (
                "SHELLS",
                "Discrete Shells",
                "Resists bending and stretching like a thin shell (the paper's energy)",
            ),
            (
                "ARAP",
                "As-Rigid-As-Possible",
                "Keeps every vertex neighbourhood rigid; bakes vibration modes "
                "only, no modal derivatives",
            ),
        ),
        description="How the surface resists being deformed: like a thin shell that keeps its curvature, or "
        "keeping every small neighbourhood rigid",
    )
    bending: FloatProperty(
        name="Bending",
        **_limits(_BAKE["bending"], soft_max=10.0),
        description="How much the surface resists bending (Discrete Shells): higher keeps its curves, so poses "
        "bend less and stretch more",
    )
    membrane: FloatProperty(
        name="Membrane",
        **_limits(_BAKE["membrane"], soft_max=10.0),
        description="How much the surface resists stretching and squashing (Discrete Shells): higher keeps its "
        "size, so poses stretch less and bend more",
    )
    stiffness_group: StringProperty(
        name="Stiffness Group",
        description="Vertex group painting where the surface is stiffer, as in Cloth (Discrete Shells): weight 0 "
        "is the material, weight 1 is Max times as stiff. Empty: the same material everywhere. "
        "Painting it anew needs a re-bake",
    )
    max_stiffness: FloatProperty(
        name="Max Stiffness",
        **_limits(_BAKE["max_stiffness"], soft_max=1000.0),
        description="How many times stiffer than the material the Stiffness group's weight 1 is",
    )
    region_group: StringProperty(
        name="Region Group",
        description="Vertex group of the only vertices that may move (weight above 0), as in Laplacian Deform: "
        "every other vertex stays exactly where it is, so a hand or a head of a dense character bakes "
        "quickly; handles must lie in it. Empty: the whole mesh moves",
    )
    # The pull μ; its identifier stays `stiffness` so that saved files keep their value.
    stiffness: FloatProperty(
        name="Pull",
        **_limits(mdc.SOLVER_OPTIONS["pull"], min=1e-3, soft_min=1.0, soft_max=1e5),
        description="How hard the handles pull their vertices toward the controllers: higher follows the "
        "controllers more exactly, lower lets the surface hold them back",
    )
    budget: FloatProperty(
        name="Budget",
        default=5.0,
        min=0.5,
        soft_max=50.0,
        description="Milliseconds Pose may spend solving per viewport update: more reach the final shape in "
        "fewer updates and may lower the frame rate. Pose takes less when Blender's own work leaves "
        "less of a 60 fps frame",
    )
    handles: CollectionProperty(
        type=ModalDeformHandle,
        name="Handles",
        description="The handles: each moves the vertices of a vertex group with a controller, or pins them",
    )
    active_handle: IntProperty(name="Active Handle", description="The handle shown below the list")
    basis: PointerProperty(
        type=bpy.types.Palette,
        name="Basis",
        description="Datablock holding the baked basis (hidden: its name starts with a dot)",
    )
    status: PointerProperty(
        type=ModalDeformBakeStatus,
        name="Bake Status",
        description="What the stored basis is and which mesh it was baked from",
    )
    preview_vector: IntProperty(
        name="Vector",
        default=6,
        min=0,
        update=_preview_changed,
        description="Which of the baked shapes the preview shows: moves and turns first, then the natural "
        "bends from the softest up (vibration modes), then the modal derivatives",
    )
    dynamics: PointerProperty(
        type=ModalDeformDynamics,
        name="Dynamics",
        description="Secondary motion and the per-frame cache of the pose",
    )
    shapes: PointerProperty(
        type=ModalDeformShapes,
        name="Blend as Shapes",
        description="The shape keys blended as shapes",
    )
    preview_amplitude: FloatProperty(
        name="Amplitude",
        default=0.1,
        soft_min=-0.5,
        soft_max=0.5,
        update=_preview_changed,
        description="How far the preview moves the mesh, as a fraction of its longest side",
    )


CLASSES = (
    ModalDeformHandle,
    ModalDeformBakeStatus,
    ModalDeformDynamics,
    ModalDeformShapes,
    ModalDeformSettings,
)


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    bpy.types.Object.modal_deform = PointerProperty(type=ModalDeformSettings)


def unregister():
    del bpy.types.Object.modal_deform
    _unregister_classes()
