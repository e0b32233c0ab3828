"""The demo's secondary motion (issue 40): Suzanne's head keyframed to tilt fast and stop (a turn
about the camera's axis, so the ears swing in the picture), her ears and chin following with
inertia, overshooting the pose and settling, played on the timeline (simulated frame after frame
into the cache) and rendered as a strip of frames.

Called by demo.py after its stage (camera, light, Cycles) is set up; run inside Blender.
"""

import math

import bpy
import numpy as np
from headless import add_handle, evaluated_positions, smooth_suzanne
from rendering import render, side_by_side

#: The head's tilt about the camera's axis (degrees) and the frames it starts and stops on.
TURN, TURN_START, TURN_STOP = 35, 1, 6
#: The frames of the strip, from rest through the stop to the settling.
STRIP = (1, 4, 6, 8, 10, 13, 17, 24, 40)
#: Ears and chin swing free: the handle holds Suzanne's vertices within this distance of the
#: vertical axis (her ears reach x = ±1.36) and above her chin.
CORE_RADIUS, CHIN = 0.55, -0.35


def head_handle(suzanne):
    """Bake `suzanne` and hold her head (CORE_RADIUS, CHIN) by a handle, her ears and chin free.
    Returns her rest positions (#V by 3) and the handle's controller."""
    V = np.empty(3 * len(suzanne.data.vertices), np.float32)
    suzanne.data.vertices.foreach_get("co", V)
    V = V.reshape(-1, 3)
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    core = (np.hypot(V[:, 0], V[:, 1]) < CORE_RADIUS) & (V[:, 2] > CHIN)
    return V, add_handle(suzanne, core).controller


def secondary_motion(addon, output, levels, width):
    """Bake a Suzanne subdivided `levels` times, tilt her head and let the ears follow; render the
    STRIP frames (`width` pixels wide each) into OUTPUT/demo_dynamics.png. Returns the strip's path."""
    frame_cache, posing = addon
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = width, width * 3 // 4
    shown = [o for o in bpy.context.scene.objects if o.type == "MESH" and not o.hide_render]
    for obj in shown:
        obj.hide_render = True
    suzanne = smooth_suzanne("Suzanne dynamics", levels)
    V, controller = head_handle(suzanne)
    bpy.context.view_layer.objects.active = suzanne
    scene.frame_set(TURN_START)
    controller.keyframe_insert("rotation_euler", frame=TURN_START)
    controller.rotation_euler.y = math.radians(TURN)
    controller.keyframe_insert("rotation_euler", frame=TURN_STOP)
    suzanne.modal_deform.dynamics.enabled = True
    scene.frame_start, scene.frame_end = TURN_START, max(STRIP)

    # The static pose after the stop, which the ears overshoot and settle to.
    scene.frame_set(max(STRIP))
    pose = posing.Pose(bpy.context, suzanne)
    pose.follow_controllers()
    pose.converge()
    settled = pose.solver.positions()
    # How far the ears are along their way from rest to where they settle: 0 at rest, 1 settled,
    # above 1 overshooting.
    ears = np.abs(V[:, 0]) > 1.0
    way = (settled[ears] - V[ears]).ravel()
    pictures, along = [], []
    for frame in range(1, max(STRIP) + 1):
        scene.frame_set(frame)
        X = evaluated_positions(suzanne)
        along.append(np.dot(X[ears].ravel() - V[ears].ravel(), way) / np.dot(way, way))
        if frame in STRIP:
            pictures.append(render(output / f"demo_dynamics_{frame:02d}.png"))
    print(
        f"the ears' way from rest (0) to where they settle (1), frames 1 to {max(STRIP)}: "
        + " ".join(f"{a:.2f}" for a in along)
    )
    cache = frame_cache.get(suzanne)
    print(
        f"secondary motion: {len(V)} vertices, {len(cache)} frames cached in {cache.nbytes() / 1024:.1f} KB"
    )
    bpy.data.objects.remove(controller)
    bpy.data.objects.remove(suzanne)
    for obj in shown:
        obj.hide_render = False
    strip = output / "demo_dynamics.png"
    side_by_side(pictures, strip)
    return strip
