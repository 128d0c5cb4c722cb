#!/usr/bin/env bash
# Installs the release packages where the build machine's libraries are absent
# and runs a scripted estimate with each (not part of tools/test.sh: it
# downloads about 1.5 GB, cached under build/roots):
#   (a) Blender 3.4 in a debootstrap'd Debian 12 root that has Blender and
#       nothing of the build's (no -dev packages, no OpenCV/Ceres/ERFA ...),
#       the 3.x add-on zip installed, the estimate scripted in Python;
#   (b) Blender 4.3 (Python 3.13) from Debian trixie and (c) Blender 5.x
#       (Python 3.14) from Debian sid, each unpacked under a prefix (private
#       apt state, dpkg-deb -x, the suite's own loader via chroot), the
#       extension installed with `-c extension install-file --enable`, then
#       `blender -c sunlapse SCENE.blend --out ... --apply-lamp --save ...`.
# In each, the saved file is opened again (tools/check_saved_scene.py): the
# lamp must match the track on every frame, and the AR setup (compositor
# included) must render a frame. The tracks must match the source tree's.
# In (b) and (c), with numpy hidden, `blender -c sunlapse` must print one
# error line and exit 4.
# (d) The window tests (tests/ui, Xvfb) run in sid's Blender 5.x too.
#   bash tools/test-packages.sh        (ends "test-packages: PASS" or exits 1)
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_root="${SUNLAPSE_BUILD_DIR:-$here/build}"
out="$build_root/pkgtest"
source "$here/tools/pkgroots.sh"
# Per-frame difference allowed between a package's track and the source
# tree's (degrees): other decoders/Python builds may round differently.
tolerance_deg="${SUNLAPSE_PACKAGE_TOLERANCE_DEG:-0.05}"

"$here/tools/install.sh" >/dev/null
bash "$here/tools/release.sh"
echo "[test-packages] Debian 12 root with Blender 3.4 (debootstrap), trixie's Blender 4.3, sid's 5.x"
ensure_bookworm
ensure_trixie
ensure_sid
dist="$build_root/release/dist"
legacy_zip=$(ls "$dist"/sunlapse-*-addon.zip)
extension_zip=$(ls "$dist"/sunlapse-*-linux_x64.zip)
mkdir -p "$out"
for f in "$legacy_zip" "$extension_zip"; do
  echo "[test-packages] $(basename "$f"): $(du -m "$f" | cut -f1) MB"
done

