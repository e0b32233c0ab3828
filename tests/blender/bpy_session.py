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
CORE_LIBRARIES = re.compile(r"lib(cholmod|amd|camd|colamd|ccolamd|suitesparseconfig|metis|openblas|blas|lapack|"
                            r"gfortran|quadmath|gomp)\b")
PRIVATE_NAME = re.compile(r"-[0-9a-f]{8}\.")  # auditwheel's renaming: libcholmod-7426373e.so.3.0.14


def mapped_files():
    return {line.split(maxsplit=5)[5].strip() for line in open("/proc/self/maps") if len(line.split()) == 6}


def install_extension(zip_path):
    blenders_own = mapped_files()
    result = bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default",
                                                      enable_on_install=True)
    assert result == {"FINISHED"}, f"installing {zip_path} as an extension: {result}"
    assert MODULE in bpy.context.preferences.addons, f"{MODULE} is not enabled after installing {zip_path}"
    assert hasattr(bpy.types.Object, "modal_deform"), "the extension did not register"
    check_nothing_of_the_build_machine_is_used(mapped_files() - blenders_own)


def check_nothing_of_the_build_machine_is_used(loaded):
    """The add-on and its compiled core come from the user folder Blender installed them into, and
    no library of the core among those `loaded` with it is the machine's own (the -dev packages'
    /usr/lib/.../libcholmod.so.3 ...): every one has a wheel's private name. (What Blender loaded
    before is its own: bpy 4.2.0 maps the system's libgomp itself.)"""
    user = os.path.realpath(os.environ["BLENDER_USER_RESOURCES"]) + os.sep
    for module in (sys.modules[MODULE], sys.modules[f"{MODULE}._native"]):
        assert os.path.realpath(module.__file__).startswith(user), f"{module.__name__} from {module.__file__}"
    core = sorted(path for path in loaded if CORE_LIBRARIES.match(os.path.basename(path)))
    machine = [path for path in core if not PRIVATE_NAME.search(os.path.basename(path))]
    assert not machine, f"the compiled core loaded libraries of this machine: {machine}"
    cholmod = [path for path in core if "cholmod" in path]
    assert cholmod and all(os.path.realpath(path).startswith(user) for path in cholmod), cholmod


def main():
    argv = sys.argv[1:]
    split = argv.index("--") if "--" in argv else len(argv)
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--extension", type=pathlib.Path, help="the extension zip to install first")
    parser.add_argument("--blend", type=pathlib.Path, help="a .blend file to open before the script runs")
    parser.add_argument("script", type=pathlib.Path)
    arguments = parser.parse_args(argv[:split])

    bpy.ops.wm.read_factory_settings(use_empty=False)
    if arguments.extension:
        install_extension(arguments.extension)
    if arguments.blend:
        bpy.ops.wm.open_mainfile(filepath=str(arguments.blend))
    sys.argv = [str(arguments.script), *argv[split:]]
    runpy.run_path(str(arguments.script), run_name="__main__")


if __name__ == "__main__":
    main()
