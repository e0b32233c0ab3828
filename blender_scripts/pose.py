"""Solve the pose of a baked object with handles, headless, for its controllers as saved, and save.

    blender -b scene.blend --python blender_scripts/pose.py -- --object Suzanne
    blender -b scene.blend --python blender_scripts/pose.py -- --object Suzanne --frames 1 48

With --frames the controllers' animation is solved frame by frame into shape keys (Bake
Animation); without, the current frame into the "Modal Deform" shape key (Solve).
"""
import argparse
import pathlib
import sys

import addon_utils
import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python_addon"))


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--object", required=True, help="name of the baked mesh object")
    parser.add_argument("--frames", type=int, nargs=2, metavar=("START", "END"), help="bake this frame range")
    parser.add_argument("--output", help="save here instead of over the opened file")
    return parser.parse_args(argv)


def main():
    args = arguments()
    addon_utils.enable("modal_deform", default_set=True)
    obj = bpy.data.objects.get(args.object)
    if obj is None or obj.type != "MESH":
        sys.exit(f"--object: no mesh object named {args.object!r} in {bpy.data.filepath or 'the file'}")
    bpy.context.view_layer.objects.active = obj
    try:
        if args.frames:
            bpy.ops.modal_deform.bake_animation(frame_start=args.frames[0], frame_end=args.frames[1])
        else:
            bpy.ops.modal_deform.solve()
    except RuntimeError as error:
        sys.exit(str(error))
    path = args.output or bpy.data.filepath
    if not path:
        sys.exit("--output: the opened file has no path to save to")
    bpy.ops.wm.save_as_mainfile(filepath=str(pathlib.Path(path).resolve()))


main()
