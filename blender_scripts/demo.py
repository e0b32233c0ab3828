"""The main job, headless: bake Suzanne (~31k vertices), pose it strongly with two handles (the top
of the head turned by TURN and bent sideways by BEND degrees against the held chin: a pose with large
rotations, what modal derivatives are for), and set Blender's own Laplacian Deform the same task
with the same handles.

    blender -b --factory-startup --python blender_scripts/demo.py -- --output out

A second row shows what vertex groups paint (issue 24): a finger of three stiff phalanges and soft
knuckles (a Stiffness Group) curled by its tip against the same tube of uniform material, and
Suzanne's left ear baked as a Region Group and pulled up while every other vertex stays exactly
where it was.

Then secondary motion (issue 40, demo_dynamics.py): a Suzanne whose head tilts fast and stops, her
ears overshooting and settling, as a strip of frames, OUTPUT/demo_dynamics.png.
And on a rig (issue 50, demo_rig.py): Suzanne on a round body, skinned to two bones, jumps and
tilts her head with Dynamics > Follow Rig, above the same frames with the Armature modifier alone,
OUTPUT/demo_rig.png.

Last, shape keys blended as shapes (issue 52, demo_shapes.py): a Suzanne with a jaw-open and an
ears-fold key, both at 0.5, as Blender mixes them and as Blend as Shapes blends them, with the keys at
1, OUTPUT/demo_shapes.png.

And in-betweens (issue 51, demo_inbetweens.py): Suzanne's head keyed at three poses only, moved
through them by Dynamics > In-betweens above the same frames as Blender interpolates the keys,
with a plot of her ear tip's height over the frames, OUTPUT/demo_inbetweens.png.

Writes OUTPUT/demo.png (Cycles on the CPU: rest, Modal Deform, Laplacian Deform side by side; below
them the uniform and the painted finger and the ear) and OUTPUT/demo.blend (Suzanne alone), ready to
pose: select the mesh, Sidebar > Modal Deform > Pose, then move the
Empties with G/R. Prints the bake time, the time per interactive update and how much each result
stretches the surface.
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
import demo_dynamics  # noqa: E402
import demo_inbetweens  # noqa: E402
import demo_rig  # noqa: E402
import demo_shapes  # noqa: E402
from headless import (  # noqa: E402
    add_handle,
    bind_laplacian_deform,
    enable_addon,
    evaluated_positions,
    smooth_suzanne,
)
from rendering import render, side_by_side, stage  # noqa: E402

#: The pose: the top of the head turned about the vertical and then bent sideways (degrees).
TURN, BEND = 45, 45
#: The top of the head (the moved handle): Suzanne's vertices above this height (she spans -1 to 1).
TOP = 0.6


def arguments():
    argv = sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--output", default="out", help="folder for demo.png and demo.blend")
    parser.add_argument(
        "--subdivisions", type=int, default=3, help="Catmull-Clark levels (3: ~31k vertices)"
    )
    parser.add_argument("--samples", type=int, default=16, help="Cycles samples per pixel")
    parser.add_argument(
        "--turn",
        type=float,
        default=TURN,
        help="the top of the head turned about the vertical, degrees",
    )
    parser.add_argument("--bend", type=float, default=BEND, help="then bent sideways, degrees")
    parser.add_argument(
        "--width", type=int, default=800, help="width of each of the three pictures, pixels"
    )
    parser.add_argument(
        "--dynamics-subdivisions",
        type=int,
        default=2,
        help="Catmull-Clark levels of the secondary motion's Suzanne (2: ~8k vertices)",
    )
    parser.add_argument(
        "--shapes-subdivisions",
        type=int,
        default=2,
        help="Catmull-Clark levels of the shape keys' Suzanne (2: ~8k vertices)",
    )
    parser.add_argument(
        "--inbetweens-subdivisions",
        type=int,
        default=2,
        help="Catmull-Clark levels of the in-betweens' Suzanne (2: ~8k vertices)",
    )
    return parser.parse_args(argv)


def subdivided_suzanne(levels):
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    return smooth_suzanne("Suzanne", levels)


def interactive_updates(posing, displays, obj, count):
    """Time `count` updates of the interactive pose (what each timer tick of the Pose operator does:
    controllers -> solver within its budget -> shape key) after the controllers were placed: the
    first updates solve toward them, the later ones find the pose converged."""
    pose = posing.Pose(bpy.context, obj)
    shown = displays.display(obj)
    times = []
    for _ in range(count):
        start = time.perf_counter()
        pose.follow_controllers()
        pose.step(obj.modal_deform.budget)
        pose.write(shown.array())
        times.append(1e3 * (time.perf_counter() - start))
    shown.restore()
    return times


def laplacian_deform_copy(obj, anchors, moving, transform):
    """A copy of obj's rest mesh with Blender's Laplacian Deform: the vertices `anchors` held, those
    of them in `moving` carried by `transform` (a hook to an Empty), as Modal Deform's handles are."""
    copy = bpy.data.objects.new("Laplacian Deform", obj.data.copy())
    copy.matrix_world = obj.matrix_world
    copy.shape_key_clear()
    bpy.context.scene.collection.objects.link(copy)
    empty, _ = bind_laplacian_deform(copy, np.flatnonzero(anchors), np.flatnonzero(moving))
    empty.matrix_world = transform
    bpy.context.view_layer.update()
    return copy, empty


