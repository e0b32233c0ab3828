"""Playback of the per-frame cache (frame_cache.py) on the timeline, like Blender's point caches.

At every frame change, for each object with a cache or with dynamics enabled: a cached frame is
read back (scrubbing costs the pose update's mapping, x = x̄ + U q, and no solve); the frame after
the last cached one is computed from it (the static pose for the controllers there, or one step of
the simulation from the previous frame's state) and cached; a frame further on is reached by
computing every frame in between (a jump forward simulates from the last cached frame and maps
only the frame it shows). Before the cache's first frame the mesh holds that frame's shape.

The result is shown by frame_display.py: mapped straight into a point attribute that a Geometry
Nodes modifier sets the positions from, or while the timeline plays into a stand-in mesh the modifier
reads (the artist's positions and shape keys are not written).
On a rig (rig.py) the simulation steps with each frame's bones, which the cache keeps beside the
state, and the frame shows as a rest-space offset before the Armature modifier
(frame_display.offset_mesh).
Frames computed here are checked against what they were computed from each time they are shown
(frame_cache: settings, basis, keyframes, the controllers' transforms at that frame) and computed
again from there when that changed.
"""

import types

import bpy
import numpy as np

from .. import app_handlers, handles, mesh_io, storage
from .. import core as mdc
from ..ops_common import FAILURES, is_posing
from ..pose import posing
from . import frame_cache, frame_display, rig

# Runtime state, by object name: the Player (solver or simulation kept between frames), and the
# last problem met (shown in the panel). Forgotten when a file is loaded.
_players = {}
problems = {}
# True while playback changes the frame itself (catching up): the handler then does nothing.
_busy = False
# True while the timeline plays (Blender 4+): objects shown then read a stand-in (frame_display).
_playing = False


