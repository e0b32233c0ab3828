"""Settings on the object (``Object.modal_deform``): basis options, handles, bake status, posing.

The baked arrays are not here: they live in a separate datablock (storage.py) that ``basis``
points to, so the object itself stays small for Blender's copy-on-write.
"""
import bpy
from bpy.props import (BoolProperty, CollectionProperty, EnumProperty, FloatProperty, FloatVectorProperty,
                       IntProperty, PointerProperty, StringProperty)

from . import core as mdc

IDENTITY = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0), (0.0, 0.0, 0.0, 1.0))


def _controller_changed(handle, context):
    from . import handles
    handles.bind(handle.id_data, handle)


def _controller_poll(handle, obj):
    return obj is not handle.id_data


def _preview_changed(settings, context):
    from . import ops_preview
    ops_preview.refresh(settings.id_data)


class ModalDeformHandle(bpy.types.PropertyGroup):
    """One handle: the vertices of a vertex group, moved rigidly by a controller object."""

    # `name` (the label in the list) comes with PropertyGroup.
    vertex_group: StringProperty(
        name="Vertex Group",
        description="Vertices this handle moves (every vertex with a weight above 0 in the group)")
    controller: PointerProperty(
        type=bpy.types.Object, name="Controller", poll=_controller_poll, update=_controller_changed,
        description="Object whose motion since it was assigned moves the handle's vertices rigidly (its scale and "
                    "shear are ignored); without one the vertices stay where they are (pinned)")
    weight: FloatProperty(
        name="Weight", default=1.0, min=1e-3, soft_max=10.0,
        description="How strongly this handle pulls its vertices, relative to the other handles: where handles "
                    "overlap, the shared vertices settle between their targets in proportion to the weights")
    bound_controller: StringProperty(
        name="Bound Controller", options={"HIDDEN"},
        description="Name of the controller when it was assigned, to tell a deleted controller from none")
    bind_matrix: FloatVectorProperty(
        name="Bind Matrix", size=(4, 4), subtype="MATRIX", default=IDENTITY, options={"HIDDEN"},
        description="The controller's matrix in the mesh object's space when it was assigned: the rest pose of "
                    "the handle")


class ModalDeformBakeStatus(bpy.types.PropertyGroup):
    """What the stored basis is and which mesh it was baked from (read-only in the UI)."""

    dimension: IntProperty(name="Dimension", description="Basis vectors: the number of reduced coordinates")
    num_rigid: IntProperty(name="Rigid", description="Rigid motions in the basis (6 per simulated part)")
    num_modes: IntProperty(name="Modes", description="Vibration modes in the basis, rigid motions included")
    num_derivatives: IntProperty(name="Derivatives", description="Modal derivatives in the basis")
    num_floppy: IntProperty(name="Floppy", description="Zero modes besides the rigid motions (mechanisms)")
    ghost_vertices: IntProperty(name="Ghost Vertices", description="Vertices of the coarse mesh used while posing")
    proxy_vertices: IntProperty(
        name="Proxy Vertices", description="Vertices of the proxy a dense mesh was baked on (0: baked as it is)")
    energy: StringProperty(name="Energy", description="The energy the basis was baked with")
    baked_at: StringProperty(name="Baked At", description="Local date and time of the bake")
    seconds: FloatProperty(name="Seconds", description="Wall time of the bake")
    num_vertices: IntProperty(name="Vertices", description="Vertex count of the mesh at the bake")
    topology_hash: StringProperty(name="Topology Hash", description="Faces of the mesh at the bake")
    rest_hash: StringProperty(name="Rest Hash", description="Vertex positions of the mesh at the bake")
    stiffness_group: StringProperty(name="Stiffness Group", description="The stiffness vertex group of the bake")
    stiffness_group_hash: StringProperty(
        name="Stiffness Hash", description="Weights of the stiffness vertex group at the bake (empty: uniform)")
    region_group: StringProperty(name="Region Group", description="The region vertex group of the bake")
    region_group_hash: StringProperty(
        name="Region Hash", description="Weights of the region vertex group at the bake (empty: the whole mesh)")


# Secondary motion and the per-frame cache (issue 40): frame_cache.py, playback.py, ops_dynamics.py.
def _dynamics_changed(dynamics, context):
    from . import frame_cache
    frame_cache.settings_changed(dynamics.id_data)


class ModalDeformDynamics(bpy.types.PropertyGroup):
    """Secondary motion: the mesh follows its controllers with inertia, and the per-frame cache of
    its reduced state (static animation or simulation) that plays back."""

    enabled: BoolProperty(
        name="Dynamics", default=False, update=_dynamics_changed,
        description="The mesh follows its controllers with inertia: parts away from the handles overshoot and "
                    "settle when the controllers stop, played live on the timeline and cached per frame")
    period: FloatProperty(
        name="Period", default=mdc.SIMULATION_DEFAULTS["period"], min=mdc.MIN_PERIOD_FRAMES, soft_max=100.0,
        update=_dynamics_changed,
        description="Frames one swing of the softest part takes (the slowest wobble): more frames make the "
                    "mesh heavier and lazier, fewer make it snappier")
    damping: FloatProperty(
        name="Damping", default=mdc.SIMULATION_DEFAULTS["damping"], min=0.0, max=1.0, update=_dynamics_changed,
        description="How quickly the swinging dies down: 0 swings on forever, 0.05 settles in a few swings, "
                    "1 settles without overshooting")
    substeps: IntProperty(
        name="Substeps", default=mdc.SIMULATION_DEFAULTS["substeps"], min=1, max=mdc.MAX_SUBSTEPS,
        update=_dynamics_changed,
        description="Simulation steps per frame: more follow fast controllers more closely and cost more per "
                    "frame")
    frame_start: IntProperty(
        name="Start", default=1, update=_dynamics_changed,
        description="Frame the simulation starts on, at rest in the pose of the controllers there; before it "
                    "the mesh holds that pose")
    cache: PointerProperty(
        type=bpy.types.Palette, name="Cache",
        description="Datablock holding the cached frames (hidden: its name starts with a dot)")


