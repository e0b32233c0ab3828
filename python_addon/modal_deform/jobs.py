"""The work the long operators drive, apart from their Blender UI plumbing: a bake of the mesh on a
thread (BakeJob), Refine on a thread (RefineJob) and an animation bake a frame at a time on the main
thread (AnimationJob, on FrameJob). They read the object when made and change it only in finish() (AnimationJob:
in tick(), taken back by cancel() and by a failure); cancel() leaves it as it was.

Every job offers what ops_common.JobOperator drives: start(); tick() on the operator's timer (every
tick_seconds), False once the job has ended; overall (the fraction done); cancel(); run() (all of
it at once, for execute); finish() on the main thread, returning (level, message) for the report and
setting `written` when it changed the object.

AnimationJob writes its frames as frame keys (frame_keys.py); refined, each frame starts from the
previous frame's refined answer.
"""

import threading
import time

import bpy
import numpy as np

from . import core as mdc
from . import frame_keys, mesh_io, posing, storage


class _ThreadJob:
    """Native work run by run() here or on a thread by start(); the native call releases the GIL, so
    Blender stays responsive. cancel() makes the next progress report stop it (Cancelled).
    Subclasses name their thread (what it does, e.g. "modal_deform bake"), set self.stage,
    self.fraction, self.cancelling, self.error, self.seconds in __init__ and implement _work()."""

    _thread = None
    thread_name = None
    tick_seconds = 0.1
    written = False

    def _progress(self, stage, fraction):
        self.stage, self.fraction = stage, fraction
        return not self.cancelling

    def run(self):
        start = time.perf_counter()
        try:
            self._work()
        except Exception as error:  # reported on the main thread (Cancelled included)
            self.error = error
        self.seconds = time.perf_counter() - start

    def start(self):
        self._thread = threading.Thread(target=self.run, name=self.thread_name, daemon=True)
        self._thread.start()

    def cancel(self):
        self.cancelling = True

    @property
    def done(self):
        return self._thread is None or not self._thread.is_alive()

    def tick(self):
        return not self.done

    def _unfinished(self, action):
        """(level, message) when the job was cancelled or failed (`action` names it, e.g. "Bake"),
        else None."""
        if isinstance(self.error, mdc.Cancelled):
            return "WARNING", f"{action} cancelled: nothing changed"
        if self.error is not None:
            return "ERROR", f"{action} failed: {self.error}"
        return None

    def _object_as_read(self):
        """The job's object, or None when it was deleted or its mesh changed since the job read it."""
        obj = bpy.data.objects.get(self.object_name)
        if obj is None or obj.type != "MESH" or storage.fingerprint(obj.data) != self.fingerprint:
            return None
        return obj


class BakeJob(_ThreadJob):
    """One bake of obj's mesh as it is now (read on the calling thread)."""

    thread_name = "modal_deform bake"

    def __init__(self, obj):
        settings = obj.modal_deform
        self.object_name = obj.name
        self.energy = settings.energy
        self.V = mesh_io.positions(obj.data)
        self.F = mesh_io.triangles(obj.data)
        self.fingerprint = storage.fingerprint(obj.data)
        self.vertex_groups = storage.groups(obj)
        region = self.vertex_groups.weights["region_group"]
        # The bake's numeric options are the settings' properties of the same names (properties.py).
        self.options = {
            name: getattr(settings, name)
            for name, option in mdc.BAKE_OPTIONS.items()
            if option.kind in ("int", "float") and hasattr(settings, name)
        }
        self.options.update(
            energy=self.energy.lower(),
            stiffness_weights=self.vertex_groups.weights["stiffness_group"],
            region=None if region is None else mesh_io.members(region),
        )
        if self.energy != "SHELLS":
            self.options["derivatives"] = 0
        self.stage, self.fraction = "starting", 0.0
        self.basis = self.error = None
        self.seconds = 0.0
        self.cancelling = False
        self.on_proxy = False

    def _progress(self, stage, fraction):
        self.on_proxy = self.on_proxy or stage == "proxy"  # a proxy, when there is one, comes first
        return super()._progress(stage, fraction)

    @property
    def overall(self):
        """Fraction of the whole bake done."""
        return mdc.bake_fraction(self.stage, self.fraction, self.on_proxy)

    def _work(self):
        self.basis = mdc.bake(self.V, self.F, progress=self._progress, **self.options)

    def finish(self):
        """Store the basis on the object (main thread). Returns (level, message) for a report."""
        unfinished = self._unfinished("Bake")
        if unfinished:
            return unfinished
        obj = self._object_as_read()
        if obj is None:
            return (
                "WARNING",
                f"'{self.object_name}' changed during the bake: the result was discarded, bake again",
            )
        storage.store(
            obj, self.basis, self.fingerprint, self.vertex_groups, self.seconds, self.energy
        )
        self.written = True
        basis = self.basis
        message = (
            f"Baked '{obj.name}' in {self.seconds:.1f} s: {basis.dimension} dimensions, ghost "
            f"{len(basis.ghost_vertices)} vertices"
        )
        if basis.num_floppy:
            message += (
                f"; {basis.num_floppy} zero modes besides the rigid motions (large parts joined at a "
                f"single vertex) came on top of the modes"
            )
        return "INFO", message


