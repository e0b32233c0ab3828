"""The zip: its manifest, and installing it in a fresh Blender (enable, disable, enable)."""
import ast
import pathlib
import sys
import tomllib
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "python_addon"))
import package  # noqa: E402


@pytest.fixture(scope="module")
def addon_zip(tmp_path_factory):
    return package.build(tmp_path_factory.mktemp("dist"))


def bl_info():
    tree = ast.parse((package.PACKAGE / "__init__.py").read_text())
    node = next(n for n in tree.body if isinstance(n, ast.Assign) and n.targets[0].id == "bl_info")
    return ast.literal_eval(node.value)


def test_zip_holds_the_package_with_its_extension_and_manifest(addon_zip):
    assert addon_zip.name == f"modal_deform-{package.version()}.zip"
    names = zipfile.ZipFile(addon_zip).namelist()
    assert all(name.startswith("modal_deform/") for name in names)
    for required in ("modal_deform/__init__.py", "modal_deform/core/__init__.py", "modal_deform/blender_manifest.toml"):
        assert required in names
    assert any(name.startswith("modal_deform/_native") and name.endswith(".so") for name in names)
    assert not any("__pycache__" in name for name in names)


def test_manifest_fields_and_version_match_bl_info():
    manifest = tomllib.loads((package.PACKAGE / "blender_manifest.toml").read_text())
    info = bl_info()
    assert manifest["schema_version"] == "1.0.0"
    assert manifest["id"] == "modal_deform" == package.PACKAGE.name
    assert manifest["version"] == ".".join(map(str, info["version"]))
    assert manifest["name"] == info["name"]
    assert manifest["type"] == "add-on"
    assert 0 < len(manifest["tagline"]) <= 64 and not manifest["tagline"].endswith(".")
    assert manifest["maintainer"]
    assert tuple(map(int, manifest["blender_version_min"].split("."))) >= (4, 2, 0)
    assert manifest["license"] == ["SPDX:GPL-3.0-or-later"]
    assert manifest["platforms"] == ["linux-x64"]
    assert set(manifest) <= {"schema_version", "id", "version", "name", "tagline", "maintainer", "type", "tags",
                             "blender_version_min", "blender_version_max", "license", "platforms", "permissions",
                             "website", "copyright", "wheels", "build"}


def test_install_enable_disable_enable(run_blender, addon_zip, tmp_path):
    user_scripts = tmp_path / "user_scripts"
    result = run_blender("install_enable_disable.py", addon_zip, user_scripts,
                         env={"BLENDER_USER_SCRIPTS": str(user_scripts)})
    assert "INSTALL_OK" in result.stdout
