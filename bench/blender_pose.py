"""Posing in headless Blender: time per update on dragon_vrip_res2 (100k vertices) at 67 and 130
dimensions, Blender's Laplacian Deform on a subdivided Suzanne of similar size, basis load time,
.blend size, and what storing the basis on the Object would cost every update. With --shapes, also
Laplacian Deform against Modal Deform on the benchmark's shapes and handles (the accuracy
experiment's meshes): time per update, shells energy and error against the full solve; the
Laplacian result is added to each mesh file for the renders.

    blender -b --factory-startup --python bench/blender_pose.py -- --output bench/results/blender_pose.json \
        [--shapes bench/results/tmp/meshes] [--quick] [--pose-only] [--subdivide 2 [--double]]

In bpy (Blender 4.2+ as a Python module), with the add-on installed from the extension zip:

    BLENDER_USER_RESOURCES=$(mktemp -d) .venv/bpy-4.5/bin/python tests/blender/bpy_session.py \
        --extension dist/modal_deform-0.1.0-blender_4.2_to_5.0-linux_x64.zip bench/blender_pose.py -- --pose-only

One update is what the Pose operator does per timer tick, through its own calls, each timed:
controller matrices → set_transforms → BFGS within what the rest of the update leaves of a 60 fps
frame (FrameBudget) → the fine positions written by the solver straight into Blender's array →
mesh.update(). Blender then evaluates
the mesh for display ("evaluate": view_layer.update()). Medians over the updates, with the
controller moving a little each time.
"""

import argparse
import importlib
import json
import math
import os
import pathlib
import resource
import sys
import tempfile
import time

import bpy
import numpy as np
from mathutils import Matrix

ROOT = pathlib.Path(__file__).resolve().parents[1]
# Not python_addon/: the add-on is the extension Blender installed, or enable_addon() adds the
# source tree's; two modal_deform packages in one Blender would register the core's types twice.
sys.path.insert(0, str(ROOT / "blender_scripts"))
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "tests"))
from headless import add_handle, bind_laplacian_deform, enable_addon, evaluated_positions  # noqa: E402 (found through the lines above)
from support import SHARED_MESHES as MESHES  # noqa: E402
from support import subdivision  # noqa: E402 (the project's midpoint subdivision, NumPy only)

ADDON = "modal_deform"  # the add-on's module: bl_ext.<repository>.modal_deform when installed as an extension


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--output", default="bench/results/blender_pose.json")
    parser.add_argument("--updates", type=int, default=30, help="pose updates timed per basis")
    parser.add_argument(
        "--laplacian-updates", type=int, default=3, help="Laplacian Deform updates timed"
    )
    parser.add_argument(
        "--shapes", help="folder of .npz meshes (bench/accuracy.py) to compare Laplacian Deform on"
    )
    parser.add_argument(
        "--quick", action="store_true", help="dragon_vrip_res4 and a coarser Suzanne (smoke test)"
    )
    parser.add_argument(
        "--pose-only", action="store_true", help="only the pose updates (no storage, no Laplacian)"
    )
    parser.add_argument(
        "--subdivide",
        type=int,
        default=0,
        help="midpoint-subdivide the dragon this many times first (2: 1.6M vertices, baked on a "
        "proxy; the 67-dimensional basis only, pose updates only)",
    )
    parser.add_argument(
        "--double",
        action="store_true",
        help="then split as many edges as there are vertices (subdivision.split_edges): twice the "
        "vertices (with --subdivide 2: 3.2M)",
    )
    parser.add_argument("--proxy", type=int, help="the object's Proxy Size (default: the add-on's)")
    return parser.parse_args(argv)


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.data.orphans_purge(do_recursive=True)


def addon(*names):
    """The add-on's modules `names`, wherever it was enabled from (source tree or extension)."""
    found = tuple(importlib.import_module(f"{ADDON}.{name}") for name in names)
    return found[0] if len(found) == 1 else found


def milliseconds(start):
    return 1e3 * (time.perf_counter() - start)


def dragon(name, subdivisions, double=False):
    mdc = addon("core")
    V, F = mdc.read_mesh(MESHES / f"{name}.ply.gz")
    for _ in range(subdivisions):
        V, F = subdivision.midpoint_subdivide(V, F)
    if double:
        V, F = subdivision.split_edges(V, F, len(V))
    return mesh_object("Dragon", V, F)


