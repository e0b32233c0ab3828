"""Zip the add-on for Blender: the modal_deform folder with its compiled extension and manifest.

    python3 python_addon/package.py dist        # -> dist/modal_deform-<version>.zip

Installs with Preferences > Add-ons > Install (or bpy.ops.preferences.addon_install) on Blender
3.4+, and as an extension from disk on 4.2+ (blender_manifest.toml inside the folder).
"""
import argparse
import ast
import pathlib
import sys
import zipfile

PACKAGE = pathlib.Path(__file__).resolve().parent / "modal_deform"


def version():
    """bl_info["version"] of the add-on as "major.minor.patch", read without importing it."""
    tree = ast.parse((PACKAGE / "__init__.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "bl_info" for t in node.targets):
            return ".".join(map(str, ast.literal_eval(node.value)["version"]))
    raise RuntimeError(f"{PACKAGE / '__init__.py'}: no bl_info")


def files():
    """The files of the package: sources, the manifest and the compiled extension."""
    native = sorted(PACKAGE.glob("_native*.so"))
    if not native:
        raise RuntimeError(f"{PACKAGE}: no compiled extension (_native*.so): run `make build` first")
    sources = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)
    return sources + [PACKAGE / "blender_manifest.toml"] + native


def build(destination):
    """Write destination/modal_deform-<version>.zip and return its path."""
    destination = pathlib.Path(destination)
    destination.mkdir(parents=True, exist_ok=True)
    path = destination / f"modal_deform-{version()}.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for file in files():
            archive.write(file, file.relative_to(PACKAGE.parent).as_posix())
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("destination", nargs="?", default="dist", help="folder for the zip (default: dist)")
    try:
        print(build(parser.parse_args().destination))
    except RuntimeError as error:
        sys.exit(str(error))


if __name__ == "__main__":
    main()
