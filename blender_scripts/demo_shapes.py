"""The demo's shape keys blended as shapes (issue 52): Suzanne with a jaw-open key and an ears-fold
key, made here as an artist sculpts them (each a smooth-weighted rotation about a hinge), both at
0.5, shown by Blender's linear mix and by Blend as Shapes (turned on with its operator, as in the
Shape Keys panel), with the keys at 1 for reference, as a strip OUTPUT/demo_shapes.png.

Called by demo.py after its stage (camera, light, Cycles) is set up; run inside Blender.
"""

import math
import time

import bpy
import numpy as np
from headless import smooth_suzanne
from mathutils import Vector
from mathutils.bvhtree import BVHTree
from rendering import look_at, render, side_by_side

#: The jaw: vertices below the mouth and in front (a smooth step from JAW_BELOW - JAW_BLEND down
#: and from JAW_FRONT back) turn by JAW_ANGLE degrees about the x axis through JAW_HINGE (y, z).
JAW_BELOW, JAW_FRONT, JAW_HINGE, JAW_ANGLE = -0.35, 0.2, (0.35, -0.3), 30
#: The ears: beyond EAR_ROOT (|x|, where each ear leaves the head) a smooth step EAR_BLEND wide
#: turns them by EAR_ANGLE degrees down in their own plane, about a hinge through the foot of the
#: root (EAR_ROOT, EAR_HINGE) square to the ear (front to back, turned EAR_FACING degrees outward
#: as the ear faces): from sticking out sideways to hanging along the cheek.
EAR_ROOT, EAR_BLEND, EAR_HINGE, EAR_FACING, EAR_ANGLE = 0.85, 0.3, (0.35, 0.0), 20, 135
#: The camera for this strip: in front of Suzanne, a little to her left (+x) and above.
EYE, TARGET, LENS = (1.2, -6.5, 0.9), (0.0, 0.0, -0.1), 65


def _smooth(t):
    t = np.clip(t, 0.0, 1.0)
    return t * t * (3 - 2 * t)


def _turned(P, weight, axis, centre, angle):
    """P with each vertex turned by its `weight` times `angle` (radians) about `axis` through
    `centre` (Rodrigues' formula); the vertices of weight 0 stay exactly where they are."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    moved = weight > 0
    theta = (angle * weight[moved])[:, None]
    p = P[moved] - centre
    X = P.copy()
    X[moved] = (
        centre
        + p * np.cos(theta)
        + np.cross(a, p) * np.sin(theta)
        + a * (p @ a)[:, None] * (1 - np.cos(theta))
    )
    return X


def ear_hinges():
    """Each ear's hinge: (side, centre, axis), side +1 for the left ear (+x), -1 for the right."""
    facing = math.radians(EAR_FACING)
    return [
        (
            side,
            np.array([side * EAR_ROOT, *EAR_HINGE]),
            np.array([-side * math.sin(facing), math.cos(facing), 0.0]),
        )
        for side in (1, -1)
    ]


def jaw_open(V):
    weight = _smooth((JAW_BELOW - V[:, 2]) / 0.15) * _smooth((JAW_FRONT - V[:, 1]) / 0.3)
    centre = np.array([0.0, *JAW_HINGE])
    return _turned(V, weight, (1, 0, 0), centre, math.radians(JAW_ANGLE))


def ears_fold(V):
    X = V.copy()
    for side, centre, axis in ear_hinges():
        weight = _smooth((side * V[:, 0] - EAR_ROOT) / EAR_BLEND)
        X = _turned(X, weight, axis, centre, side * math.radians(EAR_ANGLE))
    return X


def self_intersections(X, F):
    """Pairs of triangles of the mesh (X, F) that cross each other, neighbours left out."""
    tree = BVHTree.FromPolygons(X.tolist(), F.tolist(), all_triangles=True)
    return {(min(i, j), max(i, j)) for i, j in tree.overlap(tree) if not set(F[i]) & set(F[j])}


def _positions(obj):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    mesh = obj.evaluated_get(depsgraph).to_mesh()
    X = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", X)
    obj.evaluated_get(depsgraph).to_mesh_clear()
    return X.reshape(-1, 3).astype(np.float64)


