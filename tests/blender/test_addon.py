"""The add-on in headless Blender: bake, store, reload, solve, stale data, cancel (the animation cache:
test_dynamics.py)."""

import pathlib

import pytest
from support import SHARED_MESHES

ROOT = pathlib.Path(__file__).resolve().parents[2]
BLENDER_SCRIPTS = ROOT / "blender_scripts"


@pytest.mark.parametrize("mesh", ["suzanne", "dragon"])
def test_bake_save_reload_solve(run_blender, tmp_path, mesh):
    run_blender("bake_and_save.py", mesh, SHARED_MESHES / "dragon_vrip_res4.ply.gz")
    run_blender("reload_and_solve.py", blend=tmp_path / "baked.blend")


def test_dense_mesh_bakes_on_a_proxy_through_the_same_button(run_blender):
    run_blender("proxy_bake.py")


def test_suzanne_follows_strong_poses(run_blender):
    run_blender("strong_pose.py")


def test_painted_stiffness_is_stored_reloaded_and_posed(run_blender, tmp_path):
    run_blender("painted_stiffness.py")
    run_blender("painted_reload.py", blend=tmp_path / "painted.blend")


def test_region_bake_leaves_the_rest_exactly_still(run_blender, tmp_path):
    run_blender("region_bake.py")
    run_blender("region_reload.py", blend=tmp_path / "region.blend")


def test_pose_shown_in_positions_or_key_and_repaired_after_undo_or_load(run_blender):
    run_blender("pose_displays.py")


def test_stale_mesh_and_bad_handles_are_refused(run_blender):
    run_blender("stale_and_bad_handles.py")


def test_quads_ngons_and_mode_preview(run_blender):
    run_blender("quads_ngons_preview.py")


def test_damaged_stored_basis_is_refused_with_a_message(run_blender):
    run_blender("damaged_basis.py")


def test_cancelled_or_failed_bake_leaves_the_object_unchanged(run_blender):
    run_blender("cancel_bake.py")


def test_basis_follows_append_and_link(run_blender):
    run_blender("append_link.py")


def test_headless_bake_and_pose_scripts(run_blender, tmp_path):
    run_blender("bake_and_save.py", "suzanne")
    baked = run_blender(
        BLENDER_SCRIPTS / "bake.py",
        "--object",
        "Suzanne",
        "--modes",
        "12",
        "--derivatives",
        "10",
        "--ghost",
        "300",
        "--output",
        tmp_path / "rebaked.blend",
        blend=tmp_path / "baked.blend",
    )
    assert "baked Suzanne: 22 dimensions, ghost 300 vertices" in baked.stdout, baked.stdout[-2000:]
    run_blender(
        BLENDER_SCRIPTS / "pose.py",
        "--object",
        "Suzanne",
        "--output",
        tmp_path / "posed.blend",
        blend=tmp_path / "rebaked.blend",
    )
    run_blender("check_headless_pose.py", 22, blend=tmp_path / "posed.blend")


def test_headless_script_names_a_missing_object(run_blender):
    result = run_blender(BLENDER_SCRIPTS / "bake.py", "--object", "Nope", check=False)
    assert result.returncode == 1
    assert "--object: no mesh object named 'Nope'" in result.stdout + result.stderr


def test_refine_polishes_the_pose_and_a_cancel_changes_nothing(run_blender):
    run_blender("refine.py")


def test_a_stalled_solve_is_shown_to_the_artist(run_blender):
    out = run_blender("stalled_pose.py").stdout
    before, after = out.split("SOLVE_WITH_STALL")
    assert "Stalled after" not in before, before[-2000:]
    assert "Warning: Stalled after" in after and "the solver cannot follow this pose" in after, (
        after[-2000:]
    )