class RefineJob(_ThreadJob):
    """Refine the pose for the controllers as they are now: the reduced pose converged (here, on the
    calling thread, in milliseconds), then Newton on the full mesh from it (run()/start()).

    finish() writes the result into the "Modal Deform" shape key, where Solve and Pose put the
    reduced pose: the refined shape is the same pose made exact, and one key per pose keeps the
    artist's stack simple (a second key would add its offset on top unless muted). Until finish()
    nothing changes, so a cancelled or failed refine leaves the key as it was.
    """

    thread_name = "modal_deform refine"

    def __init__(
        self,
        context,
        obj,
        tolerance=mdc.FULL_SOLVE_OPTIONS["tolerance"].default,
        max_iterations=mdc.FULL_SOLVE_OPTIONS["max_iterations"].default,
    ):
        self.object_name = obj.name
        self.pose = posing.Pose(context, obj)
        self.pose.follow_controllers()
        self.reduced = self.pose.converge()
        self.F = mesh_io.triangles(obj.data)
        self.fingerprint = storage.fingerprint(obj.data)
        self.tolerance, self.max_iterations = tolerance, max_iterations
        self.stage, self.fraction = "starting", 0.0
        self.X = self.stats = self.error = None
        self.seconds = 0.0
        self.cancelling = False

    @property
    def overall(self):
        return self.fraction if self.stage == "solve" else 0.0

    def _work(self):
        self.X, self.stats = self.pose.solver.refine(
            self.F,
            tolerance=self.tolerance,
            max_iterations=self.max_iterations,
            progress=self._progress,
        )

    def finish(self):
        """Write the refined pose into the "Modal Deform" key (main thread). Returns (level, message)."""
        unfinished = self._unfinished("Refine")
        if unfinished:
            return unfinished
        obj = self._object_as_read()
        if obj is None:
            return (
                "WARNING",
                f"'{self.object_name}' changed during Refine: the result was discarded",
            )
        mesh_io.write_shape_key(obj.data, posing.pose_key(obj)[0], self.X.astype(np.float32))
        self.written = True
        stats = self.stats
        outcome = "Refined" if stats["converged"] else "Refine did not converge"
        message = (
            f"{outcome} in {self.seconds:.1f} s: {stats['iterations']} Newton iterations, objective "
            f"{stats['initial_energy']:.5g} -> {stats['energy']:.5g}"
        )
        return ("INFO" if stats["converged"] else "WARNING"), message


