"""The main job, headless: Suzanne, subdivided to about 30k vertices, bent, with its shells energy.

    blender -b --factory-startup --python blender_scripts/demo.py -- --output out

Writes OUTPUT/demo.blend with the bend as a shape key (the base mesh stays the rest state).
"""
import argparse
import math
import pathlib
import sys
import time

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "python_addon"))
import modal_deform.core as mdc  # noqa: E402


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--output", default="out", help="folder for demo.blend")
    parser.add_argument("--subdivisions", type=int, default=3, help="Catmull-Clark levels (3: ~31k vertices)")
    return parser.parse_args(argv)


def subdivided_suzanne(levels):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.mesh.primitive_monkey_add()
    suzanne = bpy.context.object
    modifier = suzanne.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = levels
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    return suzanne


def mesh_arrays(mesh):
    V = np.empty(3 * len(mesh.vertices), np.float64)
    mesh.vertices.foreach_get("co", V)
    mesh.calc_loop_triangles()
    F = np.empty(3 * len(mesh.loop_triangles), np.int32)
    mesh.loop_triangles.foreach_get("vertices", F)
    return V.reshape(-1, 3), F.reshape(-1, 3)


def bend(V, degrees):
    """Bend about the x axis: each vertex turns in proportion to its height, top by `degrees`."""
    z = V[:, 2]
    angle = math.radians(degrees) * (z - z.min()) / np.ptp(z)
    y, c, s = V[:, 1], np.cos(angle), np.sin(angle)
    bent = V.copy()
    bent[:, 1] = c * y - s * z
    bent[:, 2] = s * y + c * z
    return bent


def main():
    args = arguments()
    suzanne = subdivided_suzanne(args.subdivisions)
    V, F = mesh_arrays(suzanne.data)
    report = mdc.check(V, F)
    print(f"Suzanne: {report['vertices']} vertices, {report['faces']} triangles, "
          f"{report['components']} components")

    scale = 10.0 / np.ptp(V, axis=0).max()  # the paper's frame: longest bounding-box edge 10
    start = time.perf_counter()
    energy = mdc.DiscreteShells(V * scale, F)
    build = time.perf_counter() - start
    bent = bend(V, 45.0)
    start = time.perf_counter()
    value = energy.value(bent * scale)
    gradient = energy.gradient(bent * scale)
    evaluate = time.perf_counter() - start
    print(f"shells energy under a 45 degree bend: {value:.6g} "
          f"(|gradient| {np.linalg.norm(gradient):.4g}; built in {build * 1e3:.0f} ms, "
          f"value + gradient in {evaluate * 1e3:.1f} ms)")

    suzanne.shape_key_add(name="Basis")
    key = suzanne.shape_key_add(name="Bend 45")
    key.data.foreach_set("co", bent.astype(np.float32).ravel())
    key.value = 1.0
    output = pathlib.Path(args.output).resolve()
    output.mkdir(parents=True, exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=str(output / "demo.blend"))
    print(f"wrote {output / 'demo.blend'}")


main()
