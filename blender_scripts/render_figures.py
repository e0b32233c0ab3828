"""Render a rest mesh and its poses side by side with Cycles on the CPU: the benchmark's figures.

    blender -b --factory-startup --python blender_scripts/render_figures.py -- \\
        --meshes bench/results/tmp/meshes --output docs/figures [--samples 16] [--width 360]

Each MESHES/<name>.npz holds F (m, 3), rest (n, 3), view (3,) (the direction the camera looks
along) and posed positions (n, 3) under any of the keys "full", "derivatives", "linear",
"laplacian"; it becomes OUTPUT/render_<name>.png: the rest mesh, then those present in that
order, left to right, one colour each, all seen by the same camera (framing every variant).
"""

import argparse
import math
import pathlib
import sys
import tempfile

import bpy
import numpy as np
from mathutils import Vector

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from rendering import render, side_by_side, stage  # noqa: E402

#: Variant: RGB base colour (white for the rest shape, grey for the reference, blue for ours,
#: orange for linear modes, red for Laplacian Deform).
VARIANTS = {
    "rest": (0.9, 0.9, 0.9),
    "full": (0.6, 0.6, 0.6),
    "derivatives": (0.25, 0.45, 0.8),
    "linear": (0.85, 0.5, 0.15),
    "laplacian": (0.75, 0.2, 0.2),
}


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--meshes", required=True, help="folder of .npz meshes")
    parser.add_argument("--output", required=True, help="folder for render_<name>.png")
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel")
    parser.add_argument(
        "--width", type=int, default=300, help="pixels per variant; the height is the same"
    )
    return parser.parse_args(argv)


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.data.orphans_purge(do_recursive=True)


def mesh_object(V, F, colour):
    mesh = bpy.data.meshes.new("Posed")
    mesh.from_pydata(V.tolist(), [], F.tolist())
    mesh.update()
    mesh.polygons.foreach_set("use_smooth", np.ones(len(F), bool))
    material = bpy.data.materials.new("Material")
    material.use_nodes = True
    material.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (*colour, 1.0)
    mesh.materials.append(material)
    obj = bpy.data.objects.new("Posed", mesh)
    bpy.context.scene.collection.objects.link(obj)
    return obj


def framing(points, view, lens, aspect):
    """Camera target and eye that keep all `points` (k, 3) in view looking along `view`."""
    centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
    radius = np.linalg.norm(points - centre, axis=1).max()
    half_angle = math.atan(18.0 / lens) * min(1.0, aspect)  # the 36 mm sensor's narrower half-width
    distance = (
        0.95 * radius / math.sin(half_angle)
    )  # the bounding sphere is loose: 0.95 still frames
    view = np.asarray(view, float) / np.linalg.norm(view)
    return Vector(centre), Vector(centre - distance * view)


def main():
    args = arguments()
    output = pathlib.Path(args.output)
    output.mkdir(parents=True, exist_ok=True)
    for path in sorted(pathlib.Path(args.meshes).glob("*.npz")):
        data = np.load(path)
        present = [v for v in VARIANTS if v in data]
        clear_scene()
        size = (args.width, args.width)
        target, eye = framing(
            np.concatenate([data[v] for v in present]), data["view"], 50, size[0] / size[1]
        )
        stage(target, tuple(eye), lens=50, samples=args.samples, resolution=size)
        images = []
        with tempfile.TemporaryDirectory() as folder:
            for variant in present:
                obj = mesh_object(data[variant], data["F"], VARIANTS[variant])
                images.append(render(pathlib.Path(folder) / f"{variant}.png"))
                bpy.data.objects.remove(obj)
        side_by_side(images, output / f"render_{path.stem}.png")
        print(f"wrote {output / f'render_{path.stem}.png'} ({', '.join(present)})", flush=True)


main()