def edge_strain(mesh, rest, posed):
    """Mean and largest |l / l_rest - 1| over the mesh's edges: how much a pose stretches or
    squashes the surface (an artist sees it as rubbery or shrunken parts)."""
    edges = np.empty(2 * len(mesh.edges), np.int32)
    mesh.edges.foreach_get("vertices", edges)
    edges = edges.reshape(-1, 2)
    length = np.linalg.norm(posed[edges[:, 0]] - posed[edges[:, 1]], axis=1)
    strain = np.abs(length / np.linalg.norm(rest[edges[:, 0]] - rest[edges[:, 1]], axis=1) - 1)
    return strain.mean(), strain.max()


def curled_finger(mdc, name, painted, x):
    """A tube along z (a finger 2 long) at `x`, held at its base ring and its tip ring curled by 60°
    about each knuckle (about the y axis, seen from the camera); with `painted`, a Stiffness Group
    makes its three phalanges 100 times stiffer than its two knuckles. Returns the object, posed."""
    V, F = mdc.testing.cylinder(24, 60, 0.16, 2.0)
    V[:, 0] += x
    obj = bpy.data.objects.new(name, bpy.data.meshes.new(name))
    obj.data.from_pydata([tuple(v) for v in V], [], [tuple(f) for f in F])
    bpy.context.scene.collection.objects.link(obj)
    obj.location.z = -1.0
    knuckles = [(0.6, 0.8), (1.3, 1.5)]
    settings = obj.modal_deform
    settings.modes, settings.derivatives, settings.ghost = 16, 40, 1000
    if painted:
        group = obj.vertex_groups.new(name="Phalanges")
        soft = np.zeros(len(V), bool)
        for low, high in knuckles:
            soft |= (V[:, 2] > low) & (V[:, 2] < high)
        group.add([int(i) for i in np.flatnonzero(~soft)], 1.0, "REPLACE")
        settings.stiffness_group, settings.max_stiffness = "Phalanges", 100.0
    bpy.context.view_layer.objects.active = obj
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    add_handle(obj, V[:, 2] < 1e-6).controller = None
    tip = add_handle(obj, V[:, 2] > 2 - 1e-6)
    curl = Matrix()
    for low, high in reversed(knuckles):
        pivot = obj.matrix_world @ Vector((x, 0.0, (low + high) / 2))
        curl = (
            Matrix.Translation(pivot)
            @ Matrix.Rotation(math.radians(60), 4, "Y")
            @ Matrix.Translation(-pivot)
            @ curl
        )
    tip.controller.matrix_world = curl @ tip.controller.matrix_world
    bpy.context.view_layer.update()
    assert bpy.ops.modal_deform.solve() == {"FINISHED"}
    obj.data.polygons.foreach_set("use_smooth", [True] * len(obj.data.polygons))
    return obj


