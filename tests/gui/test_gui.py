"""Blender with a window under Xvfb, driven by simulated events (see scripts/pose_with_mouse.py)."""
import json
import os
import pathlib
import subprocess

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCRIPTS = pathlib.Path(__file__).resolve().parent / "scripts"


def test_pose_with_simulated_mouse_and_keys():
    # The screenshots stay as the test's artefacts (build/ is the build's own, ignored by git).
    artefacts = ROOT / "build" / "test-artefacts" / "gui"
    artefacts.mkdir(parents=True, exist_ok=True)
    for old in artefacts.iterdir():  # a result left by an earlier run must not pass this one
        old.unlink()
    command = ["xvfb-run", "-a", "-s", "-screen 0 1280x800x24", "blender", "--factory-startup",
               "--enable-event-simulate", "--python", str(SCRIPTS / "pose_with_mouse.py"), "--", str(artefacts)]
    env = dict(os.environ, ADDON_PATH=str(ROOT / "python_addon"))
    run = subprocess.run(command, capture_output=True, text=True, timeout=600, env=env, cwd=artefacts)
    result_file = artefacts / "result.json"
    assert result_file.exists(), f"Blender ended without a result:\n{run.stdout[-4000:]}\n{run.stderr[-4000:]}"
    result = json.loads(result_file.read_text())
    assert result["ok"], "\n".join(result["log"])
    assert (artefacts / "pose.png").stat().st_size > 0