def posed_dragon(name, subdivisions, double=False):
    """The dragon (subdivided, doubled: see arguments()) as a mesh object with a handle on the 5% of
    its length at each end, the low end pinned; (object, its vertex count, the high end's handle)."""
    obj = dragon(name, subdivisions, double)
    V = np.empty(3 * len(obj.data.vertices), np.float32)
    obj.data.vertices.foreach_get("co", V)
    V = V.reshape(-1, 3)
    axis = int(np.argmax(np.ptp(V, axis=0)))
    low, high = np.quantile(V[:, axis], [0.05, 0.95])
    moving = add_handle(obj, V[:, axis] > high)
    add_handle(obj, V[:, axis] < low).controller = None
    return obj, len(V), moving


def mesh_object(name, V, F):
    mesh = bpy.data.meshes.new(name)
    mesh.vertices.add(len(V))
    mesh.vertices.foreach_set("co", V.astype(np.float32).ravel())
    mesh.loops.add(F.size)
    mesh.loops.foreach_set("vertex_index", F.ravel())
    mesh.polygons.add(len(F))
    mesh.polygons.foreach_set("loop_start", np.arange(0, F.size, 3, dtype=np.int32))
    mesh.polygons.foreach_set("loop_total", np.full(len(F), 3, np.int32))
    mesh.update(calc_edges=True)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    return obj


STEPS = ("controllers", "budget", "solve", "write", "tick", "evaluate", "iterations")
#: Where the pose is shown while posing, with the posing display that shows it: the mesh as it is
#: (no shape keys: the vertex positions); with "Basis" and "Modal Deform" keys, as a mesh posed and
#: kept before has them, posed in a stand-in without shape keys (pose.displays.display's choice), or in
#: the "Modal Deform" key (the path such a mesh took before, and one whose other keys show takes).
DISPLAYS = {
    "positions": "PositionsDisplay",
    "stand_in": "StandInDisplay",
    "shape_key": "ShapeKeyDisplay",
}


def time_updates(obj, controller, updates, steps, display, draw=None):
    """`updates` pose updates while the controller turns and slides, each made of the Pose
    operator's own calls per timer tick, appended to steps[name] in ms: follow_controllers
    ("controllers": matrices and set_transforms), step ("solve": BFGS within "budget", what the
    rest of the last updates left of a 60 fps frame, at most the object's budget, as the operator's
    FrameBudget gives it), write (the pose written by the solver into Blender's array where the
    posing display named `display` shows it, and mesh.update()); then Blender's evaluation
    ("evaluate", view_layer.update()) and, given `draw`, what draw() takes ("draw")."""
    posing, displays, mdc = addon("pose.posing", "pose.displays", "core")
    pose = posing.Pose(bpy.context, obj)
    budget = mdc.FrameBudget(obj.modal_deform.budget)
    shown = displays.ShapeKeyDisplay(obj) if display == "ShapeKeyDisplay" else displays.display(obj)
    assert type(shown).__name__ == display, f"posed in a {type(shown).__name__}, not a {display}"
    size = max(obj.dimensions)
    start_matrix = controller.matrix_world.copy()
    for i in range(updates):
        controller.matrix_world = (
            Matrix.Translation((0.0, 0.01 * size * i, 0.005 * size * i))
            @ start_matrix
            @ Matrix.Rotation(math.radians(1.0 * i), 4, "X")
        )
        bpy.context.view_layer.update()
        tick = time.perf_counter()
        pose.follow_controllers()
        steps["controllers"].append(milliseconds(tick))
        steps["budget"].append(budget.ms)
        t = time.perf_counter()
        steps["iterations"].append(pose.step(budget.ms)["iterations"])
        steps["solve"].append(milliseconds(t))
        t = time.perf_counter()
        pose.write(shown.array())
        steps["write"].append(milliseconds(t))
        steps["tick"].append(milliseconds(tick))
        t = time.perf_counter()
        bpy.context.view_layer.update()
        steps["evaluate"].append(milliseconds(t))
        if draw is not None:
            t = time.perf_counter()
            draw()
            steps["draw"].append(milliseconds(t))
        budget.measured(
            steps["tick"][-1]
            - steps["solve"][-1]
            + steps["evaluate"][-1]
            + (steps["draw"][-1] if draw is not None else 0.0)
        )
    controller.matrix_world = start_matrix
    shown.restore()


