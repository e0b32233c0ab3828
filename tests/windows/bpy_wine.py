"""tests/blender/bpy_session.py for Windows `bpy` under Wine (tests/windows/test_windows_bpy.py):
install the extension zip with Blender's own installer, check that the add-on and its compiled core
come from the user folder Blender installed them into, then run a tests/blender script.

    python.exe bpy_wine.py [--extension ZIP] [--blend FILE.blend] SCRIPT [-- ARGS...]
"""
import argparse
import os
import pathlib
import runpy
import sys

import bpy

MODULE = "bl_ext.user_default.modal_deform"


def install_extension(zip_path):
    result = bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default",
                                                      enable_on_install=True)
    assert result == {"FINISHED"}, f"installing {zip_path} as an extension: {result}"
    assert MODULE in bpy.context.preferences.addons, f"{MODULE} is not enabled after installing {zip_path}"
    user = os.path.normcase(os.path.realpath(os.environ["BLENDER_USER_RESOURCES"])) + os.sep
    for module in (sys.modules[MODULE], sys.modules[f"{MODULE}._native"]):
        path = os.path.normcase(os.path.realpath(module.__file__))
        assert path.startswith(user), f"{module.__name__} from {module.__file__}, not from {user}"


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
    sys.argv = [str(arguments.script), "--", *argv[split + 1:]]
    runpy.run_path(str(arguments.script), run_name="__main__")


if __name__ == "__main__":
    main()
