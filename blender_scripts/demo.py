"""The main job, headless: bake Suzanne (~31k vertices), pose it strongly with two handles (the top
of the head turned by 30 and bent sideways by 25 degrees against the held chin: a pose with large
rotations, what modal derivatives are for), render before/after.

    blender -b --factory-startup --python blender_scripts/demo.py -- --output out

Writes OUTPUT/demo.png (Cycles on the CPU, rest and posed side by side) and OUTPUT/demo.blend,
ready to pose: select the mesh, Sidebar > Modal Deform > Pose, then move the Empties with G/R.
Prints the bake time and the time per interactive update.
"""
import argparse
import importlib
import math
import pathlib
import sys
import time

import bpy
import numpy as np
from mathutils import Matrix, Vector

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from headless import add_handle, enable_addon  # noqa: E402
from rendering import render, side_by_side, stage  # noqa: E402


#: The pose: the top of the head turned about the vertical and then bent sideways (degrees).
TURN, BEND = 30, 25


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--output", default="out", help="folder for demo.png and demo.blend")
    parser.add_argument("--subdivisions", type=int, default=3, help="Catmull-Clark levels (3: ~31k vertices)")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel")
    parser.add_argument("--width", type=int, default=800, help="width of each of the two pictures, pixels")
    return parser.parse_args(argv)


def subdivided_suzanne(levels):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.mesh.primitive_monkey_add()
    suzanne = bpy.context.object
    modifier = suzanne.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = levels
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    bpy.ops.object.shade_smooth()
    return suzanne


def interactive_updates(posing, obj, count):
    """Time `count` updates of the interactive pose (what each timer tick of the Pose operator does:
    controllers -> solver within its budget -> shape key) after the controllers were placed: the
    first updates solve toward them, the later ones find the pose converged."""
    pose = posing.Pose(bpy.context, obj)
    state = posing.ShapeKeyState(obj, posing.POSE_KEY)
    block = state.ensure()
    times = []
    for _ in range(count):
        start = time.perf_counter()
        pose.follow_controllers()
        pose.step(obj.modal_deform.budget)
        pose.write(block)
        times.append(1e3 * (time.perf_counter() - start))
    state.restore()
    return times


def main():
    args = arguments()
    posing = importlib.import_module(f"{enable_addon().__name__}.posing")
    output = pathlib.Path(args.output).resolve()
    output.mkdir(parents=True, exist_ok=True)

    suzanne = subdivided_suzanne(args.subdivisions)
    V = np.empty(3 * len(suzanne.data.vertices), np.float32)
    suzanne.data.vertices.foreach_get("co", V)
    V = V.reshape(-1, 3)
    print(f"Suzanne: {len(V)} vertices, {len(suzanne.data.polygons)} faces")

    start = time.perf_counter()
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    status = suzanne.modal_deform.status
    print(f"bake: {time.perf_counter() - start:.1f} s ({status.dimension} dimensions, ghost {status.ghost_vertices} "
          f"vertices)")

    # Handles: the top of the head, turned about the vertical and bent sideways about the head's
    # centre; the chin, held where it is (its Empty is not moved).
    head = add_handle(suzanne, V[:, 2] > 0.4)
    add_handle(suzanne, (V[:, 2] < -0.55) & (V[:, 1] < -0.3))
    turn = Matrix.Rotation(math.radians(BEND), 4, "Y") @ Matrix.Rotation(math.radians(TURN), 4, "Z")
    centre = suzanne.matrix_world.translation
    head.controller.matrix_world = (Matrix.Translation(centre) @ turn @ Matrix.Translation(-centre)
                                    @ head.controller.matrix_world)
    bpy.context.view_layer.update()

    times = interactive_updates(posing, suzanne, 30)
    print(f"interactive pose: {np.median(times):.1f} ms per update (median of {len(times)}; first {times[0]:.1f} ms; "
          f"budget {suzanne.modal_deform.budget:.0f} ms for the solver)")
    assert bpy.ops.modal_deform.solve() == {"FINISHED"}

    stage(suzanne.matrix_world.translation + Vector((0.1, 0.0, 0.05)), eye=(1.0, -6.0, 0.8), lens=70,
          samples=args.samples, resolution=(args.width, args.width * 3 // 4))
    key = suzanne.data.shape_keys.key_blocks[posing.POSE_KEY]
    start = time.perf_counter()
    key.value = 0.0
    before = render(output / "demo_before.png")
    key.value = 1.0
    after = render(output / "demo_after.png")
    side_by_side([before, after], output / "demo.png")
    print(f"rendered {output / 'demo.png'} in {time.perf_counter() - start:.1f} s")

    bpy.context.view_layer.objects.active = suzanne
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj == suzanne)
    bpy.ops.wm.save_as_mainfile(filepath=str(output / "demo.blend"))
    print(f"wrote {output / 'demo.blend'}")


main()
