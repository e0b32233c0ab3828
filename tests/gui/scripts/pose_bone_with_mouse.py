"""Blender with a window (under Xvfb, --enable-event-simulate): pose with a bone as an artist does.

Suzanne, parented to an armature, baked small, a handle on the top of her head whose controller is
the armature's bone "Head" and one on her chin pinned. The artist enters Pose Mode on the armature
(Ctrl+Tab), starts Pose from there (the sidebar is the mesh's), clicks the bone, turns it with
R + mouse motion + click; the timer solves: the top of the head follows the bone and the chin stays.
Writes OUTPUT/result.json ({"ok": bool, "log": [...]}) and bone-pose.png, then quits.
"""

import bpy
import numpy as np
from bpy_extras.view3d_utils import location_3d_to_region_2d
from mathutils import Vector
from support.blender import baked_suzanne, positions, top_and_bottom_handles
from window import (
    click,
    enable_addon,
    override,
    press,
    run,
    say,
    screenshot,
    show_sidebar_tab,
    transform_with_mouse,
    view3d,
    wait_until,
)


def armature(obj):
    """An armature "Rig" at the origin with one bone "Head" up through Suzanne (from her chin to above
    her head), drawn in front of her; obj parented to it as a rigged character is."""
    rig = bpy.data.objects.new("Rig", bpy.data.armatures.new("Rig"))
    bpy.context.scene.collection.objects.link(rig)
    rig.show_in_front = True
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="EDIT")
    bone = rig.data.edit_bones.new("Head")
    bone.head, bone.tail = (0.0, 0.0, -0.5), (0.0, 0.0, 1.2)
    bpy.ops.object.mode_set(mode="OBJECT")
    obj.parent = rig
    return rig


def on_screen(point):
    """Window coordinates of a world-space point in the 3D Viewport."""
    _, area, region = view3d()
    x, y = location_3d_to_region_2d(region, area.spaces.active.region_3d, point)
    return region.x + round(x), region.y + round(y)


def steps():
    enable_addon()
    from modal_deform import ops_common

    with override():
        obj, rest = baked_suzanne(1, 12, 10, 300)
        bpy.ops.object.shade_smooth()
        top = top_and_bottom_handles(obj, rest)
        empty = top.controller
        rig = armature(obj)
        top.controller, top.bone = rig, "Head"
        bpy.data.objects.remove(empty)
    group, pinned = np.flatnonzero(rest[:, 2] > 0.5), np.flatnonzero(rest[:, 2] < -0.5)
    bone = rig.pose.bones["Head"]

    _, _, region = view3d()
    with override():
        obj.select_set(False)
        rig.select_set(True)
        bpy.context.view_layer.objects.active = rig
        bpy.ops.view3d.view_axis(type="FRONT")
        bpy.ops.view3d.view_all()
    yield 0.5

    # Ctrl+Tab: Pose Mode on the armature; Pose started there (the mesh is the armature's child).
    middle = region.x + region.width // 2, region.y + region.height // 2
    press("TAB", *middle, ctrl=True)
    yield 0.3
    assert rig.mode == "POSE", f"Ctrl+Tab left the armature in {rig.mode}"
    with override():
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    yield 0.3
    assert ops_common.running is not None and ops_common.running.pose.obj == obj

    # Click the bone (none selected before), then turn it about its head: R, the mouse from the
    # bone's upper part to its right, a click.
    bone.bone.select, rig.data.bones.active = False, None
    world = rig.matrix_world
    head, tail = world @ bone.head, world @ bone.tail
    grip = on_screen(head.lerp(tail, 0.8))
    click(*grip)
    yield 0.3
    assert bone.bone.select and rig.data.bones.active == bone.bone, (
        "the click did not select the bone"
    )
    before = world @ bone.matrix
    pivot = on_screen(head)
    reach = grip[1] - pivot[1]
    yield from transform_with_mouse("R", grip, (pivot[0] + reach // 2, grip[1]))
    turn = (world @ bone.matrix) @ before.inverted()
    angle = np.degrees(turn.to_quaternion().angle)
    assert angle > 10, f"R did not turn the bone ({angle:.1f} degrees)"
    say(f"bone turned by {angle:.1f} degrees")

    # The timer solves until converged: the top of the head follows the bone, the chin stays.
    yield from wait_until(lambda: ops_common.running.pose.stats["converged"], 30)
    pose = positions(obj)
    local = obj.matrix_world.inverted() @ turn @ obj.matrix_world
    centre = rest[group].mean(axis=0)
    expected = np.array(local @ Vector(centre)) - centre
    followed = pose[group].mean(axis=0) - centre
    assert np.linalg.norm(followed - expected) < 0.05 * np.linalg.norm(expected), (
        followed,
        expected,
    )
    held = np.linalg.norm(pose[pinned] - rest[pinned], axis=1).max()
    # The handle term is a penalty in a small basis: the chin's centre holds, its vertices nearly.
    drift = np.linalg.norm(pose[pinned].mean(axis=0) - rest[pinned].mean(axis=0))
    assert drift < 0.02 * np.linalg.norm(expected), f"the pinned chin moved by {drift:.3f}"
    assert held < 0.2 * np.linalg.norm(expected), f"a vertex of the pinned chin moved by {held:.3f}"
    say(
        "top of the head followed by",
        np.round(followed.astype(np.float64), 3).tolist(),
        f"(the bone moves it by {np.round(expected, 3).tolist()}),",
        f"the chin's centre by {drift:.4f}, its vertices by at most {held:.3f}",
    )
    yield from show_sidebar_tab(below=262)
    yield 0.5
    screenshot("bone-pose.png")

    press("ESC", *middle)
    yield 0.3
    assert ops_common.running is None, "Esc did not end the pose"
    assert positions(obj).tobytes() == rest.tobytes(), "Esc did not restore the mesh"
    say("Esc restored the mesh")


run(steps)
