"""Modal Deform: pose high-resolution meshes with a physically based energy in a reduced space.

This file only registers the Blender layer, once native_loader made the compiled core importable.
``modal_deform.core`` is the bpy-free API and imports without Blender, so the Blender modules are
imported inside register(). The interactive pose is in pose/, playback on the timeline in playback/,
shape keys blended as shapes in shapes/.
Every import is relative: installed as an extension the package is ``bl_ext.<repository>.modal_deform``.
"""

import importlib

from . import native_loader

bl_info = {
    "name": "Modal Deform",
    "author": "Modal Deform developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Modal Deform",
    "description": "Interactive surface modeling with vibration modes and modal derivatives",
    "category": "Mesh",
}

native_loader.find_native()

# The Blender modules in registration order (properties before what refers to them).
_MODULES = (
    "properties",
    "storage",
    "playback.timeline",
    "ops_bake",
    "ops_handles",
    "pose.operators",
    "pose.recovery",
    "playback.operators",
    "playback.bake_animation",
    "ops_preview",
    "shapes.blending",
    "shapes.operators",
    "ui",
    "shapes.panel",
)


def _modules():
    return [importlib.import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
