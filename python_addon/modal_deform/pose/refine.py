"""Refine on a thread (RefineJob, which the Refine operator drives): the reduced pose converged, then
Newton's method on the full mesh from it, into the "Modal Deform" shape key."""

import numpy as np

from .. import core as mdc
from .. import mesh_io, storage
from ..jobs import ThreadJob
from . import posing


class RefineJob(ThreadJob):
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
        obj, report = self._finished_object(
            "Refine", f"'{self.object_name}' changed during Refine: the result was discarded"
        )
        if report:
            return report
        mesh_io.write_shape_key(obj.data, posing.pose_key(obj)[0], self.X.astype(np.float32))
        self.written = True
        stats = self.stats
        outcome = "Refined" if stats["converged"] else "Refine did not converge"
        message = (
            f"{outcome} in {self.seconds:.1f} s: {stats['iterations']} Newton iterations, objective "
            f"{stats['initial_energy']:.5g} -> {stats['energy']:.5g}"
        )
        return ("INFO" if stats["converged"] else "WARNING"), message
