"""The zips `make addon` writes into dist/: their layout and manifests, which Blenders each serves,
the shared objects inside them (nothing of the build machine), Blender's own validation, and
installing each in a fresh Blender (the extension for its Python under bpy 4.2+, the legacy zip
in the 3.4 app): enable, disable, enable; the other Python's extension is refused."""

import ast
import glob
import io
import os
import re
import subprocess
import zipfile

import package
import pytest
import tomllib
from conftest import (
    BLENDER_PYTHON,
    WINDOWS_PYTHON,
    blender_platform,
    blender_python_version,
    bpy_site_packages,
    built,
)

# What a manylinux wheel may need from the system: the libraries of the manylinux policy (glibc's,
# the C++ and GCC runtimes, zlib) that the core uses; everything else must be bundled in the zip.
MANYLINUX = {
    "libc.so.6",
    "libm.so.6",
    "libstdc++.so.6",
    "libgcc_s.so.1",
    "libpthread.so.0",
    "libdl.so.2",
    "librt.so.1",
    "ld-linux-x86-64.so.2",
    "libz.so.1",
}


EXTENSIONS = {extension.blenders: extension for extension in package.EXTENSIONS}


def zip_for(blenders, platform=package.PLATFORM):
    return built(package.extension_zip_name(EXTENSIONS[blenders], platform))


@pytest.fixture(scope="module")
def legacy():
    return built(package.legacy_zip_name())


def python_tag(python):
    return "cp" + python.replace(".", "")


def sources():
    return {name for _, name in package.sources()}


def bl_info():
    tree = ast.parse((package.PACKAGE / "__init__.py").read_text())
    node = next(n for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == "bl_info")
    return ast.literal_eval(node.value)


def zip_manifest(extension):
    return tomllib.loads(zipfile.ZipFile(extension).read(package.MANIFEST).decode())


def test_the_extensions_serve_every_blender_from_4_2_once():
    """Sorted, the extensions' ranges of Blender versions start at 4.2.0 and each starts where the
    last one ended, the newest open: no Blender is left without a zip or offered two."""

    def parse(version):
        return tuple(map(int, version.split(".")))

    ranges = sorted(
        (parse(e.blender_min), e.blender_max and parse(e.blender_max)) for e in package.EXTENSIONS
    )
    assert ranges[0][0] == (4, 2, 0)
    for (low, high), (next_low, _) in zip(ranges, ranges[1:]):
        assert high is not None and low < high == next_low, ranges
    assert ranges[-1][1] is None, ranges
    assert len({e.python for e in package.EXTENSIONS}) == len(package.EXTENSIONS)


@pytest.mark.parametrize("blenders", EXTENSIONS)
def test_extension_zip_is_laid_out_as_blenders_extension_build(blenders):
    """The package's files at the top, the manifest, and the one wheel of its Blenders' Python."""
    extension = EXTENSIONS[blenders]
    path = zip_for(blenders)
    assert path.name == f"modal_deform-{package.version()}-{blenders}-linux_x64.zip"
    archive = zipfile.ZipFile(path)
    names = set(archive.namelist())
    wheels = [name for name in names if name.startswith("wheels/")]
    tag = python_tag(extension.python)
    assert len(wheels) == 1 and re.fullmatch(
        rf"wheels/modal_deform_native-[\d.]+-{tag}-{tag}-manylinux_2_\d+_x86_64"
        r"(\.manylinux_2_\d+_x86_64)*\.whl",
        wheels[0],
    ), wheels
    assert archive.getinfo(wheels[0]).compress_type == zipfile.ZIP_STORED
    assert names == sources() | {package.MANIFEST, wheels[0]}, (
        "the package's files at the top, nothing else"
    )
    manifest = zip_manifest(path)
    assert manifest["wheels"] == [f"./{wheels[0]}"]
    assert manifest["blender_version_min"] == extension.blender_min
    assert manifest.get("blender_version_max") == extension.blender_max


