"""Reading the shared meshes (support.SHARED_MESHES) with the core's reader."""

import modal_deform.core as mdc
from support import SCAN_FILES, SHARED_MESHES


def read_shared(file):
    """(V, F) of the shared mesh file, e.g. "dragon_vrip_res4.ply.gz"."""
    return mdc.read_mesh(SHARED_MESHES / file)


def read_scan(name):
    """(V, F) of the shared scan called `name` (a key of support.SCAN_FILES, e.g. "dragon_res4")."""
    return read_shared(SCAN_FILES[name])
