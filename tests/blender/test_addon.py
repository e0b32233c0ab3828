"""The add-on in headless Blender: bake, store, reload, solve, stale data, animation, cancel."""
import pathlib

import pytest

SHARED_MESHES = pathlib.Path(__file__).resolve().parents[2].parent / "shared" / "meshes"


@pytest.mark.parametrize("mesh", ["suzanne", "dragon"])
def test_bake_save_reload_solve(run_blender, tmp_path, mesh):
    run_blender("bake_and_save.py", mesh, SHARED_MESHES / "dragon_vrip_res4.ply.gz")
    result = run_blender("reload_and_solve.py", blend=tmp_path / "baked.blend")
    assert "SOLVED" in result.stdout


def test_stale_mesh_and_bad_handles_are_refused(run_blender):
    assert "STALE_OK" in run_blender("stale_and_bad_handles.py").stdout


def test_bake_animation_plays_back_without_the_addon(run_blender, tmp_path):
    run_blender("animation_bake.py")
    assert "PLAYBACK_OK" in run_blender("animation_playback.py", blend=tmp_path / "animated.blend").stdout


def test_quads_ngons_and_mode_preview(run_blender):
    assert "NGONS_OK" in run_blender("quads_ngons_preview.py").stdout


def test_cancelled_or_failed_bake_leaves_the_object_unchanged(run_blender):
    assert "CANCEL_OK" in run_blender("cancel_bake.py").stdout


def test_basis_follows_append_and_link(run_blender):
    assert "APPEND_LINK_OK" in run_blender("append_link.py").stdout
