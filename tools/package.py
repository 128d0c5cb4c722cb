"""Builds the installable packages of the add-on with its compiled module(s).

  python3 tools/package.py OUT_DIR MODULE.so [MODULE.so ...] [--blender CMD] [--patchelf CMD]
  (or: cmake --build build --target package_addon; a release: bash tools/release.sh)

MODULE.so: _native built for CPython 3.11, 3.13 and/or 3.14. Each module and exactly
the shared libraries it needs (found with ldd, so with the loader's own search)
go into a `sunlapse_native` package: the modules beside `libs/`, every
library's search path set to $ORIGIN with patchelf. Only the C runtime and
system basics (SYSTEM_LIBS) are left to the machine. Writes into OUT_DIR:

  sunlapse-VERSION-addon.zip        Blender 3.x (Debian's 3.4, Python 3.11):
                                    sunlapse/ with sunlapse/sunlapse_native/
  sunlapse-VERSION-linux_x64.zip    Blender 4.2+ extension: the add-on and
                                    wheels/sunlapse_native-...-manylinux_*.whl
                                    (one wheel, tagged for each Python built)

With --blender CMD (a Blender 4.2+ command line), the extension is built and
validated by Blender itself (`-c extension build --split-platforms`,
`-c extension validate`); without it, zipped here with the same layout.
With --patchelf CMD (patchelf 0.18+), the bundled libraries and their symbols
get names of their own (isolate()), as release builds do.
Test footage (../shared/real) and the build tree never go in.
"""
import base64
import hashlib
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
import tomllib
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADDON = os.path.join(ROOT, "addon")
# glibc's own libraries, the GCC runtime and the loader: always the machine's
# (a copy of glibc's parts from another glibc would not even load).
SYSTEM_LIBS = {"linux-vdso.so.1", "libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2",
               "librt.so.1", "libresolv.so.2", "libgcc_s.so.1", "libstdc++.so.6",
               "ld-linux-x86-64.so.2"}
PLATFORM = "linux_x64"


class PackageError(Exception):
    pass


def addon_files():
    for folder, dirs, files in os.walk(ADDON):
        dirs[:] = [d for d in dirs if d not in ("__pycache__", "sunlapse_native")]
        for f in sorted(files):
            if f.endswith(".py"):
                path = os.path.join(folder, f)
                yield path, os.path.relpath(path, ADDON)


def ldd(path):
    """[(soname, resolved path or None)] as the system loader resolves them,
    with no library path set."""
    env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
    out = subprocess.run(["ldd", path], capture_output=True, text=True, env=env, check=True).stdout
    libs = []
    for line in out.splitlines():
        line = line.strip()
        m = re.match(r"(\S+) => (not found|(\S+) \(0x[0-9a-f]+\))", line)
        if m:
            libs.append((m.group(1), m.group(3)))
        elif re.match(r"(\S+) \(0x[0-9a-f]+\)", line):
            libs.append((os.path.basename(line.split()[0]), line.split()[0]))
    return libs


def python_tag(module):
    m = re.search(r"\.cpython-(\d+)-x86_64-linux-gnu\.so$", module)
    if not m:
        raise PackageError(f"{module}: not a CPython x86-64 Linux module "
                           "(_native.cpython-3XX-...so)")
    return "cp" + m.group(1)


def bundle(modules, dest):
    """Makes the sunlapse_native package in `dest`: the modules, libs/ with
    every non-system library they need, RUNPATHs set. Returns the libraries."""
    libs_dir = os.path.join(dest, "libs")
    os.makedirs(libs_dir)
    with open(os.path.join(dest, "__init__.py"), "w") as fh:
        fh.write('"""The compiled core of sunlapse and the libraries it needs."""\n')
    needed = {}
    for module in modules:
        for name, path in ldd(module):
            if name in SYSTEM_LIBS:
                continue
            if path is None:
                raise PackageError(f"{module}: {name} not found by the loader; build on a machine "
                                   "that has it")
            needed[name] = os.path.realpath(path)
    for name, path in sorted(needed.items()):
        target = os.path.join(libs_dir, name)
        shutil.copyfile(path, target)
        os.chmod(target, 0o755)
        subprocess.run(["patchelf", "--set-rpath", "$ORIGIN", target], check=True)
    for module in modules:
        target = os.path.join(dest, os.path.basename(module))
        shutil.copyfile(module, target)
        os.chmod(target, 0o755)
        subprocess.run(["strip", "--strip-unneeded", target], check=True)
        subprocess.run(["patchelf", "--set-rpath", "$ORIGIN/libs", target], check=True)
    check_self_contained(dest)
    return sorted(needed)


def _defined_symbols(path):
    out = subprocess.run(["nm", "-D", "--defined-only", "--without-symbol-versions",
                          "--format=posix", path], capture_output=True, text=True).stdout
    return {line.split()[0] for line in out.splitlines() if line.strip()}


