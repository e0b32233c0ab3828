"""The viewport's frame time while posing, in Blender with a window (Debian's 3.4.1 app under Xvfb:
software OpenGL, so the drawing figures are reported, not targets).

    xvfb-run -a -s "-screen 0 1280x800x24" blender --factory-startup --python bench/viewport_frames.py -- \
        OUTPUT.json [--subdivide N] [--updates N] [--modes M --derivatives D] [--proxy-above N --proxy P]

The dragon (100k vertices; subdivided N times: 400k, 1.6M) baked as the bench bakes it (or smaller
with the options), a handle moved every frame. A frame is the pose update of bench/blender_pose.py
(the Pose operator's calls, Blender's evaluation), then the viewport drawn and swapped
(wm.redraw_timer DRAW_WIN_SWAP): "draw" is what Blender does to show the new pose (normals, GPU
buffers, drawing). Each display (vertex positions, stand-in, shape key) in turn, A B C A B C; medians, ms.
Writes OUTPUT.json ({"ok", "log", "vertices", "displays": {display: {step: ms}}}) and quits.
"""

import argparse
import json
import pathlib
import sys
import traceback

import bpy

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import blender_pose  # noqa: E402 (found through the line above; blender_pose puts blender_scripts on the path)
from headless import enable_addon  # noqa: E402

argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
parser = argparse.ArgumentParser(
    description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
)
parser.add_argument("output")
parser.add_argument("--subdivide", type=int, default=0)
parser.add_argument("--updates", type=int, default=15, help="frames per display and round")
parser.add_argument("--modes", type=int, default=16)
parser.add_argument("--derivatives", type=int, default=45)
parser.add_argument(
    "--proxy-above", type=int, help="the object's Proxy Above (default: the add-on's)"
)
parser.add_argument("--proxy", type=int, help="the object's Proxy Size (default: the add-on's)")
args = parser.parse_args(argv)
bpy.context.preferences.view.show_splash = False


def view3d():
    window = bpy.context.window_manager.windows[0]
    area = next(a for a in window.screen.areas if a.type == "VIEW_3D")
    return window, area, next(r for r in area.regions if r.type == "WINDOW")


def measure():
    blender_pose.ADDON = enable_addon().__name__
    blender_pose.clear_scene()
    obj, vertices, moving = blender_pose.posed_dragon("dragon_vrip_res2", args.subdivide)
    settings = obj.modal_deform
    settings.modes, settings.derivatives, settings.ghost = args.modes, args.derivatives, 1000
    if args.proxy_above is not None:
        settings.proxy_above = args.proxy_above
    if args.proxy is not None:
        settings.proxy = args.proxy
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    window, area, region = view3d()
    with bpy.context.temp_override(window=window, screen=window.screen, area=area, region=region):
        bpy.ops.view3d.view_all()

        def draw():
            bpy.ops.wm.redraw_timer(type="DRAW_WIN_SWAP", iterations=1)

        figures = blender_pose.time_displays(obj, moving.controller, args.updates, draw=draw)
    for f in figures.values():
        f["frame"] = f["update"] + f["draw"]
    return {
        "vertices": vertices,
        "dimension": settings.status.dimension,
        "proxy_vertices": settings.status.proxy_vertices,
        "blender": bpy.app.version_string,
        "displays": figures,
    }


def run():
    result = {"ok": False, "log": []}
    try:
        result.update(measure(), ok=True)
        for display, f in result["displays"].items():
            result["log"].append(
                f"{result['vertices']} vertices, {display}: frame {f['frame']:.1f} ms = ours "
                f"{f['tick']:.1f} + Blender's evaluation {f['evaluate']:.1f} + drawing {f['draw']:.1f}"
            )
    except Exception:
        result["log"].append(traceback.format_exc())
    print("\n".join(result["log"]), flush=True)
    pathlib.Path(args.output).write_text(json.dumps(result, indent=1))
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(run, first_interval=0.5)
