"""What the tests share, importable as ``support``: pytest finds it through pyproject.toml's
``pythonpath``, a Blender script through the ``--python-expr`` of ``in_blender`` (bpy_session.py
puts the same folders on sys.path). The benchmarks use it too (bench/shapes.py and
bench/common.py put it on sys.path).

- this module: where the shared meshes are, and Blender's arguments to run a test script;
- ``meshes``: reading them (imports modal_deform.core);
- ``poses``, ``subdivision``, ``strong_poses``: NumPy only, safe beside an installed extension;
- ``raw_scans``, ``dynamics``: damaged dragons and the free-body measurement (modal_deform.core);
- ``blender``: inside Blender, enabling the add-on, Suzanne, handles and the scripts' helpers.

Nothing here imports modal_deform at import time: inside Blender the add-on is the one enabled.
"""

import pathlib

TESTS = pathlib.Path(__file__).resolve().parents[1]
ROOT = TESTS.parent
#: The scanned meshes, in the folder `shared` beside the repository.
SHARED_MESHES = ROOT.parent / "shared" / "meshes"
#: The shared scans by the names the benchmarks and tests give them.
SCAN_FILES = {
    "bunny": "bunny.obj.gz",
    "dragon_res4": "dragon_vrip_res4.ply.gz",
    "dragon_res3": "dragon_vrip_res3.ply.gz",
    "dragon_res2": "dragon_vrip_res2.ply.gz",
}


def in_blender(script):
    """Blender's arguments that run `script` (``--python``) with this package and the script's own
    folder importable (Blender puts neither on sys.path)."""
    folders = [str(TESTS), str(pathlib.Path(script).resolve().parent)]
    return ["--python-expr", f"import sys; sys.path[:0] = {folders!r}", "--python", str(script)]
