"""Dynamics following a rig in headless Blender (issue 50, items 2, 3 and 5)."""


def test_the_mesh_jiggles_on_its_rig_settles_to_the_armature_and_bad_rigs_are_refused(run_blender):
    out = run_blender("rig_dynamics.py").stdout
    print(out[out.find("settle error") :])


def test_a_handle_bound_in_a_posed_rig_holds_its_vertices_where_the_rig_puts_them(run_blender):
    out = run_blender("rig_bind.py").stdout
    print(out[out.find("bound in a posed rig") :])


def test_painted_stiffness_and_a_region_apply_on_the_rig(run_blender):
    out = run_blender("rig_material.py").stdout
    print(out[out.find("material on a rig") :])