class ModalDeformSettings(bpy.types.PropertyGroup):
    modes: IntProperty(
        name="Modes", default=20, min=7, soft_max=60,
        description="Vibration modes in the basis, the rigid motions (6 per part) included: more modes let the "
                    "mesh deform in more ways and make the bake and each solver iteration slower")
    derivatives: IntProperty(
        name="Derivatives", default=52, min=0, soft_max=200,
        description="Modal derivatives in the basis: they let large rotations and bends stay smooth instead of "
                    "shrinking; more of them cost bake time and solver time (Discrete Shells only)")
    ghost: IntProperty(
        name="Ghost Size", default=1000, min=4, soft_min=200, soft_max=5000,
        description="Vertices of the coarse mesh the energy is evaluated on while posing: more follow the "
                    "energy of the full mesh more closely, fewer make each iteration faster")
    proxy: IntProperty(
        name="Proxy Size", default=mdc.PROXY, min=4, soft_min=10000, soft_max=150000,
        description="A dense mesh (more vertices than Proxy Above) is baked on a simplified proxy of about this "
                    "many vertices, and every vertex follows it with its own detail")
    proxy_above: IntProperty(
        name="Proxy Above", default=mdc.PROXY_ABOVE, min=0, soft_max=500000,
        description="Meshes with more vertices than this are baked on a proxy (0: never)")
    energy: EnumProperty(
        name="Energy", default="SHELLS",
        items=(("SHELLS", "Discrete Shells", "Resists bending and stretching like a thin shell (the paper's energy)"),
               ("ARAP", "As-Rigid-As-Possible", "Keeps every vertex neighbourhood rigid; bakes vibration modes "
                                                "only, no modal derivatives")),
        description="The deformation energy the mesh resists with")
    bending: FloatProperty(
        name="Bending", default=1.0, min=0.0, soft_max=10.0,
        description="Discrete Shells: weight of the bending term; higher keeps the surface's curvature, so "
                    "poses bend less and stretch more")
    membrane: FloatProperty(
        name="Membrane", default=1.0, min=0.0, soft_max=10.0,
        description="Discrete Shells: weight of the stretching terms (edge lengths, triangle areas); higher "
                    "keeps the surface's size, so poses stretch less and bend more")
    stiffness_group: StringProperty(
        name="Stiffness Group",
        description="Vertex group painting where the surface is stiffer (Discrete Shells): each element's bending "
                    "and membrane weights are multiplied by 1 + (Max - 1) times its vertices' mean weight, as "
                    "Cloth does; empty for a uniform material. Painting it anew makes the bake stale")
    max_stiffness: FloatProperty(
        name="Max Stiffness", default=100.0, min=1.0, max=1e4, soft_max=1000.0,
        description="How many times stiffer than the material a vertex of weight 1 in the stiffness group is")
    region_group: StringProperty(
        name="Region Group",
        description="Vertex group of the vertices that may move (weight above 0), as Laplacian Deform takes one: "
                    "every other vertex stays exactly where it is, and the whole basis is spent inside the region, "
                    "so a hand or a head of a dense character bakes quickly; handles must lie in it. Empty for the "
                    "whole mesh")
    stiffness: FloatProperty(
        name="Stiffness", default=1000.0, min=1e-3, soft_min=1.0, soft_max=1e5,
        description="How hard the handles pull their vertices toward the controllers: higher follows the "
                    "controllers more exactly, lower lets the surface's energy hold them back")
    budget: FloatProperty(
        name="Milliseconds per Update", default=5.0, min=0.5, soft_max=50.0,
        description="Milliseconds the interactive pose spends in the solver per update at most: more converge "
                    "faster and may lower the frame rate. Less when the rest of the update (writing the mesh, "
                    "Blender's evaluation and drawing) leaves less of a 60 fps frame")
    handles: CollectionProperty(type=ModalDeformHandle, name="Handles")
    active_handle: IntProperty(name="Active Handle", description="The handle shown below the list")
    basis: PointerProperty(
        type=bpy.types.Palette, name="Basis",
        description="Datablock holding the baked basis (hidden: its name starts with a dot)")
    status: PointerProperty(type=ModalDeformBakeStatus)
    preview_vector: IntProperty(
        name="Basis Vector", default=6, min=0, update=_preview_changed,
        description="Which basis vector the preview deforms along: rigid motions first, then vibration modes "
                    "(low to high frequency), then modal derivatives")
    dynamics: PointerProperty(type=ModalDeformDynamics)
    preview_amplitude: FloatProperty(
        name="Amplitude", default=0.1, soft_min=-0.5, soft_max=0.5, update=_preview_changed,
        description="Largest displacement of the preview, as a fraction of the model's longest bounding-box edge")


CLASSES = (ModalDeformHandle, ModalDeformBakeStatus, ModalDeformDynamics, ModalDeformSettings)


_register_classes, _unregister_classes = bpy.utils.register_classes_factory(CLASSES)


def register():
    _register_classes()
    bpy.types.Object.modal_deform = PointerProperty(type=ModalDeformSettings)


def unregister():
    del bpy.types.Object.modal_deform
    _unregister_classes()
