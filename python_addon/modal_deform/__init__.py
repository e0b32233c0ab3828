"""Modal Deform: pose high-resolution meshes with a physically based energy in a reduced space.

This file only registers the Blender layer. ``modal_deform.core`` is the bpy-free API and
imports without Blender, so the Blender modules are imported inside register().
"""
bl_info = {
    "name": "Modal Deform",
    "author": "Modal Deform developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Modal Deform",
    "description": "Interactive surface modeling with vibration modes and modal derivatives",
    "category": "Mesh",
}

# The Blender modules in registration order (properties before what refers to them).
_MODULES = ("properties", "storage", "ops_bake", "ops_handles", "ops_pose", "ops_animation", "ops_preview", "ui")


def _modules():
    import importlib
    return [importlib.import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