class Player:
    """What computes and shows an object's frames: its basis, handles, the static pose solver and a
    simulation (which steps the dynamics and maps any cached q to the mesh: x̄ + U q, natively), for
    the settings it was made with (frame_cache.signature). `pose`: a posing.Pose of the same basis
    and pose settings (frame_cache.pose_signature) to take over, else one is made."""

    def __init__(self, obj, scene, pose=None):
        settings = obj.modal_deform
        self.signature = frame_cache.signature(obj, scene)
        self.pose_signature = frame_cache.pose_signature(obj)
        self.basis_id = frame_cache.basis_id(obj)
        self.kind = frame_cache.kind(obj)
        self.rig = None
        if rig.follows(obj):
            self._on_rig(obj, scene)
        else:
            self.pose = pose or posing.Pose(types.SimpleNamespace(scene=scene), obj)
            self.basis, self.handles = self.pose.basis, self.pose.handles
        dynamics = settings.dynamics
        indices = [h.indices for h in self.handles]
        weights = [h.weight for h in self.handles]
        if self.rig is not None:  # the Attach group: a handle held at the identity
            attach = self.rig.attach
            region = self.basis.region
            if region is not None and region.size:  # outside its region the mesh moves not at all
                attach = attach[np.isin(attach, region, assume_unique=True)]
            self.attached = attach.size > 0
            if self.attached:
                indices.append(attach)
                weights.append(1.0)
        # A rig's first frame solves its static pose with the simulation's handles (first()).
        self._solver_arguments = dict(
            handles=indices,
            weights=weights,
            pull=settings.stiffness,
            energy=settings.status.energy.lower(),
        )
        self.simulation = mdc.Simulation(
            self.basis,
            indices,
            pull=settings.stiffness,
            period=dynamics.period,
            damping=dynamics.damping,
            fps=scene.render.fps / scene.render.fps_base,
            substeps=dynamics.substeps,
            weights=weights,
            energy=settings.status.energy.lower(),
            rig=None if self.rig is None else self.rig.weights,
        )
        self.rest = self.basis.rest.astype(np.float32)
        # On a rig, True when its mesh was edited since its weights were read (_edits_reported).
        self.rig_edited = False
        # The mesh (address, vertex count) last found equal to rest; None again when Blender reports
        # a geometry update of it (_edits_reported). An undo makes every Player again (_undone).
        self.compared = None

    def _on_rig(self, obj, scene):
        """Follow Rig (rig.py): the basis, the artist's handles (none needed), the rig read once
        (its weights, the Attach group) and each handle's mean weights, for mapping its
        controller's motion into rest space. No Pose: the first frame's static pose, when a
        controller is not at its rest, is solved with the Attach group held (first())."""
        self.pose = None
        self.basis = storage.ready_basis(obj)
        self.handles, self.warnings = [], []
        if obj.modal_deform.handles:
            self.handles, self.warnings = handles.resolve(
                obj, scene, self.basis.rest, self.basis.region
            )
        self.rig = rig.Rig(obj, self.basis.num_vertices)
        self.warnings += self.rig.warnings
        self.handle_weights = [
            None if h.controller is None else self.rig.handle_weights(h.indices)
            for h in self.handles
        ]

    def rig_frame(self, obj):
        """The rig now (rig.Rig.frame), None off a rig."""
        return None if self.rig is None else self.rig.frame(obj)

    def check_mesh(self, obj, edits_reported=False):
        """Raise storage.NotReady when obj's vertices are no longer those of the bake (moved or
        added since): a comparison of the positions (mesh_io.same_positions), where the full check
        (storage.stale_reason, faces and vertex groups too) hashes the mesh. `edits_reported`: the
        caller is the frame handler, which forgets the comparisons of the meshes Blender reports
        a geometry update of: an edit between frames is reported after it (depsgraph_update_post)
        or in the frame's evaluation (frame_change_post's depsgraph), never playback's own writes
        (evaluated within the frame change). The comparison is then skipped while it holds; it
        costs more than reading 12 bytes a vertex (from Blender 4 on, reading the positions
        through RNA copies them when the evaluated mesh shares them)."""
        mesh = obj.data
        compared = (mesh.as_pointer(), len(mesh.vertices))
        if edits_reported and compared == self.compared:
            return
        if not mesh_io.same_positions(mesh, self.rest):
            storage.ready_basis(obj)
        self.compared = compared

    def fits(self, obj, signature):
        """Whether this Player is for obj's basis and settings (`signature`: frame_cache.signature)
        and, on a rig, its weights as read."""
        return (
            self.signature == signature
            and self.basis_id == frame_cache.basis_id(obj)
            and not self.rig_edited
        )

    def transforms(self, obj, rig_frame=None):
        """The handles' transforms now, (handles, 4, 4) float64; on a rig in rest space at
        `rig_frame` (rig_frame()), the Attach group's identity last (when it holds a vertex the
        basis moves)."""
        found = handles.transforms(obj, self.handles)
        if self.rig is not None:
            found = self.rig.to_rest(found, rig_frame, self.handle_weights, self.handles)
            if self.attached:
                found.append(np.eye(4))
        return np.array(found).reshape(-1, 4, 4)

    def first(self, transforms):
        """The state at the cache's first frame: the static pose for `transforms` (solved from rest,
        so that the same bake gives the same bits), at rest. On a rig with every handle at the
        identity: exactly zero displacement (the Armature modifier's result, to the bit)."""
        if self.rig is not None:
            if all(np.array_equal(T, np.eye(4)) for T in transforms):
                q = np.zeros(self.simulation.dimension)
                return q, q.copy()
            solver = mdc.ReducedSolver(self.basis, **self._solver_arguments)
            solver.set_transforms(list(transforms))
            solver.solve(max_iterations=posing.CONVERGE_MAX_ITERATIONS)
            q = solver.q
            return q, np.zeros_like(q)
        solver = self.pose.solver
        solver.reset()
        solver.set_transforms(list(transforms))
        self.pose.converge()
        q = solver.q
        return q, (np.zeros_like(q) if self.kind == "DYNAMIC" else None)

    def next(self, cache, frame, transforms, out=None, rig_frame=None):
        """The state at `frame` (the one after cache.end), from the cached frame before it, and
        whether what the display shows of it (shown()) is in `out` now: a simulation step maps it
        into `out` (a function giving a #V by 3 float32 C-contiguous array, called at once) when
        given; a frame not shown (a jump forward's frames in between, a bake's) is not mapped. On a
        rig, `rig_frame`: the rig at `frame` (rig_frame()); the cache holds every earlier frame's."""
        if self.kind == "STATIC":  # from the pose of the frame before, which the solver holds
            self.pose.solver.set_transforms(list(transforms))
            self.pose.converge()
            return self.pose.solver.q, None, False
        # From the cached state and transforms, always, with BFGS's memory of the frames since the
        # start of the frame's block (memory_frames frames from the cache's start): the same bits
        # whether played, jumped to, baked or undone. A simulation that does not hold that memory
        # steps again from the block's first state (at most memory_frames - 1 frames, reached from
        # the cache alone).
        simulation = self.simulation

        def cached_transforms(f):
            return list(cache.array("transforms")[cache.row(f)].reshape(-1, 4, 4))

        def cached_bones(f):  # the simulation's bones at a cached frame, None off a rig
            if self.rig is None:
                return None
            return self.rig.bones_of(cache.array("rig")[cache.row(f)].reshape(-1, 4, 4))

        def set_cached_state(f):  # BFGS's memory kept when it is the simulation's own state
            rig_state = None
            if self.rig is not None:  # the rig at f and the frame before (still before the start)
                rig_state = np.array([cached_bones(max(f - 1, cache.start)), cached_bones(f)])
            simulation.set_state(*cache.state(f), cached_transforms(f), bones=rig_state)

        block_start = frame - (frame - cache.start - 1) % simulation.memory_frames - 1
        set_cached_state(frame - 1)
        if simulation.remembered_frames != frame - 1 - block_start:
            set_cached_state(block_start)
            simulation.forget()
            for f in range(block_start + 1, frame):
                simulation.advance(cached_transforms(f), bones=cached_bones(f))
            set_cached_state(frame - 1)
        bones = None if self.rig is None else self.rig.bones_of(rig_frame)
        if out is None or self.rig is not None:
            simulation.advance(list(transforms), bones=bones)
        else:
            simulation.step(list(transforms), out=out(), bones=bones)
        q, v = simulation.state
        if out is not None and self.rig is not None:
            self.shown(q, out())
        return q, v, out is not None

    def positions(self, q, out):
        """x̄ + U q into `out` (#V by 3 float32, C-contiguous)."""
        self.simulation.positions_of(q, out)

    def shown(self, q, out):
        """What the display shows of q, into `out` (#V by 3 float32, C-contiguous): x̄ + U q; on a
        rig the rest-space offset U q (exactly zero at q = 0), written without reading x̄."""
        if self.rig is None:
            self.positions(q, out)
        else:
            self.simulation.displacement_of(q, out)


