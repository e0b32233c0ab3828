"""Headless Blender tests: each test runs one script in a fresh `blender -b --factory-startup`.

A script signals failure by raising (Blender then exits with code 1 via --python-exit-code).
Scripts find the add-on through the ADDON_PATH environment variable.
"""
import os
import pathlib
import subprocess

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPTS = pathlib.Path(__file__).resolve().parent / "scripts"


@pytest.fixture
def run_blender(tmp_path):
    """run_blender("script.py", *args, blend=None, env=None) -> CompletedProcess; asserts exit code 0.
    env: extra environment variables."""

    def run(script, *args, blend=None, timeout=600, env=None):
        command = ["blender", "-b"]
        if blend is not None:
            command.append(str(blend))
        command += ["--factory-startup", "--python-exit-code", "1", "--python", str(SCRIPTS / script), "--", *map(str, args)]
        env = dict(os.environ, ADDON_PATH=str(ROOT / "python_addon"), TEST_TMP=str(tmp_path), **(env or {}))
        result = subprocess.run(command, capture_output=True, text=True, timeout=timeout, env=env, cwd=tmp_path)
        assert result.returncode == 0, f"{script} failed:\n{result.stdout[-4000:]}\n{result.stderr[-4000:]}"
        return result

    return run