echo "== the packaged modules resolve every library inside the package (ldd, no library path)"
rm -rf "$out/unpacked" && mkdir -p "$out/unpacked/legacy" "$out/unpacked/wheel"
(cd "$out/unpacked/legacy" && unzip -q "$legacy_zip")
(cd "$out/unpacked/wheel" && unzip -q "$extension_zip" 'wheels/*' && unzip -q wheels/*.whl)
/usr/bin/python3 - "$here" "$out/unpacked/legacy/sunlapse/sunlapse_native" \
    "$out/unpacked/wheel/sunlapse_native" <<'PY'
import os, sys
sys.path.insert(0, os.path.join(sys.argv[1], "tools"))
import package
for d in sys.argv[2:]:
    package.check_self_contained(d)  # raises naming the file and library
    mods = sorted(f for f in os.listdir(d) if f.startswith("_native"))
    print(f"  {os.path.relpath(d, os.path.dirname(os.path.dirname(d)))}: {', '.join(mods)}, "
          f"{len(os.listdir(os.path.join(d, 'libs')))} bundled libraries: self-contained")
PY
# The same inside the bare Debian 12 root, where none of the build's libraries exist.
module=$(ls "$out"/unpacked/legacy/sunlapse/sunlapse_native/_native*.so)
outside=$(in_root "$ROOTS_DIR/bookworm" ldd "$module" | grep -v "sunlapse_native/libs/" \
          | grep -vE "linux-vdso|ld-linux|lib(c|m|pthread|dl|rt|resolv|gcc_s|stdc\+\+)\.so" || true)
if [ -n "$outside" ]; then
  echo "  in the Debian 12 root, from outside the package:"; echo "$outside"; exit 1
fi
echo "  in the Debian 12 root: everything but the system basics from the package"
# Blender 3.4 itself depends on some of the same libraries (OpenCV through
# OpenImageIO, Embree, TBB, FFmpeg): the module must not use them (ldd above).
echo "  the root's packages that the build also uses (Blender's own dependencies):" \
  $(in_root "$ROOTS_DIR/bookworm" dpkg-query -W -f '${Package}\n' | grep -E \
    "^lib(opencv|ceres|erfa|glog|gflags|cholmod|embree|tbb|avformat|avcodec|swscale)|-dev$" || true)

echo "== the scene (source tree, this machine's Blender 3.4)"
scene="$out/scene"
if [ ! -f "$scene/scene.blend" ]; then
  nice -n 10 blender -b --factory-startup --python-exit-code 1 \
    --python "$here/examples/generate_scene.py" -- --preset plaza --out "$scene" \
    --frames 12 --resolution 320x180 --samples 8 >"$out/generate.log" 2>&1 \
    || { tail -5 "$out/generate.log"; exit 1; }
fi
rm -f "$out"/*.sun.json
blender -b "$scene/scene.blend" --python-exit-code 1 --python "$here/examples/run_estimate.py" \
  -- --out "$out/source.sun.json" >"$out/source.log" 2>&1 || { tail -5 "$out/source.log"; exit 1; }

check_script="$here/tools/check_saved_scene.py"

echo "== (a) Blender 3.4, Debian 12 root without the build's libraries: the add-on zip"
user34="$out/user-3.4" && rm -rf "$user34" && mkdir -p "$user34"
b34() { in_root "$ROOTS_DIR/bookworm" env HOME=/tmp BLENDER_USER_SCRIPTS="$user34/scripts" blender "$@"; }
b34 -b "$scene/scene.blend" --python-exit-code 1 --python-expr "
import addon_utils, bpy, sys
bpy.ops.preferences.addon_install(filepath='$legacy_zip')
addon_utils.enable('sunlapse', default_set=True)
import sunlapse
assert sunlapse.__file__.startswith('$user34'), sunlapse.__file__
print('native:', sunlapse.estimate.native_loader.require().__file__)
from sunlapse import cli
sys.exit(cli.main(['--out', '$out/blender-3.4.sun.json', '--apply-lamp',
                   '--save', '$out/blender-3.4.blend']))
" >"$out/blender-3.4.log" 2>&1 || { tail -15 "$out/blender-3.4.log"; exit 1; }
grep "^native:" "$out/blender-3.4.log" | sed 's/^/  /'
b34 -b "$out/blender-3.4.blend" --python-exit-code 1 \
  --python-expr "import addon_utils; addon_utils.enable('sunlapse')" \
  --python "$check_script" -- "$out/blender-3.4.sun.json" "$out/ar-3.4" \
  >"$out/blender-3.4-check.log" 2>&1 || { tail -15 "$out/blender-3.4-check.log"; exit 1; }
grep "^check" "$out/blender-3.4-check.log" | sed 's/^/  /'

# An unpacked suite's Blender with the extension: VERSION ROOT.
extension_run() {
  local version="$1" root="$2" user="$out/user-$1"
  rm -rf "$user" && mkdir -p "$user"
  # (the unpacked prefixes have no coreutils: the environment is set out here)
  bx() { HOME=/tmp BLENDER_USER_RESOURCES="$user" in_root "$ROOTS_DIR/$root" /usr/bin/blender "$@"; }
  bx -b -c extension install-file -r user_default --enable "$extension_zip" \
    >"$out/blender-$version-install.log" 2>&1 || { tail -15 "$out/blender-$version-install.log"; return 1; }
  bx -b -c sunlapse "$scene/scene.blend" --out "$out/blender-$version.sun.json" --apply-lamp \
    --save "$out/blender-$version.blend" >"$out/blender-$version.log" 2>&1 \
    || { tail -15 "$out/blender-$version.log"; return 1; }
  bx -b --python-expr "
import sys, addon_utils
print('python', sys.version.split()[0])
import sunlapse_native._native as n; print('native:', n.__file__)
" 2>&1 | grep -E "^(python|native:)" | sed 's/^/  /' || true
  bx -b "$out/blender-$version.blend" --python-exit-code 1 --python "$check_script" -- \
    "$out/blender-$version.sun.json" "$out/ar-$version" >"$out/blender-$version-check.log" 2>&1 \
    || { tail -15 "$out/blender-$version-check.log"; return 1; }
  grep "^check" "$out/blender-$version-check.log" | sed 's/^/  /'
  # A Blender Python that cannot import numpy (hidden on PYTHONPATH here, as
  # a pyenv or conda Python first on PATH hides it from Debian's Blender):
  # `blender -c sunlapse` says so in one line and exits 4, no traceback.
  local fake="$out/no-numpy" log="$out/blender-$version-no-numpy.log" code=0
  mkdir -p "$fake/numpy" && rm -f "$out/no-numpy.sun.json"
  echo 'raise ModuleNotFoundError("No module named numpy (hidden by test-packages)", name="numpy")' \
    >"$fake/numpy/__init__.py"
  PYTHONPATH="$fake" bx --python-use-system-env -b -c sunlapse "$scene/scene.blend" \
    --out "$out/no-numpy.sun.json" >"$log" 2>&1 || code=$?
  if [ "$code" != 4 ] || ! grep -q "^sunlapse: error: .*cannot import numpy" "$log" \
      || grep -q Traceback "$log" || [ -e "$out/no-numpy.sun.json" ]; then
    echo "  without numpy: expected one error line and exit 4, got exit $code:"
    tail -15 "$log"; return 1
  fi
  echo "  without numpy: one error line, exit 4"
}

echo "== (b) Blender 4.3 / Python 3.13 from trixie: the extension"
extension_run 4.3 trixie
echo "== (c) Blender 5.x / Python 3.14 from sid: the extension"
extension_run 5 sid

echo "== (d) the window tests (Xvfb) in sid's Blender 5.x, the core from its extension"
# The root shares the machine's /tmp: the X server's socket and cookie, and
# pytest's folders.
site=$(ls -d "$out"/user-5/extensions/.local/lib/python3*/site-packages)
(cd "$here" && SUNLAPSE_ROOT_SHARE_TMP=1 SUNLAPSE_UI_SYS_PATH="$site" \
  SUNLAPSE_UI_BLENDER="bash $here/tools/pkgroots.sh run sid /usr/bin/blender" \
  /usr/bin/python3 -m pytest -q -p no:cacheprovider tests/ui) >"$out/ui-5.log" 2>&1 \
  || { tail -30 "$out/ui-5.log"; exit 1; }
