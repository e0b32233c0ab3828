"""Blender with a window (under Xvfb, --enable-event-simulate): pose through the UI as an artist does.

Bake Suzanne, add a handle, start the Pose operator from the sidebar's context, grab the controller
with a simulated G + mouse motion + click, let the timer solve, check the mesh followed (shown in
its vertex positions: Suzanne has no shape keys); Esc restores the mesh; saving mid-pose writes
the rest mesh and the pose in its shape key; entering Edit Mode mid-pose keeps the pose in the key
and edits the rest mesh; the converged pose equals the Solve operator's; undo takes a bake back; Esc
takes an animation bake's frames back; the timeline plays with Dynamics on (simulated into the cache,
scrubbing reads it); disabling the add-on mid-pose restores as Esc does (from the
shape key and from the positions).
Each step runs from bpy.app.timers so Blender handles the simulated events in between (window.run).
Writes OUTPUT/result.json ({"ok": bool, "log": [...]}) and screenshots, then quits.
"""

import importlib
import os
import threading

import addon_utils
import bpy
import numpy as np
from mathutils import Vector
from support.blender import evaluated_positions, key_positions, positions
from window import (
    enable_addon,
    output,
    override,
    press,
    run,
    say,
    screenshot,
    show_sidebar_tab,
    subdivided_suzanne,
    transform_with_mouse,
    view3d,
    wait_until,
)


