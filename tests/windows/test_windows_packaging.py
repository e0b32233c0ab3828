"""The Windows x64 zips and wheels `make addon` writes into dist/ (windows/windows.mk): layout and
manifest of each extension zip, the wheel's tags, and the import table of every DLL and extension
(x86_64-w64-mingw32-objdump -p): only DLLs every Windows has, the pythonXY.dll of the wheel's
Python, and DLLs bundled beside them. Run by Debian's Python on Linux (`make test-windows`)."""

import io
import pathlib
import re
import subprocess
import zipfile

import package
import pytest
import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[2]
DIST = ROOT / "dist"

OBJDUMP = "x86_64-w64-mingw32-objdump"
# DLLs of Windows itself: the kernel, msvcrt.dll (the C runtime MinGW-w64 links, part of Windows
# since Windows 95) and the UCRT's API sets (Windows 10 on; the OpenBLAS DLL is built against them).
SYSTEM_DLLS = {"kernel32.dll", "msvcrt.dll", "advapi32.dll", "user32.dll", "ntdll.dll"}
SYSTEM_API_SETS = r"api-ms-win-crt-[a-z]+-l1-1-0\.dll"

EXTENSIONS = {extension.blenders: extension for extension in package.EXTENSIONS}


def built(name):
    path = DIST / name
    if not path.is_file():
        pytest.fail(f"{path}: missing: run `make addon`")
    return path


def tag(python):
    return "cp" + python.replace(".", "")


def windows_zip(blenders):
    return built(package.extension_zip_name(EXTENSIONS[blenders], package.WINDOWS))


def imported_dlls(data, tmp_path):
    path = tmp_path / "object.dll"
    path.write_bytes(data)
    dump = subprocess.run(
        [OBJDUMP, "-p", str(path)], capture_output=True, text=True, check=True
    ).stdout
    return {name.lower() for name in re.findall(r"DLL Name: (\S+)", dump)}, dump


@pytest.mark.parametrize("blenders", EXTENSIONS)
def test_windows_zip_holds_the_package_and_its_pythons_win_amd64_wheel(blenders):
    extension = EXTENSIONS[blenders]
    archive = zipfile.ZipFile(windows_zip(blenders))
    names = set(archive.namelist())
    wheels = [name for name in names if name.startswith("wheels/")]
    assert wheels == [
        f"wheels/modal_deform_native-{package.version()}-{tag(extension.python)}-"
        f"{tag(extension.python)}-win_amd64.whl"
    ], wheels
    assert names == {name for _, name in package.sources()} | {package.MANIFEST, wheels[0]}
    manifest = tomllib.loads(archive.read(package.MANIFEST).decode())
    assert manifest["platforms"] == ["windows-x64"]
    assert manifest["wheels"] == [f"./{wheels[0]}"]
    assert manifest["blender_version_min"] == extension.blender_min
    assert manifest.get("blender_version_max") == extension.blender_max


@pytest.mark.parametrize("blenders", EXTENSIONS)
def test_windows_wheel_is_a_wheel_for_its_python(blenders):
    extension = EXTENSIONS[blenders]
    archive = zipfile.ZipFile(windows_zip(blenders))
    (wheel_name,) = [name for name in archive.namelist() if name.endswith(".whl")]
    wheel = zipfile.ZipFile(io.BytesIO(archive.read(wheel_name)))
    info = f"modal_deform_native-{package.version()}.dist-info"
    names = set(wheel.namelist())
    assert f"modal_deform_native/_native.{tag(extension.python)}-win_amd64.pyd" in names
    assert (
        wheel.read(f"{info}/WHEEL")
        .decode()
        .count(f"Tag: {tag(extension.python)}-{tag(extension.python)}-win_amd64")
        == 1
    )
    record = wheel.read(f"{info}/RECORD").decode()
    assert {line.split(",")[0] for line in record.splitlines()} == names
    assert "Requires-Dist: numpy" in wheel.read(f"{info}/METADATA").decode()


@pytest.mark.parametrize("blenders", EXTENSIONS)
def test_dlls_import_only_windows_python_and_what_is_bundled(blenders, tmp_path):
    """Each .pyd and .dll of the wheel imports only system DLLs, python3XY.dll and the wheel's
    own DLLs; the extension exports PyInit__native alone; no DLL of the C or C++ runtime of
    MinGW-w64 (libstdc++, libgcc_s, libwinpthread, libgomp) is needed: they are linked in."""
    extension = EXTENSIONS[blenders]
    archive = zipfile.ZipFile(windows_zip(blenders))
    (wheel_name,) = [name for name in archive.namelist() if name.endswith(".whl")]
    wheel = zipfile.ZipFile(io.BytesIO(archive.read(wheel_name)))
    binaries = [name for name in wheel.namelist() if name.endswith((".pyd", ".dll"))]
    bundled = {
        pathlib.PurePosixPath(name).name.lower() for name in binaries if name.endswith(".dll")
    }
    python_dll = f"python{tag(extension.python)[2:]}.dll"
    assert len(binaries) == 2, binaries
    for name in binaries:
        imports, dump = imported_dlls(wheel.read(name), tmp_path)
        unexpected = {
            dll
            for dll in imports - SYSTEM_DLLS - bundled - {python_dll}
            if not re.fullmatch(SYSTEM_API_SETS, dll)
        }
        assert not unexpected, f"{name} imports {sorted(unexpected)}"
        if name.endswith(".pyd"):
            assert python_dll in imports and bundled <= imports, sorted(imports)
            exports = re.search(r"\[Ordinal/Name Pointer\] Table\n(.*?)\n\n", dump, re.S)[1]
            assert re.findall(r"\] (\S+)", exports) == ["PyInit__native"]
