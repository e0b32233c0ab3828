"""Blend as Shapes in headless Blender (issue 52): the dragon (100k vertices) with KEYS shape keys made
by formula (support.poses.smooth_keys), turned on with the add-on's operator (the space's bake),
then driven as an artist drives it: one key's value changed per update, Blender's depsgraph updated
(what moving a slider in the Shape Keys panel does).

    blender -b --factory-startup --python bench/shape_keys_blender.py -- --output out.json [--quick] [--subdivide 2]

In bpy, with the add-on installed from the extension zip (what `make bench` runs, bench/run.py):

    BLENDER_USER_RESOURCES=$(mktemp -d) .venv/bpy-4.5/bin/python tests/blender/bpy_session.py \
        --extension dist/modal_deform-0.1.0-blender_4.2_to_5.0-linux_x64.zip bench/shape_keys_blender.py -- --output out.json

Per update (view_layer.update() after a key's value changed): "update" its whole time; "handlers"
the add-on's depsgraph handlers, before and after Blender's evaluation (shapes/blending.py: the
weights read, the blend, the display written), of which "blend" is the core's blend with its map
(ShapeSpace.stats["ms"]); "evaluate" the rest, Blender's evaluation; "after" what follows the
add-on's last handler (a second evaluation when a handler after the first wrote the display). Beside them Blender's own linear mix: the
same updates with Blend as Shapes off. Each figure is the median over the updates of an update's
least over ROUNDS rounds of the same value changes, each round from every key at 0 (a blend is a
function of the weights alone: the same work every round). The load average (1, 5, 15 min) before and after the run.
"""

import argparse
import json
import os
import pathlib
import sys
import time

import bpy
import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "bench"))
import blender_pose  # noqa: E402 (found through the line above; the dragon as a mesh object)
from headless import enable_addon  # noqa: E402 (blender_pose put blender_scripts/ on the path)
from support.poses import smooth_keys  # noqa: E402 (blender_pose put tests/ on the path)

#: Shape keys on the mesh, and rounds of the timed updates.
KEYS, ROUNDS = 8, 3


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--output", required=True)
    parser.add_argument("--updates", type=int, default=30, help="key value changes timed")
    parser.add_argument(
        "--subdivide",
        type=int,
        default=0,
        help="midpoint subdivisions of the 100k dragon (2: 1.6M vertices, baked on a proxy)",
    )
    parser.add_argument(
        "--quick", action="store_true", help="dragon_vrip_res4 and a small basis (smoke test)"
    )
    return parser.parse_args(argv)


def keyed_dragon(name, subdivisions):
    """The dragon with a Basis and KEYS keys (smooth_keys), all at 0; (object, key blocks)."""
    obj = blender_pose.dragon(name, subdivisions)
    mesh = obj.data
    V = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", V)
    obj.shape_key_add(name="Basis")
    blocks = []
    for i, X in enumerate(smooth_keys(V.reshape(-1, 3).astype(np.float64), KEYS)):
        block = obj.shape_key_add(name=f"Key {i + 1}", from_mix=False)
        block.data.foreach_set("co", X.astype(np.float32).ravel())
        blocks.append(block)
    return obj, blocks


def value_changes(count, seed=3):
    """`count` (key, value) changes: the keys in turn, each to a value in [0, 1]."""
    rng = np.random.default_rng(seed)
    return [(i % KEYS, float(rng.random())) for i in range(count)]


def timed_handlers(timings):
    """Wrap the add-on's depsgraph handlers (shapes/blending.py, before and after Blender's
    evaluation) so that each call appends (name, start, end) to `timings`; returns a function that
    puts them back."""
    wrapped = []
    for name in ("depsgraph_update_pre", "depsgraph_update_post"):
        handlers = getattr(bpy.app.handlers, name)
        index, found = next(
            (i, h) for i, h in enumerate(handlers) if h.__module__.endswith(".shapes.blending")
        )

        def timed(*args, found=found, name=name):
            start = time.perf_counter()
            found(*args)
            timings.append((name, start, time.perf_counter()))

        handlers[index] = timed
        wrapped.append((handlers, timed, found))

    def restore():
        for handlers, timed, found in wrapped:
            handlers[list(handlers).index(timed)] = found

    return restore


def timed_updates(obj, blocks, changes, blending=None, rounds=ROUNDS):
    """Per update of `changes` (each a key's value set, then view_layer.update()): its milliseconds;
    with `blending` (Blend as Shapes on) also the add-on's handlers', the blend's, Blender's
    evaluation (the rest of the update) and of it what follows the add-on's last handler (a
    second evaluation, of the display the handler wrote). Medians over the updates of the least
    over `rounds`."""
    names = ("update", "handlers", "blend", "evaluate", "after") if blending else ("update",)
    figures = {name: np.full((rounds, len(changes)), np.inf) for name in names}
    timings = []
    if blending:
        restore = timed_handlers(timings)
        space = blending.load(obj)
    try:
        for round_ in range(rounds):
            for block in blocks:  # every round from the same weights
                block.value = 0.0
            bpy.context.view_layer.update()
            for index, (key, value) in enumerate(changes):
                timings.clear()
                blocks[key].value = value
                start = time.perf_counter()
                bpy.context.view_layer.update()
                returned = time.perf_counter()
                update = 1e3 * (returned - start)
                figures["update"][round_, index] = update
                if blending:
                    assert obj.name not in blending.problems, blending.problems
                    handlers = 1e3 * sum(end - begin for _, begin, end in timings)
                    figures["handlers"][round_, index] = handlers
                    figures["evaluate"][round_, index] = update - handlers
                    figures["after"][round_, index] = 1e3 * (returned - timings[-1][2])
                    figures["blend"][round_, index] = space.stats["ms"]
    finally:
        if blending:
            restore()
    result = {
        name + "_ms": float(np.median(values.min(axis=0))) for name, values in figures.items()
    }
    result["updates"], result["rounds"] = len(changes), rounds
    return result


def main():
    args = arguments()
    blender_pose.ADDON = enable_addon().__name__
    blender_pose.clear_scene()
    blending = blender_pose.addon("shapes.blending")
    name = "dragon_vrip_res4" if args.quick else "dragon_vrip_res2"
    obj, blocks = keyed_dragon(name, args.subdivide)
    settings = obj.modal_deform
    if args.quick:
        settings.modes, settings.derivatives, settings.ghost = 12, 12, 300
    changes = value_changes(6 if args.quick else args.updates)
    load_before = os.getloadavg()
    results = {
        "blender": bpy.app.version_string,
        "mesh": name,
        "subdivide": args.subdivide,
        "vertices": len(obj.data.vertices),
        "keys": KEYS,
    }
    results["linear"] = timed_updates(obj, blocks, changes)
    for block in blocks:
        block.value = 0.0
    start = time.perf_counter()
    assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}
    results["bake_seconds"] = time.perf_counter() - start
    results["dimension"] = settings.shapes.dimension
    basis = blending.load(obj).basis
    results["proxy_vertices"] = basis.num_basis_vertices if basis.on_proxy else 0
    results["blend"] = timed_updates(obj, blocks, changes, blending)
    results["load_average"] = {"before": load_before, "after": os.getloadavg()}
    pathlib.Path(args.output).write_text(json.dumps(results, indent=1))
    print(json.dumps(results, indent=1))


main()