def shapes_blended(addon, output, levels, width):
    """Suzanne subdivided `levels` times with the jaw and ears keys; renders (`width` pixels wide
    each) Blender's mix at 0.5, Blend as Shapes at 0.5 and the keys at 1 into OUTPUT/demo_shapes.png
    and prints the ears' lengths and the blend's time. Returns the strip's path."""
    mesh_io, blending = addon
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = width, width * 3 // 4
    shown = [o for o in scene.objects if o.type == "MESH" and not o.hide_render]
    for obj in shown:
        obj.hide_render = True
    camera, sun = scene.camera, next(o for o in scene.objects if o.type == "LIGHT")
    placed = camera.matrix_world.copy(), sun.matrix_world.copy(), camera.data.lens
    look_at(camera, EYE, TARGET)
    camera.data.lens = LENS
    sun.rotation_euler = (
        (Vector(TARGET) - Vector(EYE) + Vector((-0.6, 0.6, -1.0)))
        .to_track_quat("-Z", "Y")
        .to_euler()
    )

    suzanne = smooth_suzanne("Suzanne shapes", levels)
    mesh = suzanne.data
    V = mesh_io.vertex_positions(mesh).astype(np.float64)
    F = mesh_io.triangles(mesh)
    keys = {"Jaw open": jaw_open(V), "Ears fold": ears_fold(V)}
    suzanne.shape_key_add(name="Basis")
    crossing = self_intersections(V, F)
    for name, X in keys.items():
        block = suzanne.shape_key_add(name=name, from_mix=False)
        block.data.foreach_set("co", X.astype(np.float32).ravel())
        print(
            f"shape key '{name}': {len(self_intersections(X, F) - crossing)} triangle pairs "
            f"crossing that do not cross at rest"
        )
    blocks = mesh.shape_keys.key_blocks

    def weigh(value):
        for name in keys:
            blocks[name].value = value
        bpy.context.view_layer.update()

    pictures = {}
    weigh(1.0)
    at_one = _positions(suzanne)
    pictures["keys"] = render(output / "demo_shapes_keys.png")
    weigh(0.5)
    linear = _positions(suzanne)
    pictures["linear"] = render(output / "demo_shapes_linear.png")
    bpy.context.view_layer.objects.active = suzanne
    start = time.perf_counter()
    assert bpy.ops.modal_deform.blend_as_shapes() == {"FINISHED"}
    print(
        f"Blend as Shapes on: {len(V)} vertices, 2 keys baked and shown in "
        f"{time.perf_counter() - start:.1f} s"
    )
    blended = _positions(suzanne)
    pictures["blend"] = render(output / "demo_shapes_blend.png")

    space = blending.load(suzanne)
    times = []
    for _ in range(20):
        space.blend([0.5, 0.5])
        times.append(space.stats["ms"])
    stats = space.stats
    print(
        f"the blend at 0.5, 0.5: {np.median(times):.1f} ms (median of {len(times)}, the map "
        f"included; {stats['iterations']} BFGS iterations, converged {stats['converged']})"
    )
    hinge = ear_hinges()[0][1]
    tip = int(np.argmax(V[:, 0]))
    print(
        "the left ear from its hinge to its tip: "
        + ", ".join(
            f"{name} {np.linalg.norm(X[tip] - hinge):.3f}"
            for name, X in (
                ("rest", V),
                ("key", keys["Ears fold"]),
                ("Blender's mix at 0.5", linear),
                ("Blend as Shapes at 0.5", blended),
            )
        )
    )
    still = np.all([np.all(X == V, axis=1) for X in keys.values()], axis=0)
    moved = np.linalg.norm(blended - V, axis=1)
    most = np.flatnonzero(still)[np.argmax(moved[still])]
    print(
        f"the {int(still.sum())} vertices that neither key moves moved in the blend by "
        f"{np.median(moved[still]):.3f} (median), at most {moved[most]:.3f} (at "
        f"{np.round(V[most], 2).tolist()}; Suzanne is {np.ptp(V[:, 0]):.2f} wide); the top of "
        f"the head at {blended[:, 2].max():.3f} (at rest {V[:, 2].max():.3f}); Blender's mix "
        f"of the keys at 1 is the keys to "
        f"{np.abs(at_one - (keys['Jaw open'] + keys['Ears fold'] - V)).max():.0e}"
    )

    camera.matrix_world, sun.matrix_world, camera.data.lens = placed
    bpy.data.objects.remove(suzanne)
    for obj in shown:
        obj.hide_render = False
    strip = output / "demo_shapes.png"
    side_by_side([pictures[name] for name in ("linear", "blend", "keys")], strip)
    return strip
