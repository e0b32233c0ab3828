"""Bake an object's basis from the command line and save the file.

    blender -b scene.blend --python blender_scripts/bake.py -- --object Suzanne --modes 20 --derivatives 52 \\
        --ghost 1000

Options left out keep the object's settings (Sidebar > Modal Deform > Basis). Exits with code 1
and the reason when the bake fails.
"""

import pathlib
import sys

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import headless  # noqa: E402 (found through the line above)

SETTINGS = ("modes", "derivatives", "ghost", "energy", "bending", "membrane")


def main():
    parser = headless.argument_parser(__doc__)
    parser.add_argument("--modes", type=int, help="vibration modes, rigid motions included")
    parser.add_argument("--derivatives", type=int, help="modal derivatives")
    parser.add_argument("--ghost", type=int, help="ghost vertices")
    parser.add_argument("--energy", choices=("SHELLS", "ARAP"), help="deformation energy")
    parser.add_argument("--bending", type=float, help="Discrete Shells bending weight")
    parser.add_argument("--membrane", type=float, help="Discrete Shells stretching weight")
    args = headless.parse(parser)
    obj = headless.active_mesh_object(args.object)
    settings = obj.modal_deform
    for name in SETTINGS:
        if getattr(args, name) is not None:
            setattr(settings, name, getattr(args, name))
    headless.run(bpy.ops.modal_deform.bake)
    status = settings.status
    print(
        f"baked {obj.name}: {status.dimension} dimensions, ghost {status.ghost_vertices} vertices, "
        f"{status.seconds:.1f} s"
    )
    headless.save(args.output)


main()
