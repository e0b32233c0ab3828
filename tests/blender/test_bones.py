"""Bones as handle controllers in headless Blender (issue 50)."""


def test_a_bone_drives_the_handle_as_an_empty_does_and_bad_rigs_are_refused(run_blender):
    out = run_blender("bone_controllers.py").stdout
    print(out[out.find("bone against Empty") :])
