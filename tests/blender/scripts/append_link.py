"""The stored basis follows an object appended or linked from a saved file (undo: tests/gui)."""

import bpy
from support import blender as support

storage = support.enable_addon("storage")

obj = support.suzanne(1)
obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 12, 10, 300
assert bpy.ops.modal_deform.bake() == {"FINISHED"}
baked = storage.load(obj).to_arrays()
path = support.tmp("library.blend")
bpy.ops.wm.save_as_mainfile(filepath=path, copy=True)

for link in (False, True):
    for other in list(bpy.data.objects):
        bpy.data.objects.remove(other)
    bpy.data.orphans_purge(do_recursive=True)
    assert len(support.stored_bases()) == 0, "a deleted object's basis must become an orphan"
    with bpy.data.libraries.load(path, link=link) as (source, target):
        target.objects = ["Suzanne"]
    obj = target.objects[0]
    bpy.context.scene.collection.objects.link(obj)
    assert obj.modal_deform.basis is not None, f"link={link}: the basis did not come along"
    assert (obj.modal_deform.basis.library is not None) == link
    assert storage.stale_reason(obj) == ""
    loaded = storage.load(obj).to_arrays()
    assert all(baked[k].tobytes() == loaded[k].tobytes() for k in baked), (
        f"link={link}: basis differs"
    )