def time_displays(obj, controller, updates, rounds=2, draw=None):
    """Medians of time_updates for each of DISPLAYS, taken in turn `rounds` times (A B C A B C), so
    that all see the shared machine alike."""
    pose_key = addon("pose.posing").POSE_KEY
    names = STEPS + (("draw",) if draw else ())
    steps = {name: {step: [] for step in names} for name in DISPLAYS}
    for _ in range(rounds):
        for name, display in DISPLAYS.items():
            if name != "positions":
                obj.shape_key_add(name="Basis")
                obj.shape_key_add(name=pose_key).value = 1.0
            time_updates(obj, controller, updates, steps[name], display, draw)
            if name != "positions":
                obj.shape_key_clear()
    figures = {
        name: {step: float(np.median(values)) for step, values in s.items()}
        for name, s in steps.items()
    }
    for f in figures.values():
        f["update"] = f["tick"] + f["evaluate"]
    return figures


def time_shape_key_update(obj, block, repeats=10):
    """Median ms of foreach_set + mesh.update() + depsgraph evaluation of a shape key."""
    co = np.empty(3 * len(obj.data.vertices), np.float32)
    block.data.foreach_get("co", co)
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        block.data.foreach_set("co", co)
        obj.data.update()
        bpy.context.view_layer.update()
        times.append(milliseconds(t))
    return float(np.median(times))


def storage_figures(obj, folder):
    """Load time and file sizes of the stored basis; the cost of keeping it on the Object instead."""
    displays, storage = addon("pose.displays", "storage")
    figures = {}
    state = displays.ShapeKeyState(obj)
    key = state.ensure()
    figures["update_ms_basis_in_palette"] = time_shape_key_update(obj, key)
    obj["vectors_probe"] = np.frombuffer(obj.modal_deform.basis["vectors"], np.float32)
    figures["update_ms_basis_on_object"] = time_shape_key_update(obj, key)
    del obj["vectors_probe"]
    state.restore()

    with_basis = os.path.join(folder, "with_basis.blend")
    bpy.ops.wm.save_as_mainfile(filepath=with_basis, copy=True)
    data = sum(a.nbytes for a in storage.load(obj).to_arrays().values())
    palette = obj.modal_deform.basis
    obj.modal_deform.basis = None
    without = os.path.join(folder, "without_basis.blend")
    bpy.ops.wm.save_as_mainfile(filepath=without, copy=True)
    obj.modal_deform.basis = palette
    figures["blend_mb"] = os.path.getsize(with_basis) / 1e6
    figures["blend_growth_mb"] = (os.path.getsize(with_basis) - os.path.getsize(without)) / 1e6
    figures["basis_data_mb"] = data / 1e6

    t = time.perf_counter()
    bpy.ops.wm.open_mainfile(filepath=with_basis)
    figures["open_blend_s"] = time.perf_counter() - t
    obj = bpy.data.objects["Dragon"]
    loads = []
    for _ in range(3):
        storage._forget_everything()
        t = time.perf_counter()
        storage.load(obj)
        loads.append(time.perf_counter() - t)
    figures["basis_load_s"] = min(loads)
    return figures


def laplacian_deform(updates, subdivisions):
    """Blender's Laplacian Deform on Suzanne at `subdivisions` levels: bind time and time per update
    (1 iteration, the modifier's default) with a hook moving the top anchors."""
    clear_scene()
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.object
    subdivision = obj.modifiers.new("Subdivision", "SUBSURF")
    subdivision.levels = subdivisions
    bpy.ops.object.modifier_apply(modifier=subdivision.name)
    V = np.empty(3 * len(obj.data.vertices), np.float32)
    obj.data.vertices.foreach_get("co", V)
    V = V.reshape(-1, 3)
    top, bottom = np.flatnonzero(V[:, 2] > 0.6), np.flatnonzero(V[:, 2] < -0.55)
    # Every connected component needs an anchor, or the modifier finds no solution: the eyes too.
    mdc, mesh_io = addon("core", "mesh_io")
    label = mdc.check(V, mesh_io.triangles(obj.data))["vertex_component"]
    eyes = np.flatnonzero(label != label[top[0]])
    anchors = np.concatenate([top, bottom, eyes])
    empty, bind = bind_laplacian_deform(obj, anchors, top)
    times = []
    for i in range(updates):
        empty.location = (0.02 * (i + 1), 0.0, 0.01 * (i + 1))
        t = time.perf_counter()
        bpy.context.view_layer.update()
        times.append(milliseconds(t))
    # Failing, the modifier passes the hooked mesh through: vertices away from the anchors stay.
    free = np.ones(len(V), bool)
    free[anchors] = False
    solved = bool(np.abs(evaluated_positions(obj)[free] - V[free]).max() > 0)
    return {
        "vertices": len(V),
        "bind_s": bind,
        "update_ms": float(np.median(times)),
        "solved": solved,
    }


