"""Guarded import of the compiled core, so the add-on registers without it.

Where the module comes from, first found wins:
  addon/_native.cpython-3XX-*.so         a source checkout (tools/install.sh builds it)
  sunlapse_native/ inside the add-on     the Blender 3.x add-on zip
  sunlapse_native (a wheel)              the Blender 4.2+ extension (Blender installs
                                         the wheel into its extensions' site-packages)
Packaged modules carry their libraries in sunlapse_native/libs/ (RUNPATH
$ORIGIN; renamed libraries and symbols in release builds, so a host's own
Embree, OpenCV ... never stand in for them); Python picks the module whose
suffix matches its own ABI.

When nothing loads, DIAGNOSIS says which file, which library or Python
version is missing, and which Blender and Python were found.
"""
import glob
import importlib
import os
import sys
import sysconfig

# The add-on's folder and package: this module sits in its estimate/ package.
ADDON_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
ADDON_PACKAGE = (__package__ or "").rpartition(".")[0]
# A source checkout has the CMake project one level up.
SOURCE_CHECKOUT = os.path.isfile(os.path.join(ADDON_DIR, os.pardir, "CMakeLists.txt")) and \
    os.path.isdir(os.path.join(ADDON_DIR, os.pardir, "native"))
# The system basics a packaged module may take from the machine.
SYSTEM_LIBS = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1",
               "libgcc_s.so.1", "libstdc++.so.6", "ld-linux-x86-64.so.2", "libresolv.so.2"}


def _import_plain(name):
    # Outside the add-on's package (addon/ on sys.path: tests, benchmarks)
    # the module beside it is a top-level one.
    if not ADDON_PACKAGE:
        name = name.lstrip(".")
    return importlib.import_module(name, ADDON_PACKAGE or None)


def _candidates():
    """(import name, loader, folder) in the order tried."""
    yield "._native", _import_plain, ADDON_DIR
    yield ".sunlapse_native._native", _import_plain, os.path.join(ADDON_DIR, "sunlapse_native")
    for entry in sys.path:
        folder = os.path.join(entry, "sunlapse_native")
        if os.path.isdir(folder):
            yield "sunlapse_native._native", _import_plain, folder
            return
    yield "sunlapse_native._native", _import_plain, None


def _load():
    errors = []
    for name, loader, folder in _candidates():
        if folder is not None and not glob.glob(os.path.join(folder, "_native*.so")):
            continue
        try:
            return loader(name), None
        except ImportError as exc:
            errors.append((folder, exc))
    return None, errors


def _elf_needed(path):
    """(DT_NEEDED names, RUNPATH/RPATH dirs with $ORIGIN expanded) of an ELF
    shared object, or None when it is not a readable 64-bit little-endian ELF."""
    import struct
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except OSError:
        return None
    if data[:4] != b"\x7fELF" or data[4] != 2 or data[5] != 1:
        return None
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    sections = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * shentsize)
                for i in range(shnum)]
    needed, paths = [], []
    for name, kind, _, _, offset, size, link, _, _, entsize in sections:
        if kind != 6:  # SHT_DYNAMIC
            continue
        strtab = sections[link][4]

        def string(at):
            end = data.index(b"\0", strtab + at)
            return data[strtab + at:end].decode(errors="replace")
        for i in range(size // (entsize or 16)):
            tag, value = struct.unpack_from("<qQ", data, offset + i * 16)
            if tag == 1:
                needed.append(string(value))
            elif tag in (15, 29):  # DT_RPATH, DT_RUNPATH
                origin = os.path.dirname(os.path.abspath(path))
                paths += [p.replace("$ORIGIN", origin) for p in string(value).split(":") if p]
    return needed, paths


def missing_libraries(module_path, limit=200):
    """[(library, needed by)] that neither the module's folders nor the system
    provide, following bundled libraries' own needs."""
    import ctypes
    missing, todo = [], [module_path]
    seen: set = set()
    while todo and len(seen) < limit:
        path = todo.pop()
        info = _elf_needed(path)
        if info is None:
            continue
        needed, dirs = info
        for lib in needed:
            if lib in seen:
                continue
            seen.add(lib)
            local = next((os.path.join(d, lib) for d in dirs
                          if os.path.exists(os.path.join(d, lib))), None)
            if local:
                todo.append(local)
                continue
            try:
                ctypes.CDLL(lib)
            except OSError:
                missing.append((lib, os.path.basename(path)))
    return missing


def _blender_and_python():
    try:
        import bpy
        blender = f"Blender {bpy.app.version_string}"
    except ImportError:
        blender = "no Blender"
    py = ".".join(map(str, sys.version_info[:3]))
    return f"{blender}, Python {py} (modules ending {sysconfig.get_config_var('EXT_SUFFIX')})"


def _python_of(path):
    """'CPython 3.11' for _native.cpython-311-x86_64-linux-gnu.so."""
    import re
    m = re.search(r"\.cpython-(\d)(\d+)-", os.path.basename(path))
    return f"CPython {m.group(1)}.{m.group(2)}" if m else os.path.basename(path)


def diagnose(errors):
    """Lines saying why no native module loaded, first line the summary."""
    found = _blender_and_python()
    files = sorted({f for folder, _ in errors if folder
                    for f in glob.glob(os.path.join(folder, "_native*.so"))})
    suffix = sysconfig.get_config_var("EXT_SUFFIX") or ""
    if not files:
        if SOURCE_CHECKOUT:
            return ["The native core (_native) is not built.",
                    "From the sunlapse source folder run: bash tools/install.sh", found]
        return ["This sunlapse package carries no native core (_native) for this system.",
                f"Looked in {ADDON_DIR} and in sunlapse_native on Python's path.", found,
                "Install the package built for linux-x64 (Python 3.11 or 3.13)."]
    matching = [f for f in files if f.endswith(suffix)]
    if not matching:
        built = ", ".join(_python_of(f) for f in files)
        lines = [f"The native core here is built for {built}; this Blender runs another Python.",
                 f"Files: {', '.join(files)}", found,
                 "Packages carry modules for Python 3.11 (Blender 4.2-4.5, Debian's 3.4) "
                 "and 3.13 (Blender 5.x)."]
        if SOURCE_CHECKOUT:
            lines.append("From the sunlapse source folder, bash tools/release.sh builds "
                         "packages with both (build/release/dist).")
        return lines
    lines = [f"The native core {matching[0]} does not load."]
    gone = missing_libraries(matching[0])
    if gone:
        lines.append("Missing libraries: " + ", ".join(f"{lib} (needed by {by})"
                                                       for lib, by in gone[:8]))
    lines.append(str(next(exc for folder, exc in errors
                          if folder and matching[0].startswith(folder))))
    lines.append(found)
    if SOURCE_CHECKOUT:
        lines.append("From the sunlapse source folder, rebuild: bash tools/install.sh")
    return lines


_native, _errors = _load()
DIAGNOSIS = [] if _native is not None else diagnose(_errors)
IMPORT_ERROR = None if _native is not None else " ".join(DIAGNOSIS)


def require():
    """Returns the native module or raises RuntimeError saying why it is missing."""
    if _native is None:
        raise RuntimeError(IMPORT_ERROR)
    return _native
