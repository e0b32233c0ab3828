"""Blender with a window (under Xvfb): In-betweens solved in the background. With In-betweens on,
the first frame shown starts Solve In-betweens (a modal operator with a progress bar, started from
a timer); a key moved with the timeline still starts it again, and the motion solved before plays
until the new one is ready; Esc cancels it and the old motion stays, with a message in the panel.
The Dynamics panel is screenshotted solving and solved. Writes OUTPUT/result.json (window.run)."""

import threading

import bpy
import numpy as np
from support import blender as support
from window import enable_addon, override, run, say, screenshot, show_sidebar_tab, view3d


def wait_for(condition, what, seconds=300):
    """Yield until condition() holds (a generator: yield from it)."""
    for _ in range(int(seconds / 0.2)):
        if condition():
            return
        yield 0.2
    raise AssertionError(f"waited {seconds} s for {what}")


def to_dynamics_panel():
    """Scroll the sidebar down to the Dynamics panel (a generator: yield from it)."""
    window, area, _ = view3d()
    region = next(r for r in area.regions if r.type == "UI")
    x, y = region.x + region.width // 2, region.y + region.height // 2
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    for _ in range(40):
        window.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=x, y=y)
    yield 1.0


def steps():
    enable_addon()
    from modal_deform.inbetweens import motion
    from modal_deform.playback import frame_cache

    # Each solve waits for the step to let it go (gate.release()), so that a quick solve cannot end
    # before the step has seen it running.
    gate, work = threading.Semaphore(0), motion.InbetweenJob._work

    def held(job):
        gate.acquire(timeout=60)
        work(job)

    motion.InbetweenJob._work = held

    with override():
        obj, V = support.baked_suzanne(1, 12, 20, 400)
        head = support.add_handle(obj, (np.hypot(V[:, 0], V[:, 1]) < 0.55) & (V[:, 2] > -0.35))
    controller = head.controller
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 30
    for frame, turn in ((1, 0.0), (10, 0.5), (20, -0.3)):
        controller.rotation_euler.y = turn
        controller.keyframe_insert("rotation_euler", frame=frame)
    bpy.context.view_layer.objects.active = obj
    yield from show_sidebar_tab()
    yield from to_dynamics_panel()
    obj.modal_deform.dynamics.enabled = obj.modal_deform.dynamics.inbetweens = True
    scene.frame_set(12)  # asks for the motion: solved in the background
    yield from wait_for(lambda: obj.name in motion.running, "the solve to start", 10)
    say("the first frame shown started Solve In-betweens")
    screenshot("inbetweens-solving.png")
    gate.release()
    yield from wait_for(lambda: obj.name not in motion.running, "the solve to end")
    cache = frame_cache.get(obj)
    assert cache is not None and cache.kind == "INBETWEEN" and len(cache) == 30, cache
    first = frame_cache.digest(cache)
    shown = support.evaluated_positions(obj)
    assert not np.array_equal(shown, V), "the solved frame does not show"
    say("solved in the background, the frame shown")
    screenshot("inbetweens-solved.png")

    # A key moved: solved again in the background, the old motion playing meanwhile.
    for curve in controller.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            if point.co.x == 20:
                point.co.y = 0.3 if curve.array_index == 1 else point.co.y
        curve.update()
    controller.animation_data.action.update_tag()
    yield from wait_for(lambda: obj.name in motion.running, "a moved key to start a solve", 10)
    assert frame_cache.digest(frame_cache.get(obj)) == first, "the old motion went before the new"
    gate.release()
    yield from wait_for(lambda: obj.name not in motion.running, "the solve to end")
    second = frame_cache.digest(frame_cache.get(obj))
    assert second != first and not motion.problem(obj), motion.problem(obj)
    say("a moved key solved again in the background")

    # Esc while solving: cancelled, the motion as it was, and the panel says so.
    for curve in controller.animation_data.action.fcurves:
        for point in curve.keyframe_points:
            if point.co.x == 10 and curve.array_index == 1:
                point.co.y = 0.2
        curve.update()
    controller.animation_data.action.update_tag()
    yield from wait_for(lambda: obj.name in motion.running, "a moved key to start a solve", 10)
    window, area, region = view3d()
    x, y = region.x + region.width // 2, region.y + region.height // 2
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    window.event_simulate(type="ESC", value="PRESS", x=x, y=y)
    yield 0.3
    gate.release()
    yield from wait_for(lambda: obj.name not in motion.running, "the cancelled solve to end")
    assert frame_cache.digest(frame_cache.get(obj)) == second, "a cancel changed the motion"
    assert "cancelled" in motion.problem(obj), motion.problem(obj)
    say("Esc:", motion.problem(obj))
    yield 0.5
    screenshot("inbetweens-cancelled.png")


run(steps)