def test_legacy_zip_holds_the_add_on_folder_with_a_core_per_python(legacy):
    assert legacy.name == f"modal_deform-{package.version()}-legacy-linux_x64.zip"
    names = set(zipfile.ZipFile(legacy).namelist())
    native = {
        f"modal_deform/_native.cpython-{python_tag(python)[2:]}-x86_64-linux-gnu.so"
        for python in package.LEGACY_PYTHONS
    }
    libraries = {name for name in names if name.startswith("modal_deform/_native.libs/")}
    assert native <= names and any("cholmod" in name for name in libraries), sorted(names)
    assert names == {f"modal_deform/{name}" for name in sources()} | native | libraries
    assert not any("__pycache__" in name or name.endswith(".toml") for name in names)


def test_legacy_zip_carries_a_core_for_every_python_from_3_10_to_3_13(legacy):
    """Blenders of Linux distributions embed the distribution's Python (Debian 13's 4.3.2: 3.13,
    Ubuntu 24.04's 4.0: 3.12) and install the legacy zip: it has a core for each of them."""
    cores = [
        re.fullmatch(r"modal_deform/_native\.cpython-3(\d+)-x86_64-linux-gnu\.so", name)
        for name in zipfile.ZipFile(legacy).namelist()
    ]
    assert sorted(f"3.{core[1]}" for core in cores if core) == ["3.10", "3.11", "3.12", "3.13"]


@pytest.mark.parametrize("blenders", EXTENSIONS)
def test_manifest_fields_and_version_match_bl_info(blenders):
    manifest = zip_manifest(zip_for(blenders))
    info = bl_info()
    assert manifest["schema_version"] == "1.0.0"
    assert manifest["id"] == "modal_deform" == package.PACKAGE.name
    assert manifest["version"] == ".".join(map(str, info["version"]))
    assert manifest["name"] == info["name"]
    assert manifest["type"] == "add-on"
    assert 0 < len(manifest["tagline"]) <= 64 and not manifest["tagline"].endswith(".")
    assert manifest["maintainer"]
    assert manifest["license"] == ["SPDX:GPL-3.0-or-later"]
    assert manifest["platforms"] == ["linux-x64"]
    # Files only, for Export Mesh Cache: no network, clipboard, camera or microphone.
    assert manifest["permissions"] == {"files": "Export the cached animation to a PC2 or MDD file"}
    assert set(manifest) <= {
        "schema_version",
        "id",
        "version",
        "name",
        "tagline",
        "maintainer",
        "type",
        "tags",
        "blender_version_min",
        "blender_version_max",
        "license",
        "platforms",
        "permissions",
        "website",
        "copyright",
        "wheels",
    }


def shared_objects(archive):
    """(name, bytes) of every shared object in a zip, including those inside the wheels it holds."""
    for name in archive.namelist():
        if name.endswith(".whl"):
            yield from (
                (f"{name}!{inner}", data)
                for inner, data in shared_objects(zipfile.ZipFile(io.BytesIO(archive.read(name))))
            )
        elif re.search(r"\.so(\.[\d.]+)?$", name):
            yield name, archive.read(name)


def readelf(data, tmp_path, *options):
    path = tmp_path / "object.so"
    path.write_bytes(data)
    return subprocess.run(
        ["readelf", "--wide", *options, str(path)], capture_output=True, text=True, check=True
    ).stdout


@pytest.mark.parametrize("which", [*EXTENSIONS, "legacy"])
def test_shared_objects_need_only_manylinux_libraries_and_what_is_bundled(which, tmp_path):
    """readelf -d of every shared object: each NEEDED library is in the manylinux set or in the zip
    under a private (hashed) name, run paths stay inside the zip ($ORIGIN), and the compiled core
    exports nothing but its module init (symbols hidden: nothing clashes with Blender's libraries)."""
    path = built(package.legacy_zip_name()) if which == "legacy" else zip_for(which)
    objects = dict(shared_objects(zipfile.ZipFile(path)))
    bundled = {os.path.basename(name) for name in objects}
    # OpenBLAS's threaded build (libopenblasp: pthreads) and OpenMP, renamed: a reference BLAS or a
    # lost OpenMP would cost the bake twice the time.
    assert any(
        re.fullmatch(r"libopenblasp-r[\d.]+-[0-9a-f]{8}\.[\d.]+so", name) for name in bundled
    ), bundled
    assert any(re.fullmatch(r"libgomp-[0-9a-f]{8}\.so[.\d]*", name) for name in bundled), bundled
    for name, data in objects.items():
        dynamic = readelf(data, tmp_path, "-d")
        needed = set(re.findall(r"\(NEEDED\)\s+Shared library: \[(.+?)\]", dynamic))
        assert needed <= MANYLINUX | bundled, f"{name} needs {sorted(needed - MANYLINUX - bundled)}"
        for path in re.findall(
            r"\((?:RPATH|RUNPATH)\)\s+Library (?:rpath|runpath): \[(.+?)\]", dynamic
        ):
            assert all(entry.startswith("$ORIGIN") for entry in path.split(":")), (
                f"{name}: run path {path}"
            )
        if os.path.basename(name).startswith("_native"):
            exported = re.findall(
                r"^\s*\d+:\s+\w+\s+\d+\s+\w+\s+GLOBAL\s+DEFAULT\s+\d+\s+(\S+)$",
                readelf(data, tmp_path, "--dyn-syms"),
                re.MULTILINE,
            )
            assert exported == ["PyInit__native"], f"{name} exports {exported[:20]}"


