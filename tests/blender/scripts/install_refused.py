"""Install an extension zip made for other Blenders (another Python): Blender's installer must
refuse it (it prints why; the operator itself may still return FINISHED), and nothing may be
installed or enabled.

Arguments: ZIP."""

import os

import bpy
from support import blender as support

(zip_path,) = support.arguments()
try:
    result = bpy.ops.extensions.package_install_files(
        filepath=zip_path, repo="user_default", enable_on_install=True
    )
except RuntimeError as error:  # the operator's error report
    result = error
assert "bl_ext.user_default.modal_deform" not in bpy.context.preferences.addons, (
    f"installed and enabled: {result}"
)
repository = bpy.utils.user_resource("EXTENSIONS", path="user_default")
assert not os.path.exists(os.path.join(repository, "modal_deform")), (
    f"files left in {repository}: {result}"
)
print("the installer returned:", result)
