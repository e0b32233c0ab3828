"""Cancelling a bake (Esc: the progress callback says stop) leaves the object exactly as it was,
with or without an earlier basis; so does a bake that fails."""

import time

import bpy
from support import blender as support

jobs = support.enable_addon("jobs")


def cancelled_bake(obj):
    before = support.mesh_state(obj)
    job = jobs.BakeJob(obj)
    job.start()
    while job.stage == "starting" and not job.done:  # cancel once the native bake reports
        time.sleep(0.001)
    job.cancel()
    while not job.done:
        time.sleep(0.01)
    level, message = job.finish()
    assert level == "WARNING" and "cancelled" in message, (level, message)
    assert support.mesh_state(obj) == before, "a cancelled bake changed the object"


obj = support.suzanne(2)
cancelled_bake(obj)
assert obj.modal_deform.basis is None and len(support.stored_bases()) == 0
obj.modal_deform.modes, obj.modal_deform.derivatives = 12, 10
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
obj.modal_deform.modes = 20
cancelled_bake(obj)  # the earlier basis stays
assert obj.modal_deform.status.num_modes == 12

# A bake that fails (more derivatives than pairs of modes) reports and changes nothing.
before = support.mesh_state(obj)
obj.modal_deform.derivatives = 10000
support.expect_error(bpy.ops.modal_deform.bake, "Bake failed")
assert support.mesh_state(obj) == before
