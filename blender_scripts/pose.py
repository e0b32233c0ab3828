"""Solve the pose of a baked object with handles, headless, for its controllers as saved, and save.

    blender -b scene.blend --python blender_scripts/pose.py -- --object Suzanne
    blender -b scene.blend --python blender_scripts/pose.py -- --object Suzanne --frames 1 48

With --frames the controllers' animation is solved frame by frame into the per-frame cache kept in
the file (Bake Animation; with Dynamics on, simulated); without, the current frame into the
"Modal Deform" shape key (Solve).
"""

import pathlib
import sys

import bpy

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import headless  # noqa: E402 (found through the line above)


def main():
    parser = headless.argument_parser(__doc__)
    parser.add_argument(
        "--frames", type=int, nargs=2, metavar=("START", "END"), help="bake this frame range"
    )
    args = headless.parse(parser)
    headless.active_mesh_object(args.object)
    if args.frames:
        headless.run(
            bpy.ops.modal_deform.bake_animation,
            frame_start=args.frames[0],
            frame_end=args.frames[1],
        )
    else:
        headless.run(bpy.ops.modal_deform.solve)
    headless.save(args.output)


main()
