"""Modal Deform: pose high-resolution meshes with a physically based energy in a reduced space.

This file only finds the compiled core and registers the Blender layer. ``modal_deform.core`` is
the bpy-free API and imports without Blender, so the Blender modules are imported inside register().
Every import is relative: installed as an extension the package is ``bl_ext.<repository>.modal_deform``.
"""
import contextlib
import ctypes
import importlib
import importlib.util
import os
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


@contextlib.contextmanager
def _passive_openmp_wait():
    """GCC's OpenMP (the core's loops and CHOLMOD's) reads its wait policy once, when the core loads
    it. By default its idle threads spin at every barrier, and on cores that other work shares (the
    artist's Blender draws while it bakes) they take the core from the thread that has work
    (bench/results/bake_busy.json; docs/measurements.md, "A bake beside a busy core"). Set only
    while the core loads and only when the user chose no policy: other add-ons never see it. An
    OpenMP runtime loaded before the core (Debian's Blender shares the system's) keeps its own."""
    if {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"} & os.environ.keys():
        yield
        return
    os.environ["OMP_WAIT_POLICY"] = "passive"
    _set_core_c_environment("OMP_WAIT_POLICY=passive")
    try:
        yield
    finally:
        del os.environ["OMP_WAIT_POLICY"]
        _set_core_c_environment("OMP_WAIT_POLICY=")


def _set_core_c_environment(assignment):
    """The Windows core's C runtime is msvcrt.dll (MinGW-w64's), which keeps a copy of the
    environment of its own: os.environ changes the process's and the UCRT's, and libgomp reads
    msvcrt's ("NAME=" removes NAME)."""
    if sys.platform == "win32":
        ctypes.cdll.msvcrt._putenv(assignment.encode())


def _find_native():
    """Make the compiled core importable as ``<this package>._native``. The source tree and the
    legacy add-on zip carry it in this folder; Blender 4.2+ installs it from the extension's bundled
    wheel into the extensions' site-packages as ``modal_deform_native._native``."""
    name = f"{__name__}._native"
    if name in sys.modules:
        return
    with _passive_openmp_wait():
        if importlib.util.find_spec("._native", __name__) is not None:
            importlib.import_module(name)
            return
        if importlib.util.find_spec("modal_deform_native") is None:
            raise ImportError(f"{__name__}: the compiled core is missing: no {name} (source tree: run `make build`) "
                              "and no modal_deform_native (installed from the extension's wheel)")
        sys.modules[name] = importlib.import_module("modal_deform_native._native")


_find_native()

# The Blender modules in registration order (properties before what refers to them).
_MODULES = ("properties", "storage", "playback", "ops_bake", "ops_handles", "ops_pose", "pose_recovery",
            "ops_dynamics", "ops_animation", "ops_preview", "ui")


def _modules():
    return [importlib.import_module(f".{name}", __name__) for name in _MODULES]


def register():
    for module in _modules():
        module.register()


def unregister():
    for module in reversed(_modules()):
        module.unregister()
