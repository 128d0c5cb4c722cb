"""Builds the installable packages of the add-on with its compiled module.

  python3 tools/package.py NATIVE_MODULE.so OUT_DIR
  (or: cmake --build build --target package_addon)

Writes into OUT_DIR:
  sunlapse-VERSION-addon.zip         Blender 3.x: Preferences > Add-ons > Install
  sunlapse-VERSION-linux-x64.zip     Blender 4.2+ extension (Install from Disk)
Both carry the module built for CPython 3.11 on x86-64 Linux. Test footage
(../shared/real) and the build tree never go in.
"""
import os
import sys
import tomllib
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADDON = os.path.join(ROOT, "addon")


def addon_files():
    for folder, dirs, files in os.walk(ADDON):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        for f in sorted(files):
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                yield path, os.path.relpath(path, ADDON)


def build(module, out_dir):
    manifest_path = os.path.join(ROOT, "blender_manifest.toml")
    with open(manifest_path, "rb") as fh:
        manifest = tomllib.load(fh)
    version = manifest["version"]
    if not os.path.isfile(module):
        sys.exit(f"package: no compiled module at {module}: build it first")
    os.makedirs(out_dir, exist_ok=True)
    module_name = os.path.basename(module)
    legacy = os.path.join(out_dir, f"sunlapse-{version}-addon.zip")
    extension = os.path.join(out_dir, f"sunlapse-{version}-linux-x64.zip")
    with zipfile.ZipFile(legacy, "w", zipfile.ZIP_DEFLATED) as z:
        for path, rel in addon_files():
            z.write(path, f"sunlapse/{rel}")
        z.write(module, f"sunlapse/{module_name}")
    with zipfile.ZipFile(extension, "w", zipfile.ZIP_DEFLATED) as z:
        z.write(manifest_path, "blender_manifest.toml")
        for path, rel in addon_files():
            z.write(path, rel)
        z.write(module, module_name)
    return legacy, extension


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    for p in build(sys.argv[1], sys.argv[2]):
        print(f"package: wrote {p}")
