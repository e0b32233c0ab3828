"""A posing session of one object: its stored basis, its handles and a reduced solver, writing the
result into a shape key. Shared by the interactive pose, the solve and the animation bake.

Per update: controller matrices → set_transforms → solve (within a time budget) →
positions(out=Blender's own array: a shape key's or the vertex positions) → mesh.update().

While the interactive pose runs, where the pose is shown is a display: the vertex positions of a
mesh without shape keys (PositionsDisplay), those of a copy without shape keys standing in for a
mesh whose only key that moves it is the "Modal Deform" one (StandInDisplay: a mesh posed before),
which Blender both evaluates without blending shape keys, or else the "Modal Deform" shape key
(ShapeKeyDisplay); each ends with the pose in the shape key (keep) or the mesh as it was (restore).
"""
import bpy
import numpy as np

from . import core as mdc
from . import handles, mesh_io, storage

POSE_KEY = "Modal Deform"
#: A mesh ID property: while it is set, the mesh's positions hold a pose and its rest is the
#: stored basis's. A file or undo step written mid-pose carries it, and recover() repairs them.
POSING_FLAG = "modal_deform_posing"
#: A mesh ID property of a stand-in (StandInDisplay): the artist's mesh it stands in for. An ID
#: property is a user, so that mesh is saved with a file written mid-pose, and recover() puts it back.
STAND_IN_OF = "modal_deform_stand_in_of"
#: The interactive pose under way (ops_pose's operator; it has .pose), or None.
running = None
#: The most BFGS iterations one update takes however much of its time budget is left: far more
#: than a budget of milliseconds allows (an iteration costs 0.2 ms at 67 dimensions), so the
#: budget or convergence ends an update.
MAX_ITERATIONS_PER_UPDATE = 1000
#: BFGS iterations at most of a solve to convergence (the Solve operator, scripts).
CONVERGE_MAX_ITERATIONS = 2000


class Pose:
    """Raises storage.NotReady (not baked, stale, damaged), handles.HandleError or ValueError (a
    solver option out of range) with a message for the artist."""

    def __init__(self, context, obj):
        settings = obj.modal_deform
        self.obj = obj
        self.basis = storage.ready_basis(obj)
        self.handles, self.warnings = handles.resolve(obj, context.scene, self.basis.rest, self.basis.region)
        self.solver = mdc.ReducedSolver(self.basis, [h.indices for h in self.handles], stiffness=settings.stiffness,
                                        weights=[h.weight for h in self.handles],
                                        energy=settings.status.energy.lower())
        self._transforms = None
        self.stats = {"iterations": 0, "energy": 0.0, "converged": False, "stalled": False}

    def follow_controllers(self):
        """Give the solver the controllers' current placement; True when it changed."""
        transforms = handles.transforms(self.obj, self.handles)
        if self._transforms is not None and all(np.array_equal(a, b) for a, b in zip(transforms, self._transforms)):
            return False
        self.solver.set_transforms(transforms)
        self._transforms = transforms
        self.stats["converged"] = False
        return True

    def step(self, budget_ms):
        """BFGS iterations until converged or `budget_ms` milliseconds are spent (timed natively)."""
        self.stats = self.solver.solve(max_iterations=MAX_ITERATIONS_PER_UPDATE, budget_ms=budget_ms)
        return self.stats

    def converge(self, max_iterations=CONVERGE_MAX_ITERATIONS, tolerance=mdc.SOLVE_TOLERANCE):
        """Iterate until the stopping test holds (or max_iterations): the result a script wants."""
        stats = self.solver.solve(max_iterations=max_iterations, tolerance=tolerance)
        self.stats = stats
        return stats

    def write(self, co):
        """x̄ + U q into `co`, a view of one of the mesh's arrays in Blender (mesh_io.shape_key_co,
        mesh_io.vertex_positions), and the mesh tagged for redraw. The solver writes (in parallel)
        straight into a contiguous array, which saves a copy of 19 MB per update at 1.6M vertices;
        Blender 3.4's vertices (strided MVert) take a copy."""
        if co.flags.c_contiguous:
            self.solver.positions(co)
        else:
            co[...] = self.solver.positions()
        self.obj.data.update()


def state(stats):
    """How a solve ended, for the artist: "converged", "stalled" (no step lowers the objective:
    the mesh stops following the controllers and the pose shown is not a solution) or "solving"."""
    if stats["converged"]:
        return "converged"
    return "stalled" if stats.get("stalled") else "solving"


STALLED_HINT = "the solver cannot follow this pose (no step lowers its energy); ease the controllers back or re-bake"


def header_text(stats, tick_ms):
    """The interactive pose's header line: how the last update's solve ended, with the hint when it
    stalled, its iterations, energy and time."""
    ended = state(stats)
    if ended == "stalled":
        ended = f"stalled: {STALLED_HINT}"
    return (f"Modal Deform: {ended}, {stats['iterations']} iterations, energy {stats['energy']:.5g}, "
            f"{tick_ms:.1f} ms per update")


def pose_key(obj):
    """The "Modal Deform" shape key, created if needed (after a Basis key when the mesh has none),
    shown at value 1; returns (key block, names of the keys created here)."""
    block, created = mesh_io.shape_key(obj, POSE_KEY)
    block.value, block.mute = 1.0, False
    return block, created