def steps():
    enable_addon()
    from modal_deform import ops_common
    from modal_deform.pose import displays, posing

    # Scene: Suzanne (2 subdivision levels, 7,958 vertices) seen from the front, sidebar open.
    obj = subdivided_suzanne(2)
    settings = obj.modal_deform
    settings.ghost = 500

    # Bake as the button does: on a thread, with progress; Esc cancels and changes nothing.
    def baking():
        return any(thread.name == "modal_deform bake" for thread in threading.enumerate())

    window, _, region = view3d()
    with override():
        assert bpy.ops.modal_deform.bake("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    yield 0.3
    assert baking(), "the bake is not running on its thread"
    press("ESC", region.x + 10, region.y + 10)
    yield from wait_until(lambda: not baking(), 60)
    yield 0.5  # the operator's next timer event ends it
    assert obj.modal_deform.basis is None and not any(
        p.name.startswith(".Modal") for p in bpy.data.palettes
    )
    say("bake cancelled with Esc: nothing changed")

    # Undo takes a bake back (the bake's datablock and status go with it); redo brings it again.
    with override():
        bpy.ops.ed.undo_push(message="Before bake")
        # Called from Python an operator pushes an undo step only when asked (third argument).
        assert bpy.ops.modal_deform.bake("EXEC_DEFAULT", True) == {"FINISHED"}
        assert bpy.data.objects["Suzanne"].modal_deform.basis is not None
        bpy.ops.ed.undo()
    yield 0.2
    assert bpy.data.objects["Suzanne"].modal_deform.basis is None, "undo did not take the bake back"
    with override():
        bpy.ops.ed.redo()
    yield 0.2
    obj = bpy.data.objects["Suzanne"]  # undo re-reads the data: earlier references are gone
    settings = obj.modal_deform
    assert settings.basis is not None, "redo did not bring the bake back"
    say("bake, undo, redo: ok")

    # A handle on the top of the head (Edit Mode selection -> vertex group + Empty), the chin pinned.
    V = positions(obj)
    rest = V.copy()
    for mask, pinned in ((V[:, 2] > 0.55, False), (V[:, 2] < -0.55, True)):
        obj.data.polygons.foreach_set("select", np.zeros(len(obj.data.polygons), bool))
        obj.data.edges.foreach_set("select", np.zeros(len(obj.data.edges), bool))
        obj.data.vertices.foreach_set("select", mask)
        with override():
            bpy.context.view_layer.objects.active = obj
            bpy.ops.object.mode_set(mode="EDIT")
            assert bpy.ops.modal_deform.add_handle() == {"FINISHED"}
            bpy.ops.object.mode_set(mode="OBJECT")
        if pinned:
            settings.handles[-1].controller = None
    top = settings.handles[0]
    controller = top.controller
    group = np.flatnonzero(V[:, 2] > 0.55)

    window, area, region = view3d()
    with override():
        bpy.ops.view3d.view_axis(type="FRONT")
        bpy.ops.view3d.view_all()
        area.spaces.active.show_region_ui = True
    yield 0.5

    # Start posing the way the Pose button does, select the controller, grab it: G, move, click.
    with override():
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
        for o in bpy.context.view_layer.objects:
            o.select_set(False)
        controller.select_set(True)
        bpy.context.view_layer.objects.active = controller
    yield 0.3
    assert ops_common.running is not None
    x, y = region.x + region.width // 2, region.y + region.height // 2
    yield from transform_with_mouse("G", (x, y), (x + 120, y + 60))
    moved = np.array(controller.matrix_world.translation) - np.array(
        obj.matrix_world @ Vector(rest[group].mean(axis=0))
    )
    assert np.linalg.norm(moved) > 0.1, f"the grab did not move the controller ({moved})"
    say("controller moved by", np.round(moved, 3).tolist())

    # The timer solves until converged; the mesh follows the controller. Suzanne has no shape keys:
    # the pose is shown in its vertex positions, the mesh flagged as posed meanwhile.
    yield from wait_until(lambda: ops_common.running.pose.stats["converged"], 30)
    assert type(ops_common.running.shown) is displays.PositionsDisplay
    assert obj.data.shape_keys is None and obj.data.get(displays.POSING_FLAG)
    pose = positions(obj)
    followed = pose[group].mean(axis=0) - rest[group].mean(axis=0)
    assert np.linalg.norm(followed - moved) < 0.05 * np.linalg.norm(moved), (followed, moved)
    say(
        "mesh followed by",
        np.round(followed, 3).tolist(),
        "at",
        f"{ops_common.running.tick_ms:.1f} ms per update",
    )
    yield from show_sidebar_tab()
    yield 0.5
    screenshot("pose.png")

    # Esc: the mesh is as it was (Suzanne had no shape keys).
    press("ESC", x, y)
    yield 0.3
    assert ops_common.running is None, "Esc did not end the pose"
    assert obj.data.shape_keys is None, "Esc left shape keys behind"
    assert positions(obj).tobytes() == rest.tobytes()
    assert obj.data.get(displays.POSING_FLAG) is None
    say("Esc restored the mesh")

    # Saving while the pose is in the vertex positions: the file has the rest mesh and the pose in
    # its shape key, and the pose goes on in the key; Esc then takes the keys away again.
    placed = controller.location.copy()
    with override():
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    controller.location.x += 0.2
    yield 0.5
    posed = positions(obj)
    assert np.abs(posed - rest).max() > 0.05, "the pose did not follow the controller"
    saved = os.path.join(output, "saved_while_posing_positions.blend")
    bpy.ops.wm.save_as_mainfile(filepath=saved, copy=True)
    assert positions(obj).tobytes() == rest.tobytes(), "saving left the pose in the base mesh"
    with bpy.data.libraries.load(saved) as (data_from, data_to):
        data_to.objects = [obj.name]
    copy = data_to.objects[0]
    assert positions(copy).tobytes() == rest.tobytes(), "the saved base mesh is not the rest mesh"
    assert copy.data.get(displays.POSING_FLAG) is None
    assert np.abs(key_positions(copy, posing.POSE_KEY) - posed).max() < 1e-5, (
        "the saved pose is not the pose"
    )
    bpy.data.objects.remove(copy)
    controller.location.x -= 0.1
    yield 0.5
    assert np.abs(key_positions(obj, posing.POSE_KEY) - posed).max() > 0.01, (
        "the pose stopped after saving"
    )
    press("ESC", x, y)
    yield 0.3
    assert ops_common.running is None and obj.data.shape_keys is None
    assert positions(obj).tobytes() == rest.tobytes()
    say("saving mid-pose wrote the rest mesh and the pose's key; Esc restored the mesh")

    # Tab into Edit Mode while the pose is in the vertex positions: the pose goes into the shape key
    # and Edit Mode edits the rest mesh.
    with override():
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    controller.location.x += 0.1
    yield 0.5
    posed = positions(obj)
    with override():
        controller.select_set(False)
        obj.select_set(True)
        bpy.context.view_layer.objects.active = obj
    press("TAB", x, y)
    yield 0.5
    assert ops_common.running is None, "Edit Mode did not end the pose"
    assert obj.mode == "EDIT"
    with override():
        bpy.ops.object.mode_set(mode="OBJECT")
    assert positions(obj).tobytes() == rest.tobytes(), "Edit Mode took the pose for the rest mesh"
    assert key_positions(obj, "Basis").tobytes() == rest.tobytes()
    assert np.abs(key_positions(obj, posing.POSE_KEY) - posed).max() < 0.05, "the pose was not kept"
    assert obj.data.get(displays.POSING_FLAG) is None
    obj.shape_key_clear()
    controller.location = placed
    with override():
        for o in bpy.context.view_layer.objects:
            o.select_set(False)
        controller.select_set(True)
        bpy.context.view_layer.objects.active = controller
    say("Edit Mode mid-pose kept the pose in the key and edits the rest mesh")

    # The Solve operator at convergence gives the pose the interactive one converged to.
    with override():
        assert bpy.ops.modal_deform.solve(tolerance=1e-8) == {"FINISHED"}
    solved = key_positions(obj, posing.POSE_KEY)
    difference = np.abs(solved - pose).max() / np.ptp(rest, axis=0).max()
    assert difference < 5e-3, f"solve and interactive pose differ by {difference:.2%} of the size"
    say(f"solve equals the interactive pose within {difference:.1e} of the size")
    yield 0.5
    screenshot("solved.png")

    # Saving while posing writes a consistent file: the base mesh as it was, the pose key, the basis.
    with override():
        bpy.ops.ed.undo_push(message="Solved")
        # Started from Python, an operator records its undo step only when asked (third argument).
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT", True) == {"RUNNING_MODAL"}
    controller.location.x -= 0.2
    yield 0.5
    saved = os.path.join(output, "saved_while_posing.blend")
    bpy.ops.wm.save_as_mainfile(filepath=saved, copy=True)
    posed = key_positions(obj, posing.POSE_KEY)
    with bpy.data.libraries.load(saved) as (data_from, data_to):
        data_to.objects = [obj.name]
    copy = data_to.objects[0]
    assert positions(copy).tobytes() == rest.tobytes(), "the saved base mesh is not the rest mesh"
    assert np.abs(key_positions(copy, posing.POSE_KEY) - posed).max() < 0.05, (
        "the saved pose is not the pose"
    )
    assert (
        copy.modal_deform.basis is not None
        and copy.modal_deform.status.dimension == settings.status.dimension
    )
    bpy.data.objects.remove(copy)

    # Enter applies; Ctrl+Z takes the applied pose back.
    before = key_positions(obj, posing.POSE_KEY).tobytes()
    press("RET", x, y)
    yield 0.3
    assert ops_common.running is None, "Enter did not end the pose"
    assert key_positions(obj, posing.POSE_KEY).tobytes() != key_positions(obj, "Basis").tobytes()
    press("Z", x, y, ctrl=True)
    yield 0.5
    obj = bpy.data.objects["Suzanne"]  # undo re-reads the data
    controller = obj.modal_deform.handles[0].controller
    assert positions(obj).tobytes() == rest.tobytes()
    undone = key_positions(obj, posing.POSE_KEY).tobytes()
    assert undone == solved.tobytes(), "Ctrl+Z did not take the applied pose back to the solved one"
    say("saving while posing wrote a consistent file; Enter applied and Ctrl+Z took it back")

    # Bake Animation as the button does: a frame per timer tick into the cache, with progress; Esc
    # puts the cache back as it was (none).
    keys = [(b.name, b.mute) for b in obj.data.shape_keys.key_blocks]
    with override():
        assert bpy.ops.modal_deform.bake_animation(
            "INVOKE_DEFAULT", frame_start=1, frame_end=1000
        ) == {"RUNNING_MODAL"}
    yield 0.5
    cache = obj.modal_deform.dynamics.cache
    assert cache is not None and cache["frames"] > 0, "the animation bake cached no frame"
    press("ESC", x, y)
    yield 0.3
    assert obj.modal_deform.dynamics.cache is None, "Esc left the cache behind"
    assert [(b.name, b.mute) for b in obj.data.shape_keys.key_blocks] == keys, (
        "Esc changed the shape keys"
    )
    assert positions(obj).tobytes() == rest.tobytes()
    say("animation bake cancelled with Esc: its cached frames went")

    # Secondary motion played in the window: Dynamics on, the controller keyed to slide and stop, the
    # timeline played: every frame shown is simulated into the cache (frames Blender drops to keep
    # time are simulated on the way), read through a stand-in while playing (Blender 4+); stopped, the
    # stand-in is gone and scrubbing back reads the cache.
    from modal_deform.playback import frame_cache, frame_display, timeline

    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 48
    scene.frame_set(1)
    controller.keyframe_insert("location", frame=1)
    controller.location.x += 0.4
    controller.keyframe_insert("location", frame=4)
    dynamics = obj.modal_deform.dynamics  # obj was read again after the undo above
    dynamics.enabled = True
    with override():
        bpy.ops.screen.animation_play()
    yield from wait_until(lambda: scene.frame_current >= 16, 60)
    playing_stand_in = frame_display.has_stand_in(obj)
    with override():
        bpy.ops.screen.animation_cancel(restore_frame=False)
    yield 0.3
    assert playing_stand_in == hasattr(bpy.app.handlers, "animation_playback_pre"), (
        "no stand-in while playing"
    )
    assert not frame_display.has_stand_in(obj) and not [
        o for o in bpy.data.objects if o.get(frame_display.STAND_IN)
    ], "a stand-in after playback stopped"
    cache = frame_cache.get(obj)
    assert timeline.problems.get(obj.name) is None, timeline.problems
    assert cache is not None and cache.kind == "DYNAMIC", "playing made no cache"
    assert cache.end >= 16, (
        f"playing simulated frames {cache.start} to {cache.end} of {scene.frame_current}"
    )
    screenshot("dynamics.png")
    shown = evaluated_positions(obj)
    assert np.abs(shown - rest).max() > 0.1, "the played mesh did not follow the controller"
    expected = np.empty_like(shown)
    timeline.player(obj, scene).positions(cache.state(8)[0], expected)
    with override():
        scene.frame_set(8)
    assert evaluated_positions(obj).tobytes() == expected.tobytes(), (
        "scrubbing did not read the cache"
    )
    assert positions(obj).tobytes() == rest.tobytes()
    played = cache.end
    with override():
        assert bpy.ops.modal_deform.free_cache() == {"FINISHED"}
    dynamics.enabled = False
    controller.animation_data_clear()
    controller.location.x -= 0.4
    scene.frame_set(1)
    yield 0.3
    say(
        f"timeline played with Dynamics on: {played} frames simulated and cached, scrubbing reads them"
    )

    # Disabling the add-on while posing ends the pose as Esc does. Solve's key was there before, the
    # only key that moves the mesh: posed in a stand-in, and the artist's mesh is put back.
    before = key_positions(obj, posing.POSE_KEY).tobytes()
    mesh = obj.data
    with override():
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    controller.location.z += 0.3
    yield 0.5
    assert type(ops_common.running.shown) is displays.StandInDisplay and obj.data != mesh
    assert positions(obj).tobytes() != rest.tobytes(), "the pose did not follow the controller"
    addon_utils.disable("modal_deform", default_set=True)
    assert ops_common.running is None, "disabling the add-on left the pose running"
    assert obj.data == mesh, "disabling did not put the artist's mesh back"
    assert key_positions(obj, posing.POSE_KEY).tobytes() == before, (
        "disabling changed the shape key"
    )
    assert positions(obj).tobytes() == rest.tobytes()
    # Blender frees the ended pose's modal handler at the next event it handles (the artist's next
    # click in Preferences); Blender 4.3 crashes when a modal operator starts before that.
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    yield 0.5
    say("disabling the add-on mid-pose put the artist's mesh back")

    # And with the pose in the vertex positions (no shape keys): the rest mesh comes back exactly.
    addon_utils.enable("modal_deform", default_set=True)
    ops_common = importlib.import_module("modal_deform.ops_common")
    displays = importlib.import_module("modal_deform.pose.displays")
    obj.shape_key_clear()
    with override():
        assert bpy.ops.modal_deform.pose("INVOKE_DEFAULT") == {"RUNNING_MODAL"}
    controller.location.z -= 0.3
    yield 0.5
    assert type(ops_common.running.shown) is displays.PositionsDisplay
    assert np.abs(positions(obj) - rest).max() > 0.05, "the pose did not follow the controller"
    addon_utils.disable("modal_deform", default_set=True)
    assert ops_common.running is None, "disabling the add-on left the pose running"
    assert positions(obj).tobytes() == rest.tobytes(), (
        "disabling did not restore the vertex positions"
    )
    assert obj.data.shape_keys is None and obj.data.get(displays.POSING_FLAG) is None
    say("disabling the add-on mid-pose restored the vertex positions")


run(steps)