def player(obj, scene, signature=None):
    """obj's Player for its settings now (made anew when they changed; a change of the dynamics'
    settings alone keeps the pose's basis, handles and solver: each first() starts from rest).
    `signature`: frame_cache.signature(obj, scene) when the caller has it."""
    found = _players.get(obj.name)
    if found is None or not found.fits(obj, signature or frame_cache.signature(obj, scene)):
        same_pose = (
            found is not None
            and found.basis_id == frame_cache.basis_id(obj)
            and found.pose_signature == frame_cache.pose_signature(obj)
        )
        found = _players[obj.name] = Player(obj, scene, pose=found.pose if same_pose else None)
    return found


def rig_warnings(obj):
    """What the Player of obj on a rig found worth saying (vertices weighted to no bone, handles
    sharing vertices); [] without one."""
    found = _players.get(obj.name)
    return found.warnings if found is not None and found.rig is not None else []


def wants_playback(obj):
    """Whether the frame handler shows obj: a mesh of this file with a cache or dynamics on, in
    Object Mode (Edit, Sculpt and Paint Modes show the mesh being edited), not being posed."""
    if obj.type != "MESH" or obj.library is not None or obj.mode != "OBJECT" or is_posing(obj):
        return False
    return plays(obj)


def plays(obj):
    """Whether obj has a cache or dynamics on (a mesh)."""
    return obj.modal_deform.dynamics.enabled or obj.modal_deform.dynamics.cache is not None