class ShapeKeyState:
    """What the "Modal Deform" shape key of obj looks like now, to put it back exactly (Esc):
    whether the mesh had shape keys, the key's positions, value and mute, the active key and solo
    display."""

    def __init__(self, obj):
        self.obj, self.name = obj, POSE_KEY
        keys = obj.data.shape_keys
        block = keys.key_blocks.get(POSE_KEY) if keys else None
        self.co = None
        if block is not None:
            self.co = np.empty(3 * len(block.data), np.float32)
            block.data.foreach_get("co", self.co)
            self.value, self.mute = block.value, block.mute
        self.active_index = obj.active_shape_key_index
        self.show_only = obj.show_only_shape_key
        self.created = []

    def ensure(self):
        """The key, created if needed (pose_key), shown at value 1."""
        block, self.created = pose_key(self.obj)
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


def is_posing(obj):
    """Whether the interactive pose runs on obj: its mesh is then not to be baked, solved or
    checked for staleness (its positions may hold the pose)."""
    try:
        return running is not None and running.pose.obj == obj
    except ReferenceError:  # the pose's object went away (undo, file loaded): it ends at its next event
        return False


def display(obj):
    """Where the interactive pose shows the pose of obj: the vertex positions of a mesh without
    shape keys, a stand-in's when only the "Modal Deform" key moves the mesh, else that key."""
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
        if block.name == POSE_KEY:
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
    Blender's evaluation of a 1.6M-vertex mesh takes 0.1 ms instead of 10 to 20 (docs/benchmarks.md).
    The rest positions are kept to put back; the mesh carries POSING_FLAG meanwhile, so a file or
    undo step written mid-pose is repaired (recover()) instead of taking the pose for the rest."""

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
        _put_rest_back(self.obj.data, self.rest)


class StandInDisplay(_TransientDisplay):
    """The pose in the vertex positions of a copy of the mesh without its shape keys, standing in for
    the mesh on obj while posing, when only the "Modal Deform" key moves it (only_pose_key_moves; a
    mesh posed and kept before): Blender evaluates any mesh with shape keys, even all muted, in 13
    ms at 1.6M vertices, a mesh without them in 0.2 (docs/benchmarks.md). The artist's mesh, its keys
    and their animation are not touched until the pose is kept; restore() puts it back on obj."""

    def __init__(self, obj):
        self.obj, self.mesh = obj, obj.data
        self.stand_in = self.mesh.copy()  # materials, attributes, vertex groups, UVs: what modifiers read
        self.stand_in.name = f"{self.mesh.name} (posing)"
        self.stand_in[STAND_IN_OF] = self.mesh
        copied_keys = self.stand_in.shape_keys.name
        obj.data = self.stand_in
        obj.shape_key_clear()
        left = bpy.data.shape_keys.get(copied_keys)
        if left is not None:  # Blender 3.4 and 4.5 count the copy's Key twice and keep it (4.5 then refuses to save)
            bpy.data.batch_remove([left])

    def array(self):
        return mesh_io.vertex_positions(self.stand_in)

    def shows_pose(self):
        """False once the artist added shape keys to the stand-in, or the mesh's other keys started
        to move it (animated values): the pose then goes on in the "Modal Deform" key."""
        return self.stand_in.shape_keys is None and only_pose_key_moves(self.obj, self.mesh)

    def restore(self):
        _put_mesh_back(self.obj, self.stand_in)


def _put_mesh_back(obj, stand_in):
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
                mesh_io.write_shape_key(mesh, carried, rest + (mesh_io.shape_key_co(stand_in, block) - start))
    bpy.data.meshes.remove(stand_in)
    mesh.update()


def _put_rest_back(mesh, rest):
    """The rest (#V by 3) back into the positions of a mesh posed by a PositionsDisplay, and into its
    reference shape key if the artist added shape keys mid-pose (the first one copies the positions,
    which held the pose); the flag goes."""
    mesh_io.vertex_positions(mesh)[...] = rest
    if mesh.shape_keys is not None:
        mesh_io.shape_key_co(mesh, mesh.shape_keys.reference_key)[...] = rest
    del mesh[POSING_FLAG]
    mesh.update()


def recover():
    """Meshes written mid-pose by a PositionsDisplay or a StandInDisplay (an undo step of a
    controller's move, autosave, a crash file, a file saved by a path without save handlers) hold
    the pose in their positions: their rest comes back (from the stored basis, or the artist's mesh
    in place of the stand-in) and the pose goes into the "Modal Deform" shape key, as if the pose
    had been kept. Meshes without a usable basis keep the flag and are reported."""
    for obj in bpy.data.objects:
        mesh = obj.data
        if obj.type != "MESH" or mesh.library is not None or is_posing(obj):
            continue
        if mesh.get(STAND_IN_OF) is not None:
            pose = mesh_io.vertex_positions(mesh).copy()
            _put_mesh_back(obj, mesh)
            mesh_io.write_shape_key(obj.data, pose_key(obj)[0], pose)
        elif mesh.get(POSING_FLAG) is not None:
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
        print(f"Modal Deform: '{obj.name}' was saved while posing and its mesh no longer fits its basis")
        return
    pose = mesh_io.vertex_positions(mesh).copy()
    _put_rest_back(mesh, rest)
    mesh_io.write_shape_key(mesh, pose_key(obj)[0], pose)
