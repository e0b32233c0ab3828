"""In-betweens in headless Blender (issue 51): keys read from the keyframes, the motion through
them played through the cache, a key moved solved again, bad keys refused with a message, the file
saved and reloaded, and a frame rendered alone in a fresh process is the timeline's."""

import os
import subprocess

import numpy as np
import support
from conftest import BLENDER_PYTHON, SCRIPTS


def test_inbetweens_play_through_the_keys_reload_and_render_a_frame_alone(run_blender, tmp_path):
    print(run_blender("inbetweens.py").stdout)
    blend = tmp_path / "inbetweens.blend"
    run_blender("inbetweens_reload.py", blend=blend)
    alone = run_blender("inbetweens_reload.py", 17, blend=blend).stdout
    assert "frames [17] are the timeline's" in alone
    if BLENDER_PYTHON:  # bpy renders no frame from a command line
        return
    # `blender -b inbetweens.blend -f 17` in a fresh process: the frame rendered is the timeline's.
    command = ["blender", "-b", str(blend), "--factory-startup", "--python-exit-code", "1"]
    command += support.in_blender(SCRIPTS / "inbetweens_render.py") + ["-f", "17"]
    environment = dict(os.environ, TEST_TMP=str(tmp_path))
    result = subprocess.run(command, capture_output=True, text=True, timeout=600, env=environment)
    assert result.returncode == 0, result.stdout[-4000:] + result.stderr[-4000:]
    assert (tmp_path / "render.txt").read_text() == "17", result.stdout[-4000:]
    shown = np.load(tmp_path / "inbetweens.npy")
    assert shown[16].tobytes() != shown[0].tobytes(), "the file's frame (1) is frame 17's"
    assert np.load(tmp_path / "render.npy").tobytes() == shown[16].tobytes()


def test_inbetweens_take_partial_keys_and_bones_and_export(run_blender):
    print(run_blender("inbetweens_partial.py").stdout)