def laplacian_on_shapes(folder):
    """Laplacian Deform and Modal Deform (67 dimensions, 1k ghost, 10 iterations per update) on each
    mesh file's shape, handles and pose (handle 0 held, handle 1 moved through the pose's steps):
    ms per update, and shells energy and RMS error against the full solve of the final pose."""
    mdc = addon("core")
    sys.path.insert(0, str(ROOT / "bench"))
    from common import rms_error

    rows = []
    for path in sorted(pathlib.Path(folder).glob("*.npz")):
        data = dict(np.load(path))
        V, F, steps = data["rest"], data["F"], data["transforms"]
        clear_scene()
        obj = mesh_object("Shape", V, F)
        empty, bind = bind_laplacian_deform(
            obj, np.concatenate([data["handle0"], data["handle1"]]), data["handle1"]
        )
        laplacian_ms = []
        for transforms in steps:
            empty.matrix_world = Matrix(transforms[1].tolist())
            t = time.perf_counter()
            bpy.context.view_layer.update()
            laplacian_ms.append(milliseconds(t))
        data["laplacian"] = evaluated_positions(obj).astype(np.float64)

        solver = mdc.ReducedSolver(
            mdc.bake(V, F, modes=20, derivatives=47, ghost=1000), [data["handle0"], data["handle1"]]
        )
        out = np.empty(V.shape, np.float32)
        ours_ms = []
        for transforms in steps:
            t = time.perf_counter()
            solver.set_transforms(transforms)
            solver.solve(max_iterations=10, tolerance=1e-6)
            solver.positions(out)
            ours_ms.append(milliseconds(t))
        while not solver.solve(max_iterations=50, tolerance=1e-10)["converged"]:
            pass
        ours = solver.positions().astype(np.float64)
        energy = mdc.DiscreteShells(V, F)
        rows.append(
            {
                "shape": str(data["shape"]),
                "pose": str(data["pose"]),
                "vertices": len(V),
                "laplacian_bind_s": bind,
                "laplacian_update_ms": float(np.median(laplacian_ms)),
                "ours_update_ms": float(np.median(ours_ms)),
                "energy_full": energy.value(data["full"]),
                "energy_ours": energy.value(ours),
                "energy_laplacian": energy.value(data["laplacian"]),
                "rms_ours": rms_error(ours, data["full"]),
                "rms_laplacian": rms_error(data["laplacian"], data["full"]),
            }
        )
        np.savez(path, **data)
        print(
            f"{rows[-1]['shape']} {rows[-1]['pose']}: Laplacian {rows[-1]['laplacian_update_ms']:.1f} ms, energy "
            f"{rows[-1]['energy_laplacian']:.4g}; ours {rows[-1]['ours_update_ms']:.2f} ms, energy "
            f"{rows[-1]['energy_ours']:.4g}; full {rows[-1]['energy_full']:.4g}",
            flush=True,
        )
    return rows


