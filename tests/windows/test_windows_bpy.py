"""The Windows extension zips in Windows `bpy` (Blender as a Python module, from its win_amd64
wheel) under Wine, through Blender's own installer (windows/windows.mk: make test-windows-bpy):
install, enable, bake Suzanne, pose, save, reload and pose again; install, disable, enable; the
zips for other Blenders and for Linux are refused. The tests/blender scripts run inside Blender by
tests/windows/bpy_wine.py. WINDOWS_BPY_PYTHON names the python.exe of the bpy environment."""
import os
import pathlib
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPTS = ROOT / "tests" / "blender" / "scripts"
sys.path.insert(0, str(ROOT / "python_addon"))
import package  # noqa: E402

PYTHON = os.environ.get("WINDOWS_BPY_PYTHON")
WINE = "/usr/lib/wine/wine64"
pytestmark = pytest.mark.skipif(not PYTHON, reason="WINDOWS_BPY_PYTHON is not set (make test-windows-bpy sets it)")
EXTENSIONS = {extension.python: extension for extension in package.EXTENSIONS}


def windows_path(path):
    """The path as Windows programs under Wine see it (drive Z: is /)."""
    return "Z:" + str(path).replace("/", "\\")


def zip_path(python, platform=package.WINDOWS):
    path = ROOT / "dist" / package.extension_zip_name(EXTENSIONS[python], platform)
    if not path.is_file():
        pytest.fail(f"{path}: missing: run `make addon`")
    return path


def blender_python():
    """"3.11": the Python of the bpy environment."""
    pth = next(pathlib.Path(PYTHON).parent.glob("python3*._pth")).name  # python311._pth
    return f"3.{pth[len('python3'):-len('._pth')]}"


def run(tmp_path, script, *args, extension=None, blend=None):
    """Runs tests/blender/scripts/SCRIPT in Windows bpy; its user folders in tmp_path/blender_user."""
    command = [WINE, PYTHON, windows_path(pathlib.Path(__file__).with_name("bpy_wine.py"))]
    if extension is not None:
        command += ["--extension", windows_path(extension)]
    if blend is not None:
        command += ["--blend", windows_path(blend)]
    command += [windows_path(SCRIPTS / script), "--", *args]
    env = dict(os.environ, WINEDEBUG="-all", BLENDER_USER_RESOURCES=windows_path(tmp_path / "blender_user"),
               TEST_TMP=windows_path(tmp_path))
    # Windows CPython needs its standard input and output to be pipes.
    result = subprocess.run(command, input="", capture_output=True, text=True, timeout=900, env=env, cwd=tmp_path)
    assert result.returncode == 0, f"{script} failed ({result.returncode}):\n{result.stdout[-4000:]}\n{result.stderr[-4000:]}"
    return result.stdout


def test_bake_pose_save_reload_and_pose_again(tmp_path):
    extension = zip_path(blender_python())
    assert "BAKED Suzanne" in run(tmp_path, "bake_and_save.py", "suzanne", extension=extension)
    run(tmp_path, "reload_and_solve.py", extension=extension, blend=tmp_path / "baked.blend")


def test_install_disable_enable(tmp_path):
    user = tmp_path / "blender_user"
    assert "INSTALL_OK" in run(tmp_path, "install_enable_disable.py", windows_path(zip_path(blender_python())),
                               windows_path(user))


def test_the_zips_for_other_blenders_and_for_linux_are_refused(tmp_path):
    python = blender_python()
    others = [zip_path(other) for other in EXTENSIONS if other != python]
    others.append(zip_path(python, package.PLATFORM))
    for other in others:
        output = run(tmp_path, "install_refused.py", windows_path(other))
        assert "REFUSED" in output, output