tail -1 "$out/ui-5.log" | sed 's/^/  /'

echo "== accuracy against the truth, and each package against the source tree"
/usr/bin/python3 - "$here" "$scene/truth.sun.json" "$out" "$tolerance_deg" <<'PY'
import os, sys
here, truth_path, out, tol = sys.argv[1], sys.argv[2], sys.argv[3], float(sys.argv[4])
sys.path.insert(0, os.path.join(here, "addon"))
from core import evaluation, trackfile
truth = trackfile.read_track(truth_path)
tracks = {n: trackfile.read_track(os.path.join(out, n + ".sun.json"))
          for n in ("source", "blender-3.4", "blender-4.3", "blender-5")}
reports = [evaluation.evaluate(n, t, truth) for n, t in tracks.items()]
print(evaluation.format_table(reports))
src = {f.frame: f for f in tracks["source"].frames}
ok = True
for name in ("blender-3.4", "blender-4.3", "blender-5"):
    worst, compared = 0.0, 0
    for f in tracks[name].frames:
        s = src.get(f.frame)
        if (s is None) or (s.has_estimate != f.has_estimate):
            print(f"{name}: frame {f.frame} estimated in one track only"); ok = False
            continue
        if f.has_estimate:
            d = evaluation.angle_between_deg(evaluation.direction(f.zenith_deg, f.azimuth_deg),
                                             evaluation.direction(s.zenith_deg, s.azimuth_deg))
            worst, compared = max(worst, d), compared + 1
    same = compared == sum(1 for f in tracks["source"].frames if f.has_estimate) and compared > 0
    print(f"{name}: {compared} frames, largest difference from the source tree's track "
          f"{worst:.4f} deg (allowed {tol})")
    ok = ok and same and worst <= tol
print("test-packages: PASS" if ok else "test-packages: FAIL")
sys.exit(0 if ok else 1)
PY