def isolate(dest, patchelf):
    """Gives the bundled libraries names of their own (SONAME prefix
    'sunlapse-') and prefixes every dynamic symbol they define (in them and in
    the modules), so a host that has loaded its own Embree, OpenCV, TBB ...
    (Blender 4.x: Embree 4, whose C functions carry Embree 3's names; trixie's
    OpenCV 4.10) never stands in for ours, and ours never for its. Needs
    patchelf 0.18+ (--rename-dynamic-symbols)."""
    libs_dir = os.path.join(dest, "libs")
    libs = sorted(os.listdir(libs_dir))
    modules = [os.path.join(dest, f) for f in os.listdir(dest) if f.endswith(".so")]
    system = set()
    for name, path in ldd(modules[0]):
        if name in SYSTEM_LIBS and path and os.path.exists(path):
            system |= _defined_symbols(path)
    symbols = set()
    for lib in libs:
        symbols |= _defined_symbols(os.path.join(libs_dir, lib))
    symbols -= system
    symbols -= {"_init", "_fini", "_edata", "_end", "__bss_start"}
    map_path = os.path.join(dest, os.pardir, "symbols.map")
    with open(map_path, "w") as fh:
        fh.writelines(f"{s} sunlapse_{s}\n" for s in sorted(symbols))
    renamed = {lib: "sunlapse-" + lib for lib in libs}
    for path in [os.path.join(libs_dir, lib) for lib in libs] + modules:
        args = [*patchelf, "--rename-dynamic-symbols", map_path]
        for old, new in renamed.items():
            args += ["--replace-needed", old, new]
        if os.path.dirname(path) == libs_dir:
            args += ["--set-soname", renamed[os.path.basename(path)]]
        subprocess.run(args + [path], check=True, capture_output=True)
    for old, new in renamed.items():
        os.rename(os.path.join(libs_dir, old), os.path.join(libs_dir, new))
    os.remove(map_path)
    return len(symbols)


def check_self_contained(dest):
    """Every library of every file in `dest` resolves inside `dest` or is a
    system basic (ldd, no library path)."""
    dest = os.path.realpath(dest)
    for folder, _, files in os.walk(dest):
        for f in files:
            if ".so" not in f:
                continue
            for name, path in ldd(os.path.join(folder, f)):
                if name in SYSTEM_LIBS:
                    continue
                if path is None or not os.path.realpath(path).startswith(dest + os.sep):
                    raise PackageError(f"{f}: {name} resolves to {path}, outside the package")


def _record_hash(data):
    return "sha256=" + base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()


def wheel(package_dir, out_dir, version, tags):
    """A wheel of the sunlapse_native package for the CPython tags given."""
    glibc = platform.libc_ver()[1].replace(".", "_") or "2_36"
    py = ".".join(tags)
    plat = f"manylinux_{glibc}_x86_64"
    name = f"sunlapse_native-{version}-{py}-{py}-{plat}.whl"
    info = f"sunlapse_native-{version}.dist-info"
    files = {}
    for folder, _, names in os.walk(package_dir):
        for f in sorted(names):
            path = os.path.join(folder, f)
            rel = os.path.relpath(path, os.path.dirname(package_dir)).replace(os.sep, "/")
            with open(path, "rb") as fh:
                files[rel] = fh.read()
    files[f"{info}/METADATA"] = (f"Metadata-Version: 2.1\nName: sunlapse-native\n"
                                 f"Version: {version}\n"
                                 "Summary: The compiled core of the sunlapse Blender add-on\n"
                                 ).encode()
    files[f"{info}/WHEEL"] = ("Wheel-Version: 1.0\nGenerator: sunlapse tools/package.py\n"
                              "Root-Is-Purelib: false\n"
                              + "".join(f"Tag: {t}-{t}-{plat}\n" for t in tags)).encode()
    record = "".join(f"{rel},{_record_hash(data)},{len(data)}\n" for rel, data in files.items())
    record += f"{info}/RECORD,,\n"
    path = os.path.join(out_dir, name)
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
        for rel, data in files.items():
            z.writestr(zipfile.ZipInfo(rel, (2020, 1, 1, 0, 0, 0)), data, zipfile.ZIP_DEFLATED)
        z.writestr(f"{info}/RECORD", record)
    return path


def _manifest_with_wheel(text, wheel_rel, tags):
    """The manifest with `wheels` set and a line naming the Pythons inside;
    top-level keys go before the first table."""
    pythons = ", ".join(f"{t[2]}.{t[3:]}" for t in tags)
    line = f'# The wheel holds the core for CPython {pythons}.\nwheels = ["{wheel_rel}"]\n'
    m = re.search(r"^\[", text, re.M)
    return text[:m.start()] + line + "\n" + text[m.start():] if m else text + line


