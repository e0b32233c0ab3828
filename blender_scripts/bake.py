"""Bake an object's basis from the command line and save the file.

    blender -b scene.blend --python blender_scripts/bake.py -- --object Suzanne --modes 20 --derivatives 52 \\
        --ghost 1000

Options left out keep the object's settings (Sidebar > Modal Deform > Basis). Exits with code 1
and the reason when the bake fails.
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
    parser.add_argument("--object", required=True, help="name of the mesh object to bake")
    parser.add_argument("--modes", type=int, help="vibration modes, rigid motions included")
    parser.add_argument("--derivatives", type=int, help="modal derivatives")
    parser.add_argument("--ghost", type=int, help="ghost vertices")
    parser.add_argument("--energy", choices=("SHELLS", "ARAP"), help="deformation energy")
    parser.add_argument("--bending", type=float, help="Discrete Shells bending weight")
    parser.add_argument("--membrane", type=float, help="Discrete Shells stretching weight")
    parser.add_argument("--output", help="save here instead of over the opened file")
    return parser.parse_args(argv)


def main():
    args = arguments()
    addon_utils.enable("modal_deform", default_set=True)
    obj = bpy.data.objects.get(args.object)
    if obj is None or obj.type != "MESH":
        sys.exit(f"--object: no mesh object named {args.object!r} in {bpy.data.filepath or 'the file'}")
    settings = obj.modal_deform
    for name in ("modes", "derivatives", "ghost", "energy", "bending", "membrane"):
        if getattr(args, name) is not None:
            setattr(settings, name, getattr(args, name))
    bpy.context.view_layer.objects.active = obj
    try:
        bpy.ops.modal_deform.bake()
    except RuntimeError as error:
        sys.exit(str(error))
    status = settings.status
    print(f"baked {obj.name}: {status.dimension} dimensions, ghost {status.ghost_vertices} vertices, "
          f"{status.seconds:.1f} s")
    path = args.output or bpy.data.filepath
    if not path:
        sys.exit("--output: the opened file has no path to save to")
    bpy.ops.wm.save_as_mainfile(filepath=str(pathlib.Path(path).resolve()))


main()
