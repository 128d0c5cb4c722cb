#!/usr/bin/env bash
# Release build of the linux-x64 packages (Blender 3.x add-on zip and the
# Blender 4.2+ extension), self-contained: modules for CPython 3.11, 3.13 and 3.14,
# a small static FFmpeg, every other library bundled with RUNPATH $ORIGIN.
#   bash tools/release.sh          -> build/release/dist/
# Downloads (cached under build/roots): trixie's Python 3.13 and sid's 3.14
# headers with their pybind11, Debian 12's FFmpeg source, trixie's Blender 4.3 (it builds and
# validates the extension). The system's apt state is never touched.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_root="${SUNLAPSE_BUILD_DIR:-$here/build}"
release_dir="$build_root/release"
source "$here/tools/pkgroots.sh"

echo "[release] Python 3.13 and 3.14 headers, static FFmpeg, Blender 4.3 (cached under $ROOTS_DIR)"
ensure_py313
ensure_py314
ensure_ffmpeg
ensure_trixie

# ccache speeds a rebuild when it is there (tools/install.sh installs it); a
# launcher that is not installed would fail CMake's compiler check.
if [ -z "${CMAKE_CXX_COMPILER_LAUNCHER:-}" ] && command -v ccache >/dev/null; then
  export CMAKE_CXX_COMPILER_LAUNCHER=ccache
fi
cmake -S "$here" -B "$release_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DPython_EXECUTABLE=/usr/bin/python3 -DSUNLAPSE_BUILD_TESTS=OFF \
  -DSUNLAPSE_COPY_MODULE_TO_ADDON=OFF \
  -DSUNLAPSE_FFMPEG_ROOT="$ROOTS_DIR/ffmpeg" -DSUNLAPSE_PY313_ROOT="$ROOTS_DIR/py313" \
  -DSUNLAPSE_PY314_ROOT="$ROOTS_DIR/py314" >/dev/null
cmake --build "$release_dir" -j "$(nproc)" --target _native _native313 _native314

modules=("$release_dir"/python/_native.cpython-311-x86_64-linux-gnu.so
         "$release_dir"/python/_native.cpython-313-x86_64-linux-gnu.so
         "$release_dir"/python/_native.cpython-314-x86_64-linux-gnu.so)
echo "[release] _native links $(ldd "${modules[0]}" | wc -l) libraries (ldd lines)"
rm -rf "$release_dir/dist"
/usr/bin/python3 "$here/tools/package.py" "$release_dir/dist" "${modules[@]}" \
  --blender "bash $here/tools/pkgroots.sh run trixie /usr/bin/blender" \
  --patchelf "bash $here/tools/pkgroots.sh run trixie /usr/bin/patchelf"
