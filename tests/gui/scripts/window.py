"""What the GUI scripts share: the add-on enabled (support.blender), the 3D Viewport of the window, its
sidebar's Modal Deform tab, screenshots, and the run itself as steps between which Blender handles
the simulated events (run(steps)), ending in OUTPUT/result.json ({"ok": bool, "log": [...]}).

Screenshots: Blender's own operator, or with MODAL_DEFORM_GRAB=x11 a grab of the X screen (xwd, then
ImageMagick's convert): Blender 4.3's operator writes a black image under Xvfb.
"""

import json
import os
import subprocess
import sys
import time
import traceback

import bpy
from support import blender

output = sys.argv[sys.argv.index("--") + 1]
log = []


def say(*words):
    log.append(" ".join(map(str, words)))
    print("GUI:", *words, flush=True)


def enable_addon():
    """Enable Modal Deform (the legacy zip Blender installed into the user folder, else the source
    tree's); fail if it does not register (addon_utils only prints why)."""
    module = blender.enable_addon()
    say(
        f"Blender {bpy.app.version_string} (Python {sys.version.split()[0]}), add-on from {module.__file__}"
    )


def view3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    region = next(r for r in area.regions if r.type == "WINDOW")
    return window, area, region


def sidebar():
    _, area, _ = view3d()
    return next(r for r in area.regions if r.type == "UI")


def override():
    window, area, region = view3d()
    return bpy.context.temp_override(window=window, screen=window.screen, area=area, region=region)


def subdivided_suzanne(levels):
    """Empties the scene and adds Suzanne subdivided `levels` times, shaded smooth; returns her."""
    with override():
        obj = blender.suzanne(levels)
        bpy.ops.object.shade_smooth()
    return obj


def screenshot(path):
    """The whole window as a PNG at path (relative: in OUTPUT)."""
    path = os.path.join(output, path)
    if os.environ.get("MODAL_DEFORM_GRAB") == "x11":
        # The X server shows the last frame Blender swapped, which may predate the latest events.
        window, _, _ = view3d()
        with bpy.context.temp_override(window=window):
            bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)
        subprocess.run(f"xwd -root -silent | convert xwd:- png:{path}", shell=True, check=True)
    else:
        window, _, _ = view3d()
        with bpy.context.temp_override(window=window):
            bpy.ops.screen.screenshot(filepath=path)
    return path


def click(x, y):
    window, _, _ = view3d()
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
    window.event_simulate(type="LEFTMOUSE", value="PRESS", x=x, y=y)
    window.event_simulate(type="LEFTMOUSE", value="RELEASE", x=x, y=y)


def press(key, x, y, **modifiers):
    """A key pressed and released with the mouse at (x, y) in the window (modifiers: ctrl=True...)."""
    window, _, _ = view3d()
    window.event_simulate(type=key, value="PRESS", x=x, y=y, **modifiers)
    window.event_simulate(type=key, value="RELEASE", x=x, y=y, **modifiers)


def transform_with_mouse(key, start, end, steps=10):
    """Move or turn what is selected as an artist does (a generator: yield from it): the mouse at
    start, the key (G, R), the mouse moved to end in steps, a click that confirms."""
    window, _, _ = view3d()
    (x0, y0), (x1, y1) = start, end
    window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x0, y=y0)
    yield 0.1
    press(key, x0, y0)
    yield 0.2
    for i in range(1, steps + 1):
        x, y = x0 + (x1 - x0) * i // steps, y0 + (y1 - y0) * i // steps
        window.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)
        yield 0.05
    click(x1, y1)
    yield 0.2


def wait_until(condition, seconds):
    """Yield to Blender until condition() holds (a generator: yield from it); fail after `seconds`."""
    start = time.time()
    while not condition():
        assert time.time() - start < seconds, f"timed out after {seconds} s"
        yield 0.1


def show_sidebar_tab(below=182):
    """Open the sidebar on its Modal Deform tab (a generator: yield from it) with clicks on its tabs
    (at the sidebar's right edge), as an artist does. Blender 4.x tells the active tab: the clicks
    walk down the tabs until it is Modal Deform. Blender 3.4 does not: a click `below` pixels under
    the sidebar's top, on the last tab of a factory-startup sidebar: 182 in Object Mode (Item, Tool,
    View, Modal Deform), 262 in Pose Mode (Animation before Modal Deform)."""
    _, area, _ = view3d()
    area.spaces.active.show_region_ui = True
    yield 0.3
    region = sidebar()
    x, top = region.x + region.width - 10, region.y + region.height
    if not hasattr(region, "active_panel_category"):
        click(x, top - below)
        yield 0.3
        return
    for y in range(top - 10, top - 400, -15):
        click(x, y)
        yield 0.2
        if region.active_panel_category == "Modal Deform":
            return
    raise AssertionError(
        f"no Modal Deform tab at the sidebar's edge (on {region.active_panel_category})"
    )


def run(steps):
    """Run the generator steps() from Blender's timers (each yield: the seconds to wait), then quit."""
    generator = steps()

    def drive():
        try:
            return next(generator)
        except StopIteration:
            finish(True)
        except Exception:
            say(traceback.format_exc())
            finish(False)
        return None

    bpy.context.preferences.view.show_splash = False
    bpy.app.timers.register(drive, first_interval=0.5)


def finish(ok):
    with open(os.path.join(output, "result.json"), "w") as f:
        json.dump({"ok": ok, "log": log}, f, indent=1)
    bpy.ops.wm.quit_blender()
