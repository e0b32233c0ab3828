def test_core_imports_and_runs_inside_blender(run_blender):
    result = run_blender("import_core.py")
    assert "MODAL_DEFORM_OK 507 3" in result.stdout