def set_frame(scene, frame):
    """Go to `frame` without playing it (the handler does nothing meanwhile)."""
    global _busy
    _busy = True
    try:
        scene.frame_set(frame)
    finally:
        _busy = False


def fill(obj, scene, cache, frame, player_, out=None, curves=None):
    """Compute and cache every frame from cache.end + 1 to `frame` (each at its own frame, for the
    controllers there); the scene is back at the frame it was on. `out`: a function giving the
    array for the positions of `frame` itself (Player.next); `curves`: the controllers' curves
    (frame_cache.controller_curves) when the caller has them. Returns whether the positions are there."""
    if cache.end >= frame:
        return False
    if curves is None:
        curves = frame_cache.controller_curves(obj)
    here = scene.frame_current
    mapped = False
    try:
        for f in range(cache.end + 1, frame + 1):
            if scene.frame_current != f:
                set_frame(scene, f)
            rig_frame = player_.rig_frame(obj)
            transforms = player_.transforms(obj, rig_frame)
            if not len(cache):
                q, v = player_.first(transforms)
                if player_.rig is not None:  # the weights its frames are made with
                    cache.block[rig.WEIGHTS] = player_.rig.digest
            else:
                shown = out if f == frame else None
                q, v, mapped = player_.next(cache, f, transforms, shown, rig_frame)
            cache.append(q, v, transforms, frame_cache.curve_values(curves, f), rig_frame)
    finally:
        if scene.frame_current != here:
            set_frame(scene, here)
    return mapped


def show(obj, scene, edits_reported=False):
    """Show obj's state at the scene's frame, computing what the cache lacks up to it.
    `edits_reported`: as Player.check_mesh takes it."""
    if frame_cache.kind(obj) == "INBETWEEN":  # solved whole, not frame by frame
        from ..inbetweens import motion

        return motion.show(obj, scene, edits_reported, stand_in=_playing)
    frame = scene.frame_current
    on_rig = rig.follows(obj)
    if on_rig:  # the Armature modifier as the offset needs it, checked every frame
        rig.check_order(obj, frame_display.modifier_of(obj))
    cache = frame_cache.get(obj)
    signature = frame_cache.signature(obj, scene)
    start = obj.modal_deform.dynamics.frame_start
    if cache is not None and frame_cache.outdated(cache, obj, signature):
        if cache.kind == frame_cache.kind(obj) == "STATIC":  # keeps the range the artist baked
            start = cache.start
        cache = None
    if cache is None:
        cache = frame_cache.create(obj, scene, start)
    player_ = player(obj, scene, signature)
    player_.check_mesh(obj, edits_reported)
    if on_rig and len(cache) and cache.block.get(rig.WEIGHTS) != player_.rig.digest:
        cache.cut(cache.start)  # weights painted since its frames were made
    curves = frame_cache.controller_curves(obj)
    frame_cache.keyframes_changed(cache, curves)
    shown = max(frame, cache.start)
    index = cache.row(frame)
    if index is not None:
        rig_frame = player_.rig_frame(obj)
        if not np.array_equal(
            player_.transforms(obj, rig_frame).ravel(), cache.array("transforms")[index]
        ) or (on_rig and not np.array_equal(rig_frame.ravel(), cache.array("rig")[index])):
            cache.cut(frame)
    if on_rig:
        mesh = frame_display.offset_mesh(obj)

        def display():
            return frame_display.offset_values(mesh)
    else:
        if frame_display.shows_offset(obj):  # Follow Rig turned off
            frame_display.remove(obj)
        mesh = frame_display.frame_mesh(obj, stand_in=_playing)

        def display():  # a frame simulated here is mapped by its step straight into it
            return frame_display.frame_positions(mesh)

    if not fill(obj, scene, cache, shown, player_, out=display, curves=curves):
        player_.shown(cache.array("q")[cache.row(shown)], display())
    mesh.update()


