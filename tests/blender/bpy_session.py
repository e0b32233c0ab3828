"""Run a test script in `bpy` (Blender as a Python module) as the Blender app runs it with
`blender -b [FILE.blend] --factory-startup --python-exit-code 1 --python SCRIPT -- ARGS`, after
installing the add-on's extension zip with Blender's own installer, as an artist does.

    python bpy_session.py [--extension ZIP] [--blend FILE.blend] SCRIPT [-- ARGS...]

The caller points Blender's user folders into a fresh folder (BLENDER_USER_RESOURCES): the
extension is installed there, into the "user_default" repository, as bl_ext.user_default.modal_deform.
A failing script raises, which ends this process with exit code 1.
"""

import argparse
import os
import pathlib
import re
import runpy
import sys

import bpy

MODULE = "bl_ext.user_default.modal_deform"
# Libraries of the compiled core (CHOLMOD, its orderings, OpenBLAS, Fortran and OpenMP runtimes):
# inside Blender they must come from the extension's wheel, never from the machine.
CORE_LIBRARIES = re.compile(
    r"lib(cholmod|amd|camd|colamd|ccolamd|suitesparseconfig|metis|openblas|blas|lapack|"
    r"gfortran|quadmath|gomp)\b"
)
PRIVATE_NAME = re.compile(r"-[0-9a-f]{8}\.")  # auditwheel's renaming: libcholmod-7426373e.so.3.0.14
WINDOWS = sys.platform == "win32"


def mapped_files():
    """The files of the libraries in this process: its modules on Windows, its mapped files on Linux."""
    if WINDOWS:
        return loaded_modules()
    return {
        line.split(maxsplit=5)[5].strip()
        for line in open("/proc/self/maps")
        if len(line.split()) == 6
    }


def loaded_modules():
    import ctypes
    from ctypes import wintypes

    psapi, process = ctypes.WinDLL("psapi"), ctypes.windll.kernel32.GetCurrentProcess()
    psapi.EnumProcessModules.argtypes = [
        wintypes.HANDLE,
        ctypes.POINTER(wintypes.HMODULE),
        wintypes.DWORD,
        ctypes.POINTER(wintypes.DWORD),
    ]
    psapi.GetModuleFileNameExW.argtypes = [
        wintypes.HANDLE,
        wintypes.HMODULE,
        wintypes.LPWSTR,
        wintypes.DWORD,
    ]
    modules, needed = (wintypes.HMODULE * 4096)(), wintypes.DWORD()
    assert psapi.EnumProcessModules(process, modules, ctypes.sizeof(modules), ctypes.byref(needed))
    name = ctypes.create_unicode_buffer(32768)
    count = min(needed.value // ctypes.sizeof(wintypes.HMODULE), len(modules))
    return {
        name.value
        for module in modules[:count]
        if psapi.GetModuleFileNameExW(process, module, name, len(name))
    }


def install_extension(zip_path):
    blenders_own = mapped_files()
    result = bpy.ops.extensions.package_install_files(
        filepath=str(zip_path), repo="user_default", enable_on_install=True
    )
    assert result == {"FINISHED"}, f"installing {zip_path} as an extension: {result}"
    assert MODULE in bpy.context.preferences.addons, (
        f"{MODULE} is not enabled after installing {zip_path}"
    )
    assert hasattr(bpy.types.Object, "modal_deform"), "the extension did not register"
    check_nothing_of_the_build_machine_is_used(mapped_files() - blenders_own)


def inside(path, folder):
    return os.path.normcase(os.path.realpath(path)).startswith(
        os.path.normcase(os.path.realpath(folder)) + os.sep
    )


def check_nothing_of_the_build_machine_is_used(loaded):
    """The add-on and its compiled core come from the user folder Blender installed them into, and
    no library of the core among those `loaded` with it is the machine's own. On Linux (the -dev
    packages' /usr/lib/.../libcholmod.so.3 ...) every one has a wheel's private name (what Blender
    loaded before is its own: bpy 4.2.0 maps the system's libgomp itself). On Windows CHOLMOD is
    linked into the core and the OpenBLAS DLL bundled beside it: every DLL loaded with the core is
    the extension's, Windows's or this Python's and Blender's own (sys.prefix)."""
    user = os.environ["BLENDER_USER_RESOURCES"]
    for module in (sys.modules[MODULE], sys.modules[f"{MODULE}._native"]):
        assert inside(module.__file__, user), f"{module.__name__} from {module.__file__}"
    if WINDOWS:
        machine = [
            path
            for path in loaded
            if not any(
                inside(path, folder) for folder in (user, os.environ["SystemRoot"], sys.prefix)
            )
        ]
        assert not machine, f"the compiled core loaded DLLs of this machine: {machine}"
        bundled = [path for path in loaded if inside(path, user) and path.lower().endswith(".dll")]
        assert bundled, f"no DLL of the extension among {sorted(loaded)}"
        return
    core = sorted(path for path in loaded if CORE_LIBRARIES.match(os.path.basename(path)))
    machine = [path for path in core if not PRIVATE_NAME.search(os.path.basename(path))]
    assert not machine, f"the compiled core loaded libraries of this machine: {machine}"
    cholmod = [path for path in core if "cholmod" in path]
    assert cholmod and all(inside(path, user) for path in cholmod), cholmod


def main():
    argv = sys.argv[1:]
    split = argv.index("--") if "--" in argv else len(argv)
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--extension", type=pathlib.Path, help="the extension zip to install first")
    parser.add_argument(
        "--blend", type=pathlib.Path, help="a .blend file to open before the script runs"
    )
    parser.add_argument("script", type=pathlib.Path)
    arguments = parser.parse_args(argv[:split])

    bpy.ops.wm.read_factory_settings(use_empty=False)
    if arguments.extension:
        install_extension(arguments.extension)
    if arguments.blend:
        bpy.ops.wm.open_mainfile(filepath=str(arguments.blend))
    sys.argv = [str(arguments.script), *argv[split:]]
    # The test-support package and the script's folder, as support.in_blender gives the app.
    sys.path[:0] = [
        str(pathlib.Path(__file__).resolve().parents[1]),
        str(arguments.script.resolve().parent),
    ]
    runpy.run_path(str(arguments.script), run_name="__main__")


if __name__ == "__main__":
    main()
