"""A posing session of one object: its stored basis, its handles and a reduced solver, writing the
result into a shape key. Shared by the interactive pose, the solve and the animation bake.

Per update: controller matrices → set_transforms → solve (within a time budget) →
positions(out=the shape key's own array, mesh_io.shape_key_co) → mesh.update().
"""
import numpy as np

from . import core as mdc
from . import handles, mesh_io, storage

POSE_KEY = "Modal Deform"
#: The most BFGS iterations one update takes however much of its time budget is left: far more
#: than a budget of milliseconds allows (an iteration costs 0.2 ms at 67 dimensions), so the
#: budget or convergence ends an update.
MAX_ITERATIONS_PER_UPDATE = 1000


class Pose:
    """Raises storage.NotReady (not baked, stale, damaged), handles.HandleError or ValueError (a
    solver option out of range) with a message for the artist."""

    def __init__(self, context, obj):
        settings = obj.modal_deform
        self.obj = obj
        self.basis = storage.ready_basis(obj)
        self.handles, self.warnings = handles.resolve(obj, context.scene, self.basis.rest)
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

    def converge(self, max_iterations=2000, tolerance=1e-6):
        """Iterate until the stopping test holds (or max_iterations): the result a script wants."""
        stats = self.solver.solve(max_iterations=max_iterations, tolerance=tolerance)
        self.stats = stats
        return stats

    def write(self, block):
        """x̄ + U q into the shape key `block` of the object's mesh: the solver writes (in parallel)
        straight into Blender's array, which saves a copy of 19 MB per update at 1.6M vertices."""
        mesh = self.obj.data
        self.solver.positions(mesh_io.shape_key_co(mesh, block))
        mesh.update()


def state(stats):
    """How a solve ended, for the artist: "converged", "stalled" (no step lowers the objective:
    the mesh stops following the controllers and the pose shown is not a solution) or "solving"."""
    if stats["converged"]:
        return "converged"
    return "stalled" if stats.get("stalled") else "solving"


STALLED_HINT = "the solver cannot follow this pose (no step lowers its energy); ease the controllers back or re-bake"


class ShapeKeyState:
    """What a shape key of obj looks like now, to put it back exactly (Esc): whether the mesh had
    shape keys, the key's positions, value and mute, the active key and solo display."""

    def __init__(self, obj, name):
        self.obj, self.name = obj, name
        keys = obj.data.shape_keys
        block = keys.key_blocks.get(name) if keys else None
        self.co = None
        if block is not None:
            self.co = np.empty(3 * len(block.data), np.float32)
            block.data.foreach_get("co", self.co)
            self.value, self.mute = block.value, block.mute
        self.active_index = obj.active_shape_key_index
        self.show_only = obj.show_only_shape_key
        self.created = []

    def ensure(self):
        """The key, created if needed (with a Basis key when the mesh had none), shown at value 1."""
        block, self.created = mesh_io.shape_key(self.obj, self.name)
        block.value, block.mute = 1.0, False
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