def free(obj):
    """Forget obj's cache and its display: the mesh shows what it shows without them."""
    frame_cache.free(obj)
    _players.pop(obj.name, None)
    problems.pop(obj.name, None)
    frame_display.remove(obj)


def _edits_reported(depsgraph):
    """Forget the comparisons (Player.check_mesh) of the meshes depsgraph reports a geometry update of,
    and end their objects' stand-ins: what the artist changed shows."""
    edited = {
        update.id.original.as_pointer()
        for update in depsgraph.updates
        if update.is_updated_geometry and isinstance(update.id, bpy.types.Mesh)
    }
    if not edited:
        return
    for name, found in _players.items():
        obj = bpy.data.objects.get(name)
        if obj is not None and obj.type == "MESH" and obj.data.as_pointer() in edited:
            found.compared = None
            frame_display.end_stand_in(obj)
            found.rig_edited = found.rig is not None  # weights painted: read again (fits())


def _frame_changed(scene, depsgraph=None):
    if _busy:
        return
    if depsgraph is not None:
        _edits_reported(depsgraph)
    displayed = frame_display.in_use()
    for obj in scene.objects:
        if not wants_playback(obj):
            if displayed and obj.type == "MESH" and obj.library is None:
                if not plays(obj):  # freed, dynamics off
                    if not obj.modal_deform.shapes.enabled:  # a blend of shapes shows (shapes/)
                        frame_display.remove(obj)
                elif _playing:  # Edit, Sculpt or Paint Mode: the mesh itself shows there
                    frame_display.end_stand_in(obj)
            continue
        try:
            show(obj, scene, edits_reported=depsgraph is not None)
            problems.pop(obj.name, None)
        except FAILURES as error:
            if problems.get(obj.name) != str(error):
                print(f"Modal Deform: '{obj.name}' cannot play: {error}")
            problems[obj.name] = str(error)
            frame_display.remove(obj)


def _geometry_updated(scene, depsgraph):
    _edits_reported(depsgraph)


def _undone(*args):
    """After an undo or redo, which reads objects and meshes back from memory, the Players (which
    hold the handles' controllers) are made again, comparing their meshes again; with the timeline
    still, a stand-in the undo step held goes."""
    _players.clear()
    if not _playing:
        frame_display.end_stand_ins()


def _forget(*args):
    global _playing
    _players.clear()
    problems.clear()
    _playing = False
    frame_display.end_stand_ins()  # a file written mid-playback


def _playback_started(*args):
    global _playing
    _playing = True


def _playback_stopped(*args):
    global _playing
    _playing = False
    frame_display.end_stand_ins()


def _before_saving(*args):
    """The file holds the mesh once: the stand-ins go, and come back at the next frame played."""
    frame_display.end_stand_ins()


# Blender's handlers and ours; the playback handlers are Blender 4's.
_HANDLERS = (
    ("frame_change_post", _frame_changed),
    ("depsgraph_update_post", _geometry_updated),
    ("undo_post", _undone),
    ("redo_post", _undone),
    ("load_post", _forget),
    ("save_pre", _before_saving),
    ("animation_playback_pre", _playback_started),
    ("animation_playback_post", _playback_stopped),
)


def register():
    app_handlers.register(_HANDLERS)
    if frame_display.remove not in posing.covers:  # a frame shown would hide a pose shown after it
        posing.covers.append(frame_display.remove)


def unregister():
    app_handlers.unregister(_HANDLERS)
    if frame_display.remove in posing.covers:
        posing.covers.remove(frame_display.remove)
    _forget()
    frame_display.remove_all()