class FrameJob:
    """A job done a frame per tick() on the main thread (it changes the scene and the mesh): a subclass
    sets `frames` through __init__, does a frame in _frame(frame) and takes away what it added in
    _take_back(), after a failure (self.error, reported by finish()) or cancel()."""

    tick_seconds = 0.01

    def __init__(self, frames):
        self.frames = list(frames)
        self.frames_done = 0
        self.cancelling = self.written = False
        self.error = None

    @property
    def overall(self):
        return self.frames_done / len(self.frames) if self.frames else 1.0

    def start(self):
        """Nothing to start: the frames are done on the main thread, one per tick()."""

    def tick(self):
        """Do the next frame; False once the job has ended (every frame done, cancelled, or failed:
        self.error, with what it added taken away)."""
        if self.cancelling or self.error is not None or self.frames_done == len(self.frames):
            return False
        try:
            self._frame(self.frames[self.frames_done])
        except Exception as error:  # reported by finish(), as the thread jobs' are
            self.error = error
            self._take_back()
            return False
        self.frames_done += 1
        return True

    def run(self):
        while self.tick():
            pass

    def cancel(self):
        """Take away everything this job added."""
        self.cancelling = True
        self._take_back()


class AnimationJob(FrameJob):
    """Writes the frames one per tick() into new shape keys: each frame's pose refined on the full
    mesh (Newton's method from the reduced pose, then from the previous frame's answer), or with
    `positions` (frame -> #V by 3 float32) what it gives (the cache's frames); finish() keys them,
    cancel() (or a failure) takes them away."""

    def __init__(self, context, obj, frames, positions=None):
        super().__init__(frames)
        self.positions = positions
        self.action = "Animation bake" if positions is None else "Shape key export"
        self.pose = posing.Pose(context, obj) if positions is None else None
        self.triangles = mesh_io.triangles(obj.data) if positions is None else None
        self.refined = None
        self.obj, self.scene = obj, context.scene
        self.frame_before = self.scene.frame_current
        self.created = []  # (frame, key name as created: a new key may get a ".001" suffix)
        self.basis_created = obj.data.shape_keys is None
        self.unconverged = 0

    def _frame(self, frame):
        """Solve (or take) the frame's positions into a new shape key."""
        if self.positions is None:
            self.scene.frame_set(frame)
            self.pose.follow_controllers()
            self.pose.converge()
            self.refined, stats = self.pose.solver.refine(self.triangles, initial=self.refined)
            if not stats["converged"]:
                self.unconverged += 1
            co = self.refined.astype(np.float32)
        else:
            co = self.positions(frame)
        mesh_io.ensure_reference_key(self.obj)
        block = self.obj.shape_key_add(name=frame_keys.frame_key_name(frame), from_mix=False)
        block.value = 0.0
        self.created.append((frame, block.name))
        mesh_io.write_shape_key(self.obj.data, block, co)

    def finish(self):
        """Replace the keys of an earlier animation bake with the new ones and key their values.
        Returns (level, message) for a report."""
        if self.cancelling:
            return "WARNING", f"{self.action} cancelled: nothing changed"
        if self.error is not None:
            return "ERROR", f"{self.action} failed: {self.error}"
        obj = self.obj
        blocks = obj.data.shape_keys.key_blocks
        new_names = {name for _, name in self.created}
        old = [
            b.name for b in blocks if frame_keys.is_frame_key(b.name) and b.name not in new_names
        ]
        frame_keys.remove_keys(obj, old)
        pose_block = blocks.get(posing.POSE_KEY)
        if pose_block is not None:
            pose_block.mute = True  # the frame keys take its place; it would add on top
        for frame, name in self.created:
            block = blocks[name]
            block.name = frame_keys.frame_key_name(frame)
            frame_keys.show_on_its_frame(obj, block, frame)
        self.scene.frame_set(self.frame_before)
        self.written = True
        message = (
            f"{'Exported' if self.positions else 'Baked'} {len(self.frames)} frames into shape keys"
        )
        if self.unconverged:
            return "WARNING", f"{message}; {self.unconverged} did not converge"
        return "INFO", message

    def _take_back(self):
        names = [name for _, name in self.created]
        if self.basis_created and self.obj.data.shape_keys is not None:
            names.append(self.obj.data.shape_keys.reference_key.name)
        mesh_io.remove_shape_keys(self.obj, names)
        self.created = []
        self.scene.frame_set(self.frame_before)
