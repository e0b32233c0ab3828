"""A solve that cannot make progress says so (issue 22): with the reduced solver reporting a stall
(no step lowers the objective), Solve warns with the hint for the artist, and the interactive
pose's header names the stall; a converged solve says neither."""

import sys

import bpy
from support import blender as support

posing, core = support.enable_addon("pose.posing", "core")
obj, rest = support.baked_suzanne(0, 10, 20, 300)
top = support.top_and_bottom_handles(obj, rest)
top.controller.location.y += 0.15
bpy.context.view_layer.update()

assert bpy.ops.modal_deform.solve() == {"FINISHED"}
converged = posing.Pose(bpy.context, obj)
converged.follow_controllers()
stats = converged.converge()
assert posing.state(stats) == "converged", stats
assert "stalled" not in posing.header_text(stats, 1.0)

# The solver as it ends at a stall: the call made no progress and did not converge.
solve = core.ReducedSolver.solve
core.ReducedSolver.solve = lambda self, *args, **kwargs: dict(
    solve(self, *args, **kwargs), converged=False, stalled=True
)
print("SOLVE_WITH_STALL")
sys.stdout.flush()
assert bpy.ops.modal_deform.solve() == {
    "FINISHED"
}  # the pose so far stays in the key, with a warning
sys.stdout.flush()
stalled = posing.Pose(bpy.context, obj)
stalled.follow_controllers()
header = posing.header_text(stalled.step(10.0), 2.5)
assert header.startswith("Modal Deform: stalled: ") and posing.STALLED_HINT in header, header