def pulled_ear(suzanne, V):
    """A copy of Suzanne whose left ear (x > 0.75) alone is baked as a Region Group and pulled up
    and out by its tip; every other vertex stays exactly at rest. Returns the object, posed."""
    ear = bpy.data.objects.new("Ear", suzanne.data.copy())
    ear.matrix_world = suzanne.matrix_world
    ear.shape_key_clear()
    bpy.context.scene.collection.objects.link(ear)
    region = ear.vertex_groups.new(name="Ear")
    region.add([int(i) for i in np.flatnonzero(V[:, 0] > 0.75)], 1.0, "REPLACE")
    ear.modal_deform.region_group = "Ear"
    ear.modal_deform.modes, ear.modal_deform.derivatives, ear.modal_deform.ghost = 16, 40, 1000
    bpy.context.view_layer.objects.active = ear
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    tip = add_handle(ear, V[:, 0] > 1.25)
    tip.controller.matrix_world = (
        Matrix.Translation((0.15, 0.0, 0.35)) @ tip.controller.matrix_world
    )
    bpy.context.view_layer.update()
    assert bpy.ops.modal_deform.solve() == {"FINISHED"}
    return ear


def painted_row(mdc, posing, suzanne, V, output):
    """The second row (issue 24): the uniform finger, the painted finger, Suzanne's pulled ear,
    each alone in the row's stage. Returns their pixels left to right."""
    objects = [
        curled_finger(mdc, "Uniform finger", False, 0.0),
        curled_finger(mdc, "Painted finger", True, 0.0),
        pulled_ear(suzanne, V),
    ]
    ear = objects[2].data
    posed = np.empty(3 * len(ear.vertices), np.float32)
    ear.shape_keys.key_blocks[posing.POSE_KEY].data.foreach_get("co", posed)
    outside = V[:, 0] <= 0.75
    print(
        f"Region: the ear's tip moved by {np.abs(posed.reshape(-1, 3) - V).max():.2f}; the "
        f"{int(outside.sum())} vertices outside the ear moved by "
        f"{np.abs(posed.reshape(-1, 3)[outside] - V[outside]).max():g}"
    )
    pictures = []
    for shown in objects:
        for obj in objects + [suzanne]:
            obj.hide_render = obj is not shown
        pictures.append(render(output / f"demo_{shown.name.lower().replace(' ', '_')}.png"))
    for obj in objects:
        for handle in obj.modal_deform.handles:
            if handle.controller is not None:
                bpy.data.objects.remove(handle.controller)
        bpy.data.objects.remove(obj)
    suzanne.hide_render = False
    return pictures


