"""Dynamics on a rig keeps the bake's material (issue 50, item 2): three tubes skinned to one chain of
bones, attached at their base, jump with the armature object: one of uniform material, one whose top
half is painted stiff (a Stiffness group), one baked with its upper two thirds as its Region. The stiff top
lags less than the uniform one; outside the Region the mesh is the Armature modifier's result to
the bit, while inside it lags as on the whole mesh."""

import bpy
import numpy as np
from support import blender as support
from support import rig as rig_support

timeline, frame_display, mdc = support.enable_addon(
    "playback.timeline", "playback.frame_display", "core"
)
scene, view_layer = bpy.context.scene, bpy.context.view_layer
LENGTH, BONES = 3.0, 3
V, F = mdc.testing.cylinder(12, 24, radius=0.2, length=LENGTH)
size = np.ptp(V, axis=0).max()
top = V[:, 2] > LENGTH / 2

first = support.mesh_object("Uniform", V, F)
tubes = [first]
for name in ("Stiff top", "Top region"):
    tube = bpy.data.objects.new(name, first.data.copy())
    scene.collection.objects.link(tube)
    tubes.append(tube)

armature = rig_support.chain_armature("Rig", BONES, LENGTH)

# Weights: each vertex to the bone along it (rigid segments), so that skinning alone moves nothing
# relative to the bones and the lag is the simulation's.
bone_of = np.minimum((V[:, 2] / (LENGTH / BONES)).astype(int), BONES - 1)


def group(tube, name, indices, weight=1.0):
    found = tube.vertex_groups.get(name) or tube.vertex_groups.new(name=name)
    found.add([int(i) for i in indices], weight, "REPLACE")
    return found


for tube in tubes:
    rig_support.skin(tube, armature, np.eye(BONES)[bone_of])
    tube.parent = armature
    settings = tube.modal_deform
    settings.modes, settings.derivatives, settings.ghost = 12, 20, 300
group(tubes[1], "Stiff", np.flatnonzero(top))
tubes[1].modal_deform.stiffness_group = "Stiff"
group(tubes[2], "Region", np.flatnonzero(V[:, 2] > LENGTH / 3))
tubes[2].modal_deform.region_group = "Region"
for tube in tubes:
    view_layer.objects.active = tube
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}, tube.name
    group(tube, "Attach", np.flatnonzero(V[:, 2] < 0.4))
    dynamics = tube.modal_deform.dynamics
    dynamics.attach_group = "Attach"
    dynamics.enabled, dynamics.follow_rig = True, True
    dynamics.period, dynamics.damping = 8.0, 0.3

armature.keyframe_insert("location", frame=4)
armature.location.x += 1.5
armature.keyframe_insert("location", frame=8)
scene.frame_start, scene.frame_end = 1, 40

lag = {tube.name: [] for tube in tubes}
region_bits = []
reference = tubes[2].copy()  # the Armature modifier alone, for the vertices outside the Region
scene.collection.objects.link(reference)
reference.modal_deform.dynamics.enabled = False
for modifier in [m for m in reference.modifiers if m.type == "NODES"]:
    reference.modifiers.remove(modifier)
outside = V[:, 2] <= LENGTH / 3
for frame in range(1, 41):
    scene.frame_set(frame)
    for tube in tubes:
        assert tube.name not in timeline.problems, timeline.problems[tube.name]
        offset = frame_display.offset_values(tube.data)
        lag[tube.name].append(np.abs(offset[top & (V[:, 2] > LENGTH - 0.3)]).max() / size)
    offset = frame_display.offset_values(tubes[2].data)
    assert not offset[outside].any(), (frame, np.abs(offset[outside]).max())
    shown = support.evaluated_positions(tubes[2])
    expected = support.evaluated_positions(reference)
    region_bits.append(shown[outside].tobytes() == expected[outside].tobytes())
assert all(region_bits), region_bits

uniform, stiff, region = (max(lag[t.name]) for t in tubes)
print(
    f"material on a rig: the free end's largest lag, of the size: uniform {uniform:.4f}, "
    f"stiff top {stiff:.4f}, top region {region:.4f}"
)
assert uniform > 0.01, uniform
assert stiff < 0.75 * uniform, (stiff, uniform)  # Period sets the lowest mode: a ratio, not 0
assert region > 0.3 * uniform, (region, uniform)
print("rig material: all checks passed")
