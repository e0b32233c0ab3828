"""Inside Blender: what the test scripts share (``from support import blender as support``).

Enabling the add-on and making handles are blender_scripts/headless.py's, the user-facing helpers
the demo and the benchmarks use too: this module puts that folder on sys.path and builds on them.
"""

import importlib
import os
import pathlib
import sys

import bpy
import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "blender_scripts"))
import headless  # noqa: E402
from headless import add_handle, evaluated_positions  # noqa: E402,F401 (the scripts call them from here)


def enable_addon(*modules):
    """Enable Modal Deform (the installed extension under bpy, else the source tree) and return the
    add-on's modules named, e.g. enable_addon("core", "storage"); its package when none is named."""
    package = headless.enable_addon()
    assert hasattr(bpy.types.Object, "modal_deform"), "the add-on did not register"
    if not modules:
        return package
    found = tuple(importlib.import_module(f"{package.__name__}.{name}") for name in modules)
    return found[0] if len(found) == 1 else found


def tmp(name):
    return os.path.join(os.environ["TEST_TMP"], name)


def suzanne(levels=1):
    """Suzanne with `levels` of Catmull-Clark subdivision applied (quads), selected and active, in
    place of the startup file's objects."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    bpy.ops.mesh.primitive_monkey_add()
    obj = bpy.context.object
    if levels:
        modifier = obj.modifiers.new("Subdivision", "SUBSURF")
        modifier.levels = levels
        bpy.ops.object.modifier_apply(modifier=modifier.name)
    return obj


def baked_suzanne(levels, modes, derivatives, ghost):
    """suzanne(levels) baked through the operator with these settings; (obj, rest positions)."""
    obj = suzanne(levels)
    obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = (
        modes,
        derivatives,
        ghost,
    )
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    return obj, positions(obj)


def top_and_bottom_handles(obj, rest):
    """A handle on the top of the head (returned, its controller free to move) and one on the chin,
    pinned where it is."""
    top = add_handle(obj, rest[:, 2] > 0.5)
    add_handle(obj, rest[:, 2] < -0.5).controller = None
    return top


def keyed_suzanne(last_frame, modes, derivatives, ghost):
    """baked_suzanne(1, ...) with top_and_bottom_handles, the top's controller keyed to slide by 0.5
    along y from frame 1 to `last_frame`; (obj, rest positions, controller)."""
    obj, rest = baked_suzanne(1, modes, derivatives, ghost)
    controller = top_and_bottom_handles(obj, rest).controller
    controller.keyframe_insert("location", frame=1)
    controller.location.y += 0.5
    controller.keyframe_insert("location", frame=last_frame)
    return obj, rest, controller


def positions(obj):
    co = np.empty(3 * len(obj.data.vertices), np.float32)
    obj.data.vertices.foreach_get("co", co)
    return co.reshape(-1, 3)


def key_positions(obj, name):
    block = obj.data.shape_keys.key_blocks[name]
    co = np.empty(3 * len(block.data), np.float32)
    block.data.foreach_get("co", co)
    return co.reshape(-1, 3)


def stored_bases():
    """Names of the datablocks holding baked bases (the startup file has a palette of its own)."""
    return sorted(p.name for p in bpy.data.palettes if p.name.startswith(".Modal Deform"))


def mesh_state(obj):
    """Everything of the mesh a cancelled or restoring operator must leave as it was."""
    mesh = obj.data
    return {
        "co": positions(obj).tobytes(),
        "polygons": len(mesh.polygons),
        "loops": len(mesh.loops),
        "shape_keys": None
        if mesh.shape_keys is None
        else [
            (b.name, b.value, b.mute, key_positions(obj, b.name).tobytes())
            for b in mesh.shape_keys.key_blocks
        ],
        "basis": obj.modal_deform.basis,
        "palettes": stored_bases(),
        "status": obj.modal_deform.status.dimension,
        "vertex_groups": len(obj.vertex_groups),
    }


def arguments():
    """The script's arguments (after "--")."""
    return sys.argv[sys.argv.index("--") + 1 :] if "--" in sys.argv else []


def mesh_object(name, V, F):
    """A mesh object from arrays (V #V by 3, F a list of faces of any size), active, in the scene."""
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata([tuple(v) for v in V], [], [tuple(f) for f in F])
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    bpy.context.view_layer.objects.active = obj
    obj.select_set(True)
    return obj


def expect_error(operator, fragment, **kwargs):
    """Run `operator` and check that it fails with a message containing `fragment`."""
    try:
        operator(**kwargs)
    except RuntimeError as error:
        assert fragment in str(error), f"expected {fragment!r} in the error, got: {error}"
        return str(error)
    raise AssertionError(f"{operator} did not fail (expected {fragment!r})")