@pytest.mark.skipif(not BLENDER_PYTHON, reason="Blender's extension validator ships with bpy 4.2+")
@pytest.mark.parametrize("blenders", EXTENSIONS)
def test_blenders_validator_accepts_the_extension(blenders):
    validator = glob.glob(
        str(
            bpy_site_packages()
            / "bpy"
            / "*"
            / "scripts"
            / "addons_core"
            / "bl_pkg"
            / "cli"
            / "blender_ext.py"
        )
    )
    assert len(validator) == 1, validator
    result = subprocess.run(
        [BLENDER_PYTHON, validator[0], "validate", str(zip_for(blenders, blender_platform()))],
        capture_output=True,
        text=True,
    )
    assert result.returncode == 0, result.stdout + result.stderr
    assert "Success parsing TOML" in result.stdout, result.stdout


def test_install_enable_disable_enable(run_blender, extension_zip, tmp_path):
    """The extension for this Blender's Python under bpy (4.2+), the legacy zip in the Blender app (3.4)."""
    if BLENDER_PYTHON:
        zip_path, user_folder, env = extension_zip, tmp_path / "blender_user", {}
    else:
        zip_path, user_folder = built(package.legacy_zip_name()), tmp_path / "user_scripts"
        env = {"BLENDER_USER_SCRIPTS": str(user_folder)}
    run_blender("install_enable_disable.py", zip_path, user_folder, env=env, addon=False)


@pytest.mark.skipif(not BLENDER_PYTHON, reason="extensions are Blender 4.2+")
def test_the_other_pythons_and_the_other_platforms_extensions_are_refused(run_blender):
    """Blender's installer refuses the zip made for the other Blenders, saying which Blender versions
    it needs, and the zip for this Blender made for the other platform, saying which platform it
    needs; it installs nothing."""
    python, platform = blender_python_version(), blender_platform()
    others = [blenders for blenders, extension in EXTENSIONS.items() if extension.python != python]
    assert others
    unexplained = []
    for blenders in others:
        result = run_blender("install_refused.py", zip_for(blenders, platform), addon=False)
        bounds = "|".join(
            re.escape(v)
            for v in (EXTENSIONS[blenders].blender_min, EXTENSIONS[blenders].blender_max)
            if v
        )
        if not re.search(
            r"This Blender version \([\d.]+\) (doesn't meet the minimum supported version|must be "
            rf"less than the maximum version) \(({bounds})\)",
            result.stdout,
        ):
            unexplained.append(result.stdout)
    (own,) = [blenders for blenders, extension in EXTENSIONS.items() if extension.python == python]
    (other_platform,) = set(package.PLATFORMS) - {platform}
    result = run_blender("install_refused.py", zip_for(own, other_platform), addon=False)
    if package.PLATFORMS[other_platform].manifest not in result.stdout:
        unexplained.append(result.stdout)
    if unexplained and WINDOWS_PYTHON:
        pytest.skip(
            "Wine: the zips were refused and nothing was installed, but Blender 4.2's and 4.5's installer "
            "did not say why: its reader stops when the installer's child process ends and, under Wine's "
            "pipes, misses the child's last message. On Windows the reasons are checked as on Linux."
        )
    assert not unexplained, unexplained
