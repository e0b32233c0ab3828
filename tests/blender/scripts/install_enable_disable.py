"""Install a zip as an artist does, then enable, disable, enable again: nothing may be left behind
by disabling (classes, properties, handlers, timers), and the installed copy (not the source tree)
bakes, with the compiled core of this Blender's Python. Blender 4.2+: the extension zip with
Blender's extension installer (module bl_ext.user_default.modal_deform); earlier: the legacy zip
like Preferences > Add-ons > Install.

Arguments: ZIP USER_FOLDER (where Blender installs into)."""

import os
import sys

import bpy
from support import blender as support

zip_path, user_folder = support.arguments()
handlers = {
    name: len(getattr(bpy.app.handlers, name)) for name in ("depsgraph_update_post", "load_post")
}
assert not any(name.endswith("modal_deform") for name in sys.modules)
if bpy.app.version >= (4, 2, 0):
    module_name = "bl_ext.user_default.modal_deform"
    installed = bpy.ops.extensions.package_install_files(
        filepath=zip_path, repo="user_default", enable_on_install=False
    )
else:
    module_name = "modal_deform"
    installed = bpy.ops.preferences.addon_install(filepath=zip_path)
assert installed == {"FINISHED"}, installed


def enable_and_bake():
    # The operator behind Preferences' checkbox, as an artist enables it: in Blender 4.2.0 it, and not
    # addon_utils.enable, installs the extension's wheels first.
    assert bpy.ops.preferences.addon_enable(module=module_name) == {"FINISHED"}, "enabling failed"
    module = sys.modules[module_name]
    assert os.path.realpath(module.__file__).startswith(os.path.realpath(user_folder)), (
        module.__file__
    )
    # The compiled core of this Blender's own Python, from where Blender installed it.
    native = sys.modules[f"{module_name}._native"].__file__
    assert os.path.realpath(native).startswith(os.path.realpath(user_folder)), native
    python = f"{sys.version_info[0]}{sys.version_info[1]}"
    assert os.path.basename(native).startswith(
        (f"_native.cpython-{python}-", f"_native.cp{python}-win_amd64")
    ), native
    assert hasattr(bpy.types.Object, "modal_deform") and hasattr(
        bpy.types, "VIEW3D_PT_modal_deform"
    )
    obj = support.suzanne(0)
    obj.modal_deform.modes, obj.modal_deform.derivatives, obj.modal_deform.ghost = 10, 5, 100
    assert bpy.ops.modal_deform.bake() == {"FINISHED"}
    assert obj.modal_deform.status.dimension >= 15


def disable():
    assert bpy.ops.preferences.addon_disable(module=module_name) == {"FINISHED"}
    assert not hasattr(bpy.types.Object, "modal_deform")
    for name in ("VIEW3D_PT_modal_deform", "MODAL_DEFORM_UL_handles", "ModalDeformSettings"):
        assert not hasattr(bpy.types, name), f"{name} is still registered"
    assert "bake" not in dir(bpy.ops.modal_deform)
    now = {name: len(getattr(bpy.app.handlers, name)) for name in handlers}
    assert now == handlers, f"handlers left behind: {now} vs {handlers}"


enable_and_bake()
disable()
enable_and_bake()
disable()
