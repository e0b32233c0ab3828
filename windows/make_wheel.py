"""Pack the cross-built Windows extension into a wheel (`make wheels-windows`, windows/windows.mk).

    python windows/make_wheel.py DIST PYTHON EXTENSION DLL LICENSE...

writes DIST/modal_deform_native-<version>-cpXY-cpXY-win_amd64.whl for Python X.Y ("3.11"): the
extension (_native.cpXY-win_amd64.pyd) and the DLL it imports beside it (the OpenBLAS of
scipy-openblas32 under the private name the extension was linked to; CPython 3.8+ loads an
extension's DLLs from the extension's own folder), the project's licence and the bundled ones.
The same package layout and metadata as the Linux wheels that scikit-build-core writes from
pyproject.toml. Entries carry a fixed date, so the same inputs give the same wheel.
"""

import base64
import hashlib
import pathlib
import re
import sys
import zipfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
MANIFEST = ROOT / "python_addon" / "modal_deform" / "blender_manifest.toml"
PYPROJECT = ROOT / "pyproject.toml"
NATIVE_PACKAGE = "modal_deform_native"
PLATFORM_TAG = "win_amd64"
FIXED_DATE = (2020, 1, 1, 0, 0, 0)


def project_field(name):
    """A string field of pyproject.toml's [project] table, e.g. description."""
    match = re.search(rf'(?m)^{name} = "([^"]*)"$', PYPROJECT.read_text())
    if match is None:
        raise RuntimeError(f'{PYPROJECT}: no {name} = "..."')
    return match[1]


def version():
    """The version pyproject.toml takes from the manifest (its metadata.version regex)."""
    match = re.search(r'(?m)^version = "([^"]+)"', MANIFEST.read_text())
    if match is None:
        raise RuntimeError(f"{MANIFEST}: no version line")
    return match[1]


def record_line(name, data):
    digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
    return f"{name},sha256={digest},{len(data)}"


def build(dist, python, extension, dll, licenses):
    tag = "cp" + python.replace(".", "")
    extension, dll = pathlib.Path(extension), pathlib.Path(dll)
    expected = f"_native.{tag}-{PLATFORM_TAG}.pyd"
    if extension.name != expected:
        raise RuntimeError(
            f"{extension}: expected an extension named {expected} for Python {python}"
        )
    info = f"{NATIVE_PACKAGE}-{version()}.dist-info"
    metadata = "\n".join(
        [
            "Metadata-Version: 2.4",
            f"Name: {NATIVE_PACKAGE}",
            f"Version: {version()}",
            f"Summary: {project_field('description')}",
            f"License-Expression: {project_field('license')}",
            *(f"License-File: {pathlib.Path(path).name}" for path in licenses),
            f"Requires-Python: {project_field('requires-python')}",
            "Requires-Dist: numpy",
            "",
        ]
    )
    wheel = "\n".join(
        [
            "Wheel-Version: 1.0",
            "Generator: modal_deform windows/make_wheel.py",
            "Root-Is-Purelib: false",
            f"Tag: {tag}-{tag}-{PLATFORM_TAG}",
            "",
        ]
    )
    entries = [
        (f"{NATIVE_PACKAGE}/{extension.name}", extension.read_bytes()),
        (f"{NATIVE_PACKAGE}/{dll.name}", dll.read_bytes()),
    ]
    entries += [
        (f"{info}/licenses/{pathlib.Path(path).name}", pathlib.Path(path).read_bytes())
        for path in licenses
    ]
    entries += [(f"{info}/METADATA", metadata.encode()), (f"{info}/WHEEL", wheel.encode())]
    record = "\n".join(
        [record_line(name, data) for name, data in entries] + [f"{info}/RECORD,,", ""]
    )
    entries.append((f"{info}/RECORD", record.encode()))
    path = pathlib.Path(dist) / f"{NATIVE_PACKAGE}-{version()}-{tag}-{tag}-{PLATFORM_TAG}.whl"
    path.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED, compresslevel=9) as archive:
        for name, data in entries:
            entry = zipfile.ZipInfo(name, FIXED_DATE)
            entry.external_attr = 0o644 << 16
            archive.writestr(entry, data, compress_type=zipfile.ZIP_DEFLATED)
    return path


if __name__ == "__main__":
    if len(sys.argv) < 6:
        sys.exit(__doc__)
    try:
        print(build(*sys.argv[1:5], sys.argv[5:]))
    except (RuntimeError, OSError) as error:
        sys.exit(str(error))
