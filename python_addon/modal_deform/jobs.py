"""The work the long operators drive, apart from their Blender UI plumbing, in two kinds: native
work on a thread (ThreadJob: the bake of the mesh, BakeJob, here; Refine in pose/refine.py) and a
frame per tick on the main thread (FrameJob: the cache bake in playback/operators.py; the refined
animation bake and the shape key export, AnimationJob, in playback/frame_keys.py). They read the
object when made and change it only in finish() (AnimationJob: in tick(), taken back by cancel() and
by a failure); cancel() leaves it as it was.

Every job offers what ops_common.JobOperator drives: start(); tick() on the operator's timer (every
tick_seconds), False once the job has ended; overall (the fraction done); cancel(); run() (all of
it at once, for execute); finish() on the main thread, returning (level, message) for the report and
setting `written` when it changed the object.
"""

import threading
import time

import bpy

from . import core as mdc
from . import mesh_io, storage


class ThreadJob:
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

    def _finished_object(self, action, changed):
        """(the job's object, None) for finish() to write to, or (None, (level, message)) for the
        report when there is nothing to write: the job was cancelled or failed (`action` names it,
        e.g. "Bake"), or its object was deleted or its mesh changed since the job read it
        (`changed` says so)."""
        if isinstance(self.error, mdc.Cancelled):
            return None, ("WARNING", f"{action} cancelled: nothing changed")
        if self.error is not None:
            return None, ("ERROR", f"{action} failed: {self.error}")
        obj = bpy.data.objects.get(self.object_name)
        if obj is None or obj.type != "MESH" or storage.fingerprint(obj.data) != self.fingerprint:
            return None, ("WARNING", changed)
        return obj, None


class BakeJob(ThreadJob):
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
        obj, report = self._finished_object(
            "Bake",
            f"'{self.object_name}' changed during the bake: the result was discarded, bake again",
        )
        if report:
            return report
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
