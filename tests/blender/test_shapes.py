"""Blend as Shapes in headless Blender (issue 52): enable, play, keep, restore; save and reload
without a bake, staleness, render; the exports; bad input."""


def test_blend_as_shapes_shows_plays_keeps_and_restores(run_blender):
    out = run_blender("shapes_blend.py").stdout
    assert "SAVED" in out


def test_reload_keeps_the_space_renders_the_blend_and_tells_a_stale_key(run_blender, tmp_path):
    run_blender("shapes_blend.py")
    run_blender("shapes_reload.py", blend=tmp_path / "shapes.blend")


def test_exports_play_the_blend_without_the_addon(run_blender, tmp_path):
    run_blender("shapes_export.py")
    run_blender("shapes_exported.py", blend=tmp_path / "exported.blend", addon=False)


def test_bad_input_is_refused_with_a_message_and_nothing_lost(run_blender):
    run_blender("shapes_bad_input.py")