def main():
    global ADDON
    args = arguments()
    ADDON = enable_addon().__name__
    clear_scene()
    mesh = "dragon_vrip_res4" if args.quick else "dragon_vrip_res2"
    obj, vertices, moving = posed_dragon(mesh, args.subdivide, args.double)
    if args.subdivide or args.double:
        args.pose_only = True
        mesh = f"{mesh} subdivided {args.subdivide}x" + (
            ", edges split to double" if args.double else ""
        )
    results = {"mesh": mesh, "vertices": vertices, "bases": {}}
    # The paper's 67 and 130 dimensions (bench_solve.cpp bakes the same 130).
    for modes, derivatives in (
        ((15, 52),) if args.subdivide or args.double else ((15, 52), (25, 105))
    ):
        settings = obj.modal_deform
        settings.modes, settings.derivatives, settings.ghost = modes, derivatives, 1000
        if args.proxy is not None:
            settings.proxy = args.proxy
        t = time.perf_counter()
        bpy.ops.modal_deform.bake()
        bake = time.perf_counter() - t
        dimension = settings.status.dimension
        figures = time_displays(obj, moving.controller, args.updates)
        figures.update(bake_s=bake, proxy_vertices=settings.status.proxy_vertices)
        results["bases"][str(dimension)] = figures
        print(
            f"{dimension} dimensions: baked in {bake:.1f} s (proxy {settings.status.proxy_vertices} vertices); "
            + "; ".join(
                f"{display}: ours {figures[display]['tick']:.1f} ms + Blender's evaluation "
                f"{figures[display]['evaluate']:.1f} ms"
                for display in DISPLAYS
            ),
            flush=True,
        )
    results["blender"] = bpy.app.version_string
    results["peak_gb"] = (
        resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20
    )  # the bake's, on dense meshes
    if not args.pose_only:
        with tempfile.TemporaryDirectory() as folder:
            results["storage"] = storage_figures(obj, folder)
        results["laplacian_deform"] = laplacian_deform(
            args.laplacian_updates, 2 if args.quick else 4
        )
    if args.shapes:
        results["shapes"] = laplacian_on_shapes(args.shapes)
    results["parameters"] = {
        "mesh": mesh,
        "updates": args.updates,
        "laplacian_updates": args.laplacian_updates,
        "suzanne_subdivisions": 2 if args.quick else 4,
        "shapes": args.shapes,
        "bases": "(15, 52) and (25, 105) modes, derivatives; 1k ghost",
    }

    print(
        f"\nPose update on {mesh} ({vertices} vertices), headless Blender {bpy.app.version_string}, shared 2-core "
        "machine; ms, medians"
    )
    print(
        f"{'dims':>5} {'display':>10} {'ctrl':>6} {'budget':>6} {'solve':>6} {'write':>6} {'tick':>6} {'eval':>6} "
        f"{'iters':>5}"
    )
    for dims, b in results["bases"].items():
        for display in DISPLAYS:
            f = b[display]
            print(
                f"{dims:>5} {display:>10} {f['controllers']:6.2f} {f['budget']:6.2f} {f['solve']:6.2f} "
                f"{f['write']:6.2f} "
                f"{f['tick']:6.2f} {f['evaluate']:6.1f} {f['iterations']:5.0f}"
            )
    if not args.pose_only:
        lap = results["laplacian_deform"]
        print(
            f"\nLaplacian Deform, Suzanne {lap['vertices']} vertices: bind {lap['bind_s']:.1f} s, "
            f"{lap['update_ms']:.0f} ms per update (solved: {lap['solved']})"
        )
        for dims, b in results["bases"].items():
            f = b[
                "positions"
            ]  # what a mesh without shape keys gets, as the Laplacian Deform's mesh has none
            f["laplacian_ratio_tick"] = lap["update_ms"] / f["tick"]
            f["laplacian_ratio_tick_and_evaluate"] = lap["update_ms"] / (f["tick"] + f["evaluate"])
            print(
                f"  ratio to Modal Deform at {dims} dims: {f['laplacian_ratio_tick']:.0f}x per tick, "
                f"{f['laplacian_ratio_tick_and_evaluate']:.0f}x with Blender's evaluation of both"
            )
        s = results["storage"]
        print(
            f"\nStorage: .blend {s['blend_mb']:.1f} MB, grows {s['blend_growth_mb']:.1f} MB for {s['basis_data_mb']:.1f} MB "
            f"of basis; open {s['open_blend_s']:.2f} s; basis load {s['basis_load_s'] * 1e3:.0f} ms"
        )
        print(
            f"Shape-key update + evaluation: {s['update_ms_basis_in_palette']:.1f} ms with the basis in its palette, "
            f"{s['update_ms_basis_on_object']:.1f} ms with the vectors on the Object"
        )
    output = pathlib.Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    output.write_text(json.dumps(results, indent=1))
    print(f"wrote {output}")


if __name__ == "__main__":  # imported by bench/viewport_frames.py for its meshes and updates
    main()
