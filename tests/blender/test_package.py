"""The installable packages: built, valid, and installable in a clean Blender."""
import os
import subprocess
import sys
import tomllib
import zipfile

import bpy
import pytest

from conftest import ROOT, sunlapse

sys.path.insert(0, os.path.join(ROOT, "tools"))
import package  # noqa: E402

REQUIRED = ["schema_version", "id", "version", "name", "tagline", "maintainer", "type",
            "blender_version_min", "license"]


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    from sunlapse import native_loader
    module = native_loader.require().__file__
    return package.build(module, str(tmp_path_factory.mktemp("dist")))


def test_extension_manifest_has_the_required_fields(packages):
    legacy, extension = packages
    with zipfile.ZipFile(extension) as z:
        names = z.namelist()
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
    assert all(k in manifest for k in REQUIRED)
    assert manifest["schema_version"] == "1.0.0" and manifest["type"] == "add-on"
    assert manifest["platforms"] == ["linux-x64"]
    assert "__init__.py" in names and "core/trackfile.py" in names
    assert any(n.startswith("_native") and n.endswith(".so") for n in names)
    assert not any("__pycache__" in n or "shared/real" in n for n in names)


def test_addon_zip_installs_and_enables_in_a_clean_blender(packages, tmp_path):
    legacy, _ = packages
    script = (
        "import bpy, addon_utils, sys\n"
        f"bpy.ops.preferences.addon_install(filepath={legacy!r})\n"
        "addon_utils.enable('sunlapse', default_set=True)\n"
        "import sunlapse\n"
        "ok = sunlapse.native_loader._native is not None and hasattr(bpy.types.Scene, 'sunlapse')\n"
        "print('INSTALLED', ok, sunlapse.__file__)\n"
        "sys.exit(0 if ok else 1)\n")
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "scripts"))
    proc = subprocess.run([bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
                           "--python-expr", script], capture_output=True, text=True, env=env,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    line = next(l for l in proc.stdout.splitlines() if l.startswith("INSTALLED"))
    assert str(tmp_path / "scripts") in line  # the installed copy, not the source tree
