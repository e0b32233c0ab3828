#!/usr/bin/python3
"""BLENDER_PYTHON for tests/blender in Windows `bpy` under Wine (windows/windows.mk:
make test-windows-blender-X.Y): runs WINDOWS_PYTHON, the python.exe of a Windows bpy environment,
under Wine with this command's arguments. Absolute paths, among the arguments and in the variables
that name folders for the scripts and for Blender, are written as Windows programs under Wine see
them (drive Z: is /). Windows CPython needs its standard input and output to be pipes (it stops in
init_sys_streams otherwise): its output is read here and passed on. The exit status is Python's;
a crash is a non-zero status (the Wine prefix starts no debugger)."""

import os
import subprocess
import sys

WINE = "/usr/lib/wine/wine64"
PATH_VARIABLES = ("BLENDER_USER_RESOURCES", "TEST_TMP")


def windows_path(argument):
    return "Z:" + argument.replace("/", "\\") if argument.startswith("/") else argument


def main():
    environment = dict(os.environ, WINEDEBUG="-all")
    for name in PATH_VARIABLES:
        if name in environment:
            environment[name] = windows_path(environment[name])
    command = [WINE, os.environ["WINDOWS_PYTHON"], *map(windows_path, sys.argv[1:])]
    result = subprocess.run(command, input=b"", capture_output=True, env=environment)
    sys.stdout.buffer.write(result.stdout)
    sys.stderr.buffer.write(result.stderr)
    return result.returncode


if __name__ == "__main__":
    sys.exit(main())
