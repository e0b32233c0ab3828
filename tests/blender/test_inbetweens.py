"""In-betweens in headless Blender (issue 51): keys read from the keyframes, the motion through
them played through the cache, a key moved solved again, bad keys refused with a message, the file
saved and reloaded, and a frame rendered alone in a fresh process is the timeline's."""


def test_inbetweens_play_through_the_keys_reload_and_render_a_frame_alone(run_blender, tmp_path):
    out = run_blender("inbetweens.py").stdout
    print(out)
    blend = tmp_path / "inbetweens.blend"
    run_blender("inbetweens_reload.py", blend=blend)
    assert (
        "frames [17] are the timeline's"
        in run_blender("inbetweens_reload.py", 17, blend=blend).stdout
    )


def test_inbetweens_take_partial_keys_and_bones_and_export(run_blender):
    print(run_blender("inbetweens_partial.py").stdout)
