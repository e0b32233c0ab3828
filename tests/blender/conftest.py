"""Headless Blender tests: each test runs one script in a fresh Blender session.

Which Blender: the environment variable BLENDER_PYTHON names the Python of a virtual environment
holding `bpy` (Blender 4.2+ as a module; `make test-bpy-4.5`, `make test-bpy-5.0`); without it,
the Blender app on PATH (Debian's 3.4.1; `make test-blender`).
- App: `blender -b [file] --factory-startup --python-exit-code 1 --python SCRIPT -- ARGS`, after a
  --python-expr that makes the test-support package importable (support.in_blender); the scripts
  enable the add-on from the source tree (support.blender.enable_addon).
- bpy: bpy_session.py runs the script after installing the extension zip from dist/ (`make addon`)
  with Blender's installer, in a session that sees neither the source tree's add-on nor the build
  machine's libraries: PYTHONPATH unset, LD_LIBRARY_PATH empty, user folders in the
  test's temporary folder.
- Windows bpy under Wine (`make test-windows-bpy-5.3`): BLENDER_PYTHON is
  tests/windows/wine_python.py and WINDOWS_PYTHON the python.exe of the Windows bpy environment;
  the Windows zips are installed.
A script fails by raising (exit code 1) and passes by running to its end: the tests read its output
only for what it reports.
"""

import os
import pathlib
import subprocess

import package
import pytest
import support

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPTS = pathlib.Path(__file__).resolve().parent / "scripts"
BLENDER_PYTHON = os.environ.get("BLENDER_PYTHON")
WINDOWS_PYTHON = os.environ.get("WINDOWS_PYTHON")
DIST = pathlib.Path(os.environ.get("MODAL_DEFORM_DIST", ROOT / "dist"))


def built(pattern):
    """The one file in dist/ matching `pattern` (made by `make addon`)."""
    found = sorted(DIST.glob(pattern))
    if len(found) != 1:
        pytest.fail(
            f"{DIST}: expected one {pattern}, found {[p.name for p in found]}: run `make addon`"
        )
    return found[0]


def blender_python_version():
    """ "3.13": the Python of the bpy venv (BLENDER_PYTHON), which is the one its Blender embeds."""
    return subprocess.run(
        [BLENDER_PYTHON, "-c", "import sys; print('%d.%d' % sys.version_info[:2])"],
        capture_output=True,
        text=True,
        check=True,
    ).stdout.strip()


def blender_platform():
    """The platform of the extension zips this Blender takes (package.PLATFORMS)."""
    return package.WINDOWS if WINDOWS_PYTHON else package.PLATFORM


def bpy_site_packages():
    """The bpy environment's site-packages: the embeddable Windows CPython's, or the venv's."""
    if WINDOWS_PYTHON:
        return pathlib.Path(WINDOWS_PYTHON).parent / "Lib" / "site-packages"
    (found,) = pathlib.Path(BLENDER_PYTHON).parents[1].glob("lib/python3.*/site-packages")
    return found


@pytest.fixture(scope="session")
def extension_zip():
    """The extension zip whose wheel is for this Blender's Python (package.EXTENSIONS)."""
    if not BLENDER_PYTHON:
        return None
    python = blender_python_version()
    extension = next((e for e in package.EXTENSIONS if e.python == python), None)
    if extension is None:
        pytest.fail(
            f"{BLENDER_PYTHON} runs Python {python}: no extension zip is made for it (package.EXTENSIONS)"
        )
    return built(package.extension_zip_name(extension, blender_platform()))


@pytest.fixture
def run_blender(tmp_path, extension_zip):
    """run_blender("script.py", *args, blend=None, env=None, addon=True, check=True) -> CompletedProcess.
    env: extra environment variables; addon=False: under bpy, no extension is installed;
    check: assert exit code 0."""

    def run(script, *args, blend=None, timeout=600, env=None, addon=True, check=True):
        script = SCRIPTS / script
        if BLENDER_PYTHON:
            command = [BLENDER_PYTHON, str(pathlib.Path(__file__).with_name("bpy_session.py"))]
            if addon:
                command += ["--extension", str(extension_zip)]
            if blend is not None:
                command += ["--blend", str(blend)]
            command += [str(script), "--", *map(str, args)]
            base = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
            base.update(LD_LIBRARY_PATH="", BLENDER_USER_RESOURCES=str(tmp_path / "blender_user"))
        else:
            command = ["blender", "-b"] + ([str(blend)] if blend is not None else [])
            command += [
                "--factory-startup",
                "--python-exit-code",
                "1",
                *support.in_blender(script),
                "--",
                *map(str, args),
            ]
            base = dict(os.environ)
        environment = dict(base, TEST_TMP=str(tmp_path), **(env or {}))
        result = subprocess.run(
            command, capture_output=True, text=True, timeout=timeout, env=environment, cwd=tmp_path
        )
        if check:
            assert result.returncode == 0, (
                f"{script.name} failed:\n{result.stdout[-4000:]}\n{result.stderr[-4000:]}"
            )
        return result

    return run
