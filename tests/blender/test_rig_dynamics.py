"""Dynamics following a rig in headless Blender (issue 50, items 2, 3 and 5)."""


def test_the_mesh_jiggles_on_its_rig_settles_to_the_armature_and_bad_rigs_are_refused(run_blender):
    out = run_blender("rig_dynamics.py").stdout
    print(out[out.find("settle error") :])
