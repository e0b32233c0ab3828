"""Modal Deform: pose high-resolution meshes with a physically based energy in a reduced space.

This file only finds the compiled core and registers the Blender layer. ``modal_deform.core`` is
the bpy-free API and imports without Blender, so the Blender modules are imported inside register().
Every import is relative: installed as an extension the package is ``bl_ext.<repository>.modal_deform``.
"""
import importlib
import importlib.util
import sys

bl_info = {
    "name": "Modal Deform",
    "author": "Modal Deform developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "View3D > Sidebar > Modal Deform",
    "description": "Interactive surface modeling with vibration modes and modal derivatives",
    "category": "Mesh",
}


def _find_native():
    """Make the compiled core importable as ``<this package>._native``. The source tree and the
    legacy add-on zip carry it in this folder; Blender 4.2+ installs it from the extension's bundled
    wheel into the extensions' site-packages as ``modal_deform_native._native``."""
    name = f"{__name__}._native"
    if name in sys.modules or importlib.util.find_spec("._native", __name__) is not None:
        return
    if importlib.util.find_spec("modal_deform_native") is None:
        raise ImportError(f"{__name__}: the compiled core is missing: no {name} (source tree: run `make build`) "
                          "and no modal_deform_native (installed from the extension's wheel)")
    sys.modules[name] = importlib.import_module("modal_deform_native._native")


_find_native()

# The Blender modules in registration order (properties before what refers to them).
_MODULES = ("properties", "storage", "ops_bake", "ops_handles", "ops_pose", "ops_animation", "ops_preview", "ui")


def _modules():
    return [importlib.import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