def build(modules, out_dir, blender=None, patchelf=None):
    """Writes the 3.x add-on zip and the extension into out_dir; returns their
    paths. `blender`: a Blender 4.2+ command line to build and validate the
    extension; `patchelf`: a patchelf 0.18+ command line to isolate() the
    bundled libraries (release builds)."""
    if isinstance(modules, str):
        modules = [modules]
    manifest_path = os.path.join(ROOT, "blender_manifest.toml")
    with open(manifest_path, "rb") as fh:
        version = tomllib.load(fh)["version"]
    for m in modules:
        if not os.path.isfile(m):
            raise PackageError(f"no compiled module at {m}: build it first")
    tags = sorted({python_tag(m) for m in modules})
    os.makedirs(out_dir, exist_ok=True)
    stage = os.path.join(out_dir, "stage")
    shutil.rmtree(stage, ignore_errors=True)

    # Blender 3.x: the add-on folder with the 3.11 module vendored.
    legacy_modules = [m for m in modules if python_tag(m) == "cp311"] or modules
    legacy_dir = os.path.join(stage, "legacy", "sunlapse")
    bundle(legacy_modules, os.path.join(legacy_dir, "sunlapse_native"))
    if patchelf:
        isolate(os.path.join(legacy_dir, "sunlapse_native"), shlex.split(patchelf))
        check_self_contained(os.path.join(legacy_dir, "sunlapse_native"))
    legacy = os.path.join(out_dir, f"sunlapse-{version}-addon.zip")
    with zipfile.ZipFile(legacy, "w", zipfile.ZIP_DEFLATED) as z:
        for path, rel in addon_files():
            z.write(path, f"sunlapse/{rel}")
        for folder, _, files in os.walk(os.path.join(legacy_dir, "sunlapse_native")):
            for f in sorted(files):
                path = os.path.join(folder, f)
                z.write(path, "sunlapse/" + os.path.relpath(path, legacy_dir))

    # Blender 4.2+: the extension with one wheel for every Python built.
    native_dir = os.path.join(stage, "native", "sunlapse_native")
    bundle(modules, native_dir)
    if patchelf:
        isolate(native_dir, shlex.split(patchelf))
        check_self_contained(native_dir)
    ext_dir = os.path.join(stage, "extension")
    os.makedirs(os.path.join(ext_dir, "wheels"))
    whl = wheel(native_dir, os.path.join(ext_dir, "wheels"), version, tags)
    with open(manifest_path) as fh:
        manifest = _manifest_with_wheel(fh.read(), "./wheels/" + os.path.basename(whl), tags)
    with open(os.path.join(ext_dir, "blender_manifest.toml"), "w") as fh:
        fh.write(manifest)
    for path, rel in addon_files():
        os.makedirs(os.path.dirname(os.path.join(ext_dir, rel)), exist_ok=True)
        shutil.copyfile(path, os.path.join(ext_dir, rel))
    extension = os.path.join(out_dir, f"sunlapse-{version}-{PLATFORM}.zip")
    if os.path.exists(extension):
        os.remove(extension)
    if blender:
        cmd = shlex.split(blender)
        run = subprocess.run(cmd + ["-c", "extension", "build", "--source-dir", ext_dir,
                                    "--output-dir", out_dir, "--split-platforms"],
                             capture_output=True, text=True)
        if run.returncode != 0 or not os.path.exists(extension):
            raise PackageError("blender -c extension build failed:\n" + run.stdout + run.stderr)
        run = subprocess.run(cmd + ["-c", "extension", "validate", extension],
                             capture_output=True, text=True)
        if run.returncode != 0:
            raise PackageError("blender -c extension validate failed:\n" + run.stdout + run.stderr)
    else:
        with zipfile.ZipFile(extension, "w", zipfile.ZIP_DEFLATED) as z:
            for folder, _, files in os.walk(ext_dir):
                for f in sorted(files):
                    path = os.path.join(folder, f)
                    z.write(path, os.path.relpath(path, ext_dir))
    shutil.rmtree(stage, ignore_errors=True)
    return legacy, extension


def main(argv):
    tools = {"--blender": None, "--patchelf": None}
    for flag in tools:
        if flag in argv:
            i = argv.index(flag)
            if i + 1 >= len(argv):
                sys.exit(f"package: {flag} needs a command line")
            tools[flag] = argv[i + 1]
            argv = argv[:i] + argv[i + 2:]
    if len(argv) < 2:
        sys.exit(__doc__)
    try:
        paths = build(argv[1:], argv[0], tools["--blender"], tools["--patchelf"])
    except PackageError as e:
        sys.exit(f"package: {e}")
    for p in paths:
        print(f"package: wrote {p} ({os.path.getsize(p) / 1e6:.1f} MB)")


if __name__ == "__main__":
    main(sys.argv[1:])
