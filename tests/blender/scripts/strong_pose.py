"""Suzanne (subdivided twice, baked through the operator) under strong poses (issue 22): turns of
90 and 170 degrees about her longest axis and bends of 90 and 180 degrees converge without a
stall, with the objective continuous along the way (support.strong_poses, as the pytest cases)."""

import bpy
from support import blender as support
from support import strong_poses

storage, core = support.enable_addon("storage", "core")

obj = support.suzanne(2)  # 7,958 vertices
obj.modal_deform.ghost = 1000
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
basis = storage.load(obj)
for pose in strong_poses.POSES:
    path = strong_poses.follow(core, basis, basis.rest, pose, check_differences=True)
    assert not any(step["stalled"] for step in path), (pose, path)
    assert path[-1]["converged"], (pose, path[-1])
    worst = max(step["difference_error"] for step in path)
    assert worst < 1e-4, (pose, worst)
    print(pose, sum(step["iterations"] for step in path), "iterations, energy", path[-1]["energy"])
