"""A posing session of one object: its stored basis, its handles and a reduced solver, writing the
result into a shape key. Shared by the interactive pose, the solve, Refine, the animation bake and
playback.

Per update: controller matrices → set_transforms → solve (within a time budget) →
positions(out=Blender's own array: a shape key's or the vertex positions) → mesh.update().

Where the interactive pose shows the pose while it runs is a display (displays.py); meshes written
mid-pose are repaired by recovery.py. The interactive pose under way is ops_common.running.
"""

import numpy as np

from .. import core as mdc
from .. import handles, mesh_io, storage

POSE_KEY = "Modal Deform"
#: Functions of an object, each taking off it a display that would hide a pose shown there (playback
#: adds its frame display's removal when registered: playback/timeline.py); uncover() calls them.
covers = []
#: The most BFGS iterations one update takes however much of its time budget is left: far more
#: than a budget of milliseconds allows (bench/results/table1.json, "ms_per_iteration"), so the
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
        self.handles, self.warnings = handles.resolve(
            obj, context.scene, self.basis.rest, self.basis.region
        )
        self.solver = mdc.ReducedSolver(
            self.basis,
            [h.indices for h in self.handles],
            pull=settings.stiffness,
            weights=[h.weight for h in self.handles],
            energy=settings.status.energy.lower(),
        )
        self._transforms = None
        self.stats = {"iterations": 0, "energy": 0.0, "converged": False, "stalled": False}

    def follow_controllers(self):
        """Give the solver the controllers' current placement; True when it changed."""
        transforms = handles.transforms(self.obj, self.handles)
        if self._transforms is not None and all(
            np.array_equal(a, b) for a, b in zip(transforms, self._transforms)
        ):
            return False
        self.solver.set_transforms(transforms)
        self._transforms = transforms
        self.stats["converged"] = False
        return True

    def step(self, budget_ms):
        """BFGS iterations until converged or `budget_ms` milliseconds are spent (timed natively)."""
        self.stats = self.solver.solve(
            max_iterations=MAX_ITERATIONS_PER_UPDATE, budget_ms=budget_ms
        )
        return self.stats

    def converge(
        self,
        max_iterations=CONVERGE_MAX_ITERATIONS,
        tolerance=mdc.SOLVE_OPTIONS["tolerance"].default,
    ):
        """Iterate until the stopping test holds (or max_iterations): the result a script wants."""
        stats = self.solver.solve(max_iterations=max_iterations, tolerance=tolerance)
        self.stats = stats
        return stats

    def write(self, co):
        """x̄ + U q into `co`, a view of one of the mesh's arrays in Blender (mesh_io.shape_key_co,
        mesh_io.vertex_positions), and the mesh tagged for redraw. The solver writes (in parallel)
        straight into a contiguous array, which saves a copy of the whole mesh per update;
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
    return (
        f"Modal Deform: {ended}, {stats['iterations']} iterations, energy {stats['energy']:.5g}, "
        f"{tick_ms:.1f} ms per update"
    )


def pose_key(obj):
    """The "Modal Deform" shape key, created if needed (after a Basis key when the mesh has none),
    shown at value 1 (what would hide the key goes: uncover); returns (key block, names of the keys
    created here)."""
    block, created = mesh_io.shape_key(obj, POSE_KEY)
    block.value, block.mute = 1.0, False
    uncover(obj)
    return block, created


def uncover(obj):
    """Take off obj every display that would hide a pose shown there (covers): a frame of playback."""
    for remove in covers:
        remove(obj)
