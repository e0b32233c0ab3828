"""What the headless scripts share: their arguments after "--", the object they work on, saving."""
import argparse
import pathlib
import sys

import addon_utils
import bpy

ROOT = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "python_addon"))


def argument_parser(doc):
    """A parser for the arguments after Blender's own (``blender -b ... --python script.py -- ...``),
    with the --object and --output every script takes."""
    parser = argparse.ArgumentParser(description=doc, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--object", required=True, help="name of the mesh object")
    parser.add_argument("--output", help="save here instead of over the opened file")
    return parser


def parse(parser):
    return parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])


def active_mesh_object(name):
    """Enable the add-on and make the mesh object `name` active; exit with the reason if there is none."""
    addon_utils.enable("modal_deform", default_set=True)
    obj = bpy.data.objects.get(name)
    if obj is None or obj.type != "MESH":
        sys.exit(f"--object: no mesh object named {name!r} in {bpy.data.filepath or 'the file'}")
    bpy.context.view_layer.objects.active = obj
    return obj


def run(operator, **options):
    """Call a Modal Deform operator; exit with code 1 and its message when it fails."""
    try:
        operator(**options)
    except RuntimeError as error:
        sys.exit(str(error))


def save(output):
    path = output or bpy.data.filepath
    if not path:
        sys.exit("--output: the opened file has no path to save to")
    bpy.ops.wm.save_as_mainfile(filepath=str(pathlib.Path(path).resolve()))
