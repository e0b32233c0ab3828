def test_core_imports_and_runs_inside_blender(run_blender):
    run_blender("import_core.py")
