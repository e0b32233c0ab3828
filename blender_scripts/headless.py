"""What the headless scripts share: their arguments after "--", the object they work on, saving, handles
made as an artist makes them, and Blender's Laplacian Deform to compare with."""

import argparse
import importlib
import pathlib
import sys
import time

import addon_utils
import bmesh
import bpy
import numpy as np

ADDON_PARENT = pathlib.Path(__file__).resolve().parents[1] / "python_addon"


def argument_parser(doc):
    """A parser for the arguments after Blender's own (``blender -b ... --python script.py -- ...``),
    with the --object and --output every script takes."""
    parser = argparse.ArgumentParser(
        description=doc, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--object", required=True, help="name of the mesh object")
    parser.add_argument("--output", help="save here instead of over the opened file")
    return parser


def parse(parser):
    return parser.parse_args(sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else [])


def enable_addon():
    """Enable Modal Deform and return its package: the extension Blender installed (4.2+, module
    bl_ext.<repository>.modal_deform) if there is one, else the add-on of this source tree."""
    installed = sorted(
        m.__name__
        for m in addon_utils.modules()
        if m.__name__.startswith("bl_ext.") and m.__name__.endswith(".modal_deform")
    )
    if installed:
        name = installed[0]
    else:
        name = "modal_deform"
        sys.path.append(str(ADDON_PARENT))
    if addon_utils.enable(name, default_set=True) is None:
        raise RuntimeError(f"enabling the add-on {name} failed (see the messages above)")
    return importlib.import_module(name)


def active_mesh_object(name):
    """Enable the add-on (enable_addon) and make the mesh object `name` active; exit with the reason
    if there is none."""
    enable_addon()
    obj = bpy.data.objects.get(name)
    if obj is None or obj.type != "MESH":
        sys.exit(f"--object: no mesh object named {name!r} in {bpy.data.filepath or 'the file'}")
    bpy.context.view_layer.objects.active = obj
    return obj


def run(operator, **options):
    """Call a Modal Deform operator; exit with code 1 and its message when it fails."""
    try:
        operator(**options)
    except RuntimeError as error:
        sys.exit(str(error))


def save(output):
    path = output or bpy.data.filepath
    if not path:
        sys.exit("--output: the opened file has no path to save to")
    bpy.ops.wm.save_as_mainfile(filepath=str(pathlib.Path(path).resolve()))


def smooth_suzanne(name, levels):
    """Blender's Suzanne as an object named `name`, subdivided `levels` times (the modifier
    applied) and shaded smooth: the demos' mesh."""
    bpy.ops.mesh.primitive_monkey_add()
    suzanne = bpy.context.object
    suzanne.name = name
    modifier = suzanne.modifiers.new("Subdivision", "SUBSURF")
    modifier.levels = levels
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    bpy.ops.object.shade_smooth()
    return suzanne


def add_handle(obj, mask):
    """A handle of obj's vertices in the boolean `mask`, made as an artist does: select them in Edit
    Mode, Add Handle (a vertex group and an Empty at their centre). Returns the handle."""
    bpy.context.view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    # Selected in Edit Mode: Blender 5.0.1 crashes setting MeshEdge.select (foreach_set or one by one)
    # on a mesh made by from_pydata.
    bpy.ops.mesh.select_all(action="DESELECT")
    bm = bmesh.from_edit_mesh(obj.data)
    bm.verts.ensure_lookup_table()
    for index in np.flatnonzero(mask):
        bm.verts[int(index)].select = True
    bm.select_flush(True)
    bmesh.update_edit_mesh(obj.data)
    result = bpy.ops.modal_deform.add_handle()
    bpy.ops.object.mode_set(mode="OBJECT")
    if result != {"FINISHED"}:
        raise RuntimeError(f"Add Handle on {obj.name!r} did not finish: {result}")
    return obj.modal_deform.handles[-1]


def bind_laplacian_deform(obj, anchors, moving):
    """Blender's Laplacian Deform on obj, bound to its current shape, with the vertices `anchors`
    held and those of them in `moving` carried by a hook to an Empty at the origin (its matrix_world
    is then the moving handle's transform). Every connected component needs an anchor, or the
    modifier finds no solution and passes the hooked mesh through. Returns the Empty and the bind
    time in seconds."""
    group = obj.vertex_groups.new(name="Moving")
    group.add(np.asarray(moving).tolist(), 1.0, "REPLACE")
    empty = bpy.data.objects.new(f"{obj.name} hook", None)
    bpy.context.scene.collection.objects.link(empty)
    hook = obj.modifiers.new("Hook", "HOOK")
    hook.object, hook.vertex_group = empty, group.name
    group = obj.vertex_groups.new(name="Anchors")
    group.add(np.asarray(anchors).tolist(), 1.0, "REPLACE")
    laplacian = obj.modifiers.new("LaplacianDeform", "LAPLACIANDEFORM")
    laplacian.vertex_group = group.name
    bpy.context.view_layer.update()
    start = time.perf_counter()
    with bpy.context.temp_override(object=obj, active_object=obj):
        bpy.ops.object.laplaciandeform_bind(modifier=laplacian.name)
    bpy.context.view_layer.update()
    return empty, time.perf_counter() - start


def evaluated_positions(obj):
    """obj's vertex positions after its modifiers and shape keys, (n, 3) float32."""
    evaluated = obj.evaluated_get(bpy.context.evaluated_depsgraph_get())
    mesh = evaluated.to_mesh()
    co = np.empty(3 * len(mesh.vertices), np.float32)
    mesh.vertices.foreach_get("co", co)
    evaluated.to_mesh_clear()
    return co.reshape(-1, 3)