def main():
    args = arguments()
    addon = enable_addon().__name__
    posing, displays, mesh_io, mdc = (
        importlib.import_module(f"{addon}.{name}")
        for name in ("pose.posing", "pose.displays", "mesh_io", "core")
    )
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
    print(
        f"bake: {time.perf_counter() - start:.1f} s ({status.dimension} dimensions, ghost {status.ghost_vertices} "
        f"vertices)"
    )

    # Handles: the top of the head, turned about the vertical and bent sideways about the head's
    # centre; the chin, held where it is (its Empty is not moved).
    top, chin = V[:, 2] > TOP, (V[:, 2] < -0.55) & (V[:, 1] < -0.3)
    head = add_handle(suzanne, top)
    add_handle(suzanne, chin)
    turn = Matrix.Rotation(math.radians(args.bend), 4, "Y") @ Matrix.Rotation(
        math.radians(args.turn), 4, "Z"
    )
    centre = suzanne.matrix_world.translation
    transform = Matrix.Translation(centre) @ turn @ Matrix.Translation(-centre)
    head.controller.matrix_world = transform @ head.controller.matrix_world
    bpy.context.view_layer.update()

    times = interactive_updates(posing, displays, suzanne, 30)
    print(
        f"interactive pose: {np.median(times):.1f} ms per update (median of {len(times)}; first {times[0]:.1f} ms; "
        f"budget {suzanne.modal_deform.budget:.0f} ms for the solver)"
    )
    assert bpy.ops.modal_deform.solve() == {"FINISHED"}

    # Laplacian Deform gets the same handles. Each connected component needs an anchor of its own:
    # the eyes go with the top of the head.
    component = mdc.check(V, mesh_io.triangles(suzanne.data))["vertex_component"]
    eyes = component != component[np.flatnonzero(top)[0]]
    laplacian, hook = laplacian_deform_copy(suzanne, top | chin | eyes, top | eyes, transform)
    key = suzanne.data.shape_keys.key_blocks[posing.POSE_KEY]
    posed = np.empty(V.size, np.float32)
    key.data.foreach_get("co", posed)
    for name, X in (
        ("Modal Deform", posed.reshape(-1, 3)),
        ("Laplacian Deform", evaluated_positions(laplacian)),
    ):
        mean, largest = edge_strain(suzanne.data, V, X)
        print(
            f"{name}: edges stretched or squashed by {100 * mean:.1f}% on average, at most {100 * largest:.0f}%"
        )

    stage(
        suzanne.matrix_world.translation + Vector((0.1, 0.0, 0.05)),
        eye=(1.0, -6.0, 0.8),
        lens=70,
        samples=args.samples,
        resolution=(args.width, args.width * 3 // 4),
    )
    start = time.perf_counter()
    laplacian.hide_render = True
    key.value = 0.0
    rest = render(output / "demo_before.png")
    key.value = 1.0
    ours = render(output / "demo_after.png")
    suzanne.hide_render, laplacian.hide_render = True, False
    theirs = render(output / "demo_laplacian.png")
    # The file keeps Suzanne alone, ready to pose.
    bpy.data.objects.remove(laplacian)
    bpy.data.objects.remove(hook)
    below = painted_row(mdc, posing, suzanne, V, output)
    side_by_side(
        [
            np.concatenate([row[i] for row in (below, [rest, ours, theirs])], axis=0)
            for i in range(3)
        ],
        output / "demo.png",
    )
    print(
        f"rendered {output / 'demo.png'} (rest, Modal Deform, Laplacian Deform; the uniform and the painted "
        f"finger, the ear) in {time.perf_counter() - start:.1f} s"
    )

    bpy.context.view_layer.objects.active = suzanne
    for obj in bpy.context.view_layer.objects:
        obj.select_set(obj == suzanne)
    bpy.ops.wm.save_as_mainfile(filepath=str(output / "demo.blend"))
    print(f"wrote {output / 'demo.blend'}")

    def modules(*names):
        return tuple(importlib.import_module(f"{addon}.{name}") for name in names)

    def rendered(what, strip_of):
        start = time.perf_counter()
        strip = strip_of()
        print(f"rendered {strip} ({what}) in {time.perf_counter() - start:.1f} s")

    half = args.width // 2
    rendered(
        "secondary motion",
        lambda: demo_dynamics.secondary_motion(
            modules("playback.frame_cache", "pose.posing"), output, args.dynamics_subdivisions, half
        ),
    )
    rendered(
        "secondary motion on a rig",
        lambda: demo_rig.rig_dynamics(
            *modules("playback.frame_cache"), output, args.width * 3 // 10, args.samples
        ),
    )
    rendered(
        "shape keys blended as shapes",
        lambda: demo_shapes.shapes_blended(
            modules("mesh_io", "shapes.blending"), output, args.shapes_subdivisions, half
        ),
    )
    rendered(
        "in-betweens",
        lambda: demo_inbetweens.inbetweens(
            modules("playback.frame_cache", "inbetweens.motion"),
            output,
            args.inbetweens_subdivisions,
            half,
        ),
    )


main()
