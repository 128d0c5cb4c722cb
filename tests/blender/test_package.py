"""The installable packages: built, valid, and installable in a clean Blender."""
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile

import bpy
import pytest

from conftest import ROOT

sys.path.insert(0, os.path.join(ROOT, "tools"))
import package  # noqa: E402

REQUIRED = ["schema_version", "id", "version", "name", "tagline", "maintainer", "type",
            "blender_version_min", "license"]


@pytest.fixture(scope="module")
def packages(tmp_path_factory):
    from sunlapse.estimate import native_loader
    module = native_loader.require().__file__
    return package.build([module], str(tmp_path_factory.mktemp("dist")))


def test_extension_manifest_has_the_required_fields(packages):
    legacy, extension = packages
    with zipfile.ZipFile(extension) as z:
        names = z.namelist()
        manifest_text = z.read("blender_manifest.toml").decode()
        manifest = tomllib.loads(manifest_text)
    assert all(k in manifest for k in REQUIRED)
    # It names exactly the Pythons the wheel holds.
    assert "# The wheel holds the core for CPython 3.11.\n" in manifest_text
    assert manifest["schema_version"] == "1.0.0" and manifest["type"] == "add-on"
    assert manifest["platforms"] == ["linux-x64"]
    assert "__init__.py" in names and "core/trackfile.py" in names
    # The module travels as the wheel the manifest names, not loose.
    assert len(manifest["wheels"]) == 1 and manifest["wheels"][0].lstrip("./") in names
    assert manifest["wheels"][0].endswith("-cp311-cp311-manylinux_2_36_x86_64.whl")
    assert not any(n.endswith(".so") for n in names)
    assert not any("__pycache__" in n or "shared/real" in n for n in names)


def test_packaged_module_needs_only_system_basics_from_the_machine(packages, tmp_path):
    legacy, extension = packages
    with zipfile.ZipFile(extension) as z:
        manifest = tomllib.loads(z.read("blender_manifest.toml").decode())
        z.extract(manifest["wheels"][0].lstrip("./"), tmp_path)
    with zipfile.ZipFile(tmp_path / manifest["wheels"][0].lstrip("./")) as w:
        names = w.namelist()
        w.extractall(tmp_path / "wheel")
    assert "sunlapse_native/_native.cpython-311-x86_64-linux-gnu.so" in names
    assert any(n.endswith(".dist-info/RECORD") for n in names)
    libs = [n for n in names if n.startswith("sunlapse_native/libs/")]
    assert any("libembree3" in n for n in libs) and any("libopencv_core" in n for n in libs)
    assert any("libturbojpeg" in n for n in libs)  # JPEG stills (video stage)
    # ldd with no library path: everything else resolves inside the package.
    package.check_self_contained(str(tmp_path / "wheel" / "sunlapse_native"))
    for name, path in package.ldd(str(tmp_path / "wheel" / "sunlapse_native" /
                                      "_native.cpython-311-x86_64-linux-gnu.so")):
        assert name in package.SYSTEM_LIBS or "/sunlapse_native/libs/" in path, (name, path)
    # A library removed from the package is caught.
    os.remove(next(p for p in (tmp_path / "wheel" / "sunlapse_native" / "libs").iterdir()
                   if p.name.startswith("liberfa")))
    with pytest.raises(package.PackageError, match="liberfa"):
        package.check_self_contained(str(tmp_path / "wheel" / "sunlapse_native"))


def _loader_report(tmp_path, module_src, module_name):
    """DIAGNOSIS of a copy of native_loader beside `module_name` (not a source checkout)."""
    pkg = tmp_path / "pkg" / "fake_addon"
    pkg.mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "estimate").mkdir()
    (pkg / "estimate" / "__init__.py").write_text("")
    shutil.copy(os.path.join(ROOT, "addon", "estimate", "native_loader.py"), pkg / "estimate")
    if module_src:
        shutil.copy(module_src, pkg / module_name)
    code = ("import sys; sys.path.insert(0, sys.argv[1]); "
            "from fake_addon.estimate import native_loader as n;"
            "print(n._native is None); print('\\n'.join(n.DIAGNOSIS))")
    out = subprocess.run(["/usr/bin/python3", "-c", code, str(tmp_path / "pkg")],
                         capture_output=True, text=True, timeout=60, check=True).stdout
    return out.splitlines()


def test_loader_says_which_python_the_module_is_for(tmp_path):
    from sunlapse.estimate import native_loader
    lines = _loader_report(tmp_path, native_loader.require().__file__,
                           "_native.cpython-313-x86_64-linux-gnu.so")
    assert lines[0] == "True"
    text = "\n".join(lines)
    assert "CPython 3.13" in text and "Python 3.11" in text and "not built" not in text


def test_loader_names_the_missing_library(tmp_path):
    from sunlapse.estimate import native_loader
    broken = tmp_path / "broken.so"
    shutil.copy(native_loader.require().__file__, broken)
    subprocess.run(["patchelf", "--replace-needed", "liberfa.so.1", "liberfa_gone.so.1",
                    str(broken)], check=True)
    lines = _loader_report(tmp_path, str(broken), "_native.cpython-311-x86_64-linux-gnu.so")
    text = "\n".join(lines)
    assert "liberfa_gone.so.1 (needed by _native.cpython-311-x86_64-linux-gnu.so)" in text
    assert "not built" not in text and "tools/install.sh" not in text


def test_loader_without_any_module_outside_a_source_tree_is_no_build_hint(tmp_path):
    lines = _loader_report(tmp_path, None, None)
    text = "\n".join(lines)
    assert "carries no native core" in text and "tools/install.sh" not in text


def test_addon_zip_installs_and_enables_in_a_clean_blender(packages, tmp_path):
    legacy, _ = packages
    script = (
        "import bpy, addon_utils, sys\n"
        f"bpy.ops.preferences.addon_install(filepath={legacy!r})\n"
        "addon_utils.enable('sunlapse', default_set=True)\n"
        "import sunlapse\n"
        "ok = (sunlapse.estimate.native_loader._native is not None\n"
        "      and hasattr(bpy.types.Scene, 'sunlapse'))\n"
        "print('INSTALLED', ok, sunlapse.__file__)\n"
        "sys.exit(0 if ok else 1)\n")
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(tmp_path / "scripts"))
    proc = subprocess.run([bpy.app.binary_path, "-b", "--factory-startup",
                           "--python-exit-code", "1", "--python-expr", script],
                          capture_output=True, text=True, env=env, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    line = next(ln for ln in proc.stdout.splitlines() if ln.startswith("INSTALLED"))
    assert str(tmp_path / "scripts") in line  # the installed copy, not the source tree
