#!/usr/bin/env bash
# Foreign Debian roots for the release build and the package tests, all under
# the build folder (downloads cached there; the system's apt state is never
# touched). Sourced by tools/release.sh and tools/test-packages.sh, or run:
#   bash tools/pkgroots.sh py313      Python 3.13 headers + pybind11 (trixie)
#   bash tools/pkgroots.sh py314      Python 3.14 headers + pybind11 (sid)
#   bash tools/pkgroots.sh trixie     Blender 4.3 + its closure, unpacked
#   bash tools/pkgroots.sh sid        Blender 5.x + its closure, unpacked
#   bash tools/pkgroots.sh bookworm   a debootstrap root with only Blender 3.4
#   bash tools/pkgroots.sh ffmpeg     a small static FFmpeg for the release module
#   bash tools/pkgroots.sh run NAME CMD...   CMD chrooted in a root
set -euo pipefail
_here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
ROOTS_DIR="${SUNLAPSE_ROOTS_DIR:-${SUNLAPSE_BUILD_DIR:-$_here/build}/roots}"

# The Debian mirror the machine already uses (first URI of its apt sources),
# unless SUNLAPSE_DEBIAN_MIRROR says otherwise.
debian_mirror() {
  if [ -n "${SUNLAPSE_DEBIAN_MIRROR:-}" ]; then echo "$SUNLAPSE_DEBIAN_MIRROR"; return; fi
  local uri
  uri=$(grep -hE '^(URIs:|deb )' /etc/apt/sources.list.d/*.sources /etc/apt/sources.list \
          2>/dev/null | grep -v security | grep -m1 -oE '(https?|file)://[^ ]*/debian' || true)
  [ -n "$uri" ] || { echo "pkgroots: no Debian mirror found in the apt sources; set SUNLAPSE_DEBIAN_MIRROR" >&2; return 1; }
  echo "$uri"
}

# apt with a private state (lists, cache, an empty dpkg status) for another
# Debian suite (trixie, sid). Usage: suite_apt SUITE APT-ARGS...
suite_apt() {
  local d="$ROOTS_DIR/apt-$1"; shift
  apt-get -q -o Dir::State="$d/state" -o Dir::State::status="$d/state/status" \
    -o Dir::Cache="$d/cache" -o Dir::Etc::SourceList="$d/sources.list" \
    -o Dir::Etc::SourceParts="$d/none" -o Dir::Etc::Preferences="$d/none/prefs" \
    -o Dir::Etc::PreferencesParts="$d/none" -o APT::Architecture=amd64 \
    -o APT::Architectures::=amd64 -o Acquire::Languages=none \
    -o APT::Install-Recommends=false -o Debug::NoLocking=true "$@"
}

suite_apt_update() {
  local suite="$1" d="$ROOTS_DIR/apt-$1"
  mkdir -p "$d/state/lists/partial" "$d/cache/archives/partial" "$d/none"
  : >"$d/state/status"
  echo "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] $(debian_mirror) $suite main" \
    >"$d/sources.list"
  # sid moves daily: a day-old list may name packages the mirror has dropped.
  local age=7; [ "$suite" = sid ] && age=0
  if [ ! -f "$d/updated" ] || [ -n "$(find "$d/updated" -mtime +$age)" ]; then
    suite_apt "$suite" update >/dev/null && touch "$d/updated"
  fi
}

# Python headers and a pybind11 that knows them, for another module:
# ensure_python 3.13 trixie, ensure_python 3.14 sid -> $ROOTS_DIR/py313, py314.
ensure_python() {
  local version="$1" suite="$2" dest="$ROOTS_DIR/py${1/./}"
  if [ -f "$dest/.done" ]; then return; fi
  suite_apt_update "$suite"
  rm -rf "$dest" && mkdir -p "$dest/debs"
  (cd "$dest/debs" && suite_apt "$suite" download "libpython$version-dev" pybind11-dev >/dev/null)
  for deb in "$dest"/debs/*.deb; do dpkg-deb -x "$deb" "$dest"; done
  test -f "$dest/usr/include/python$version/Python.h"
  test -f "$dest/usr/include/pybind11/pybind11.h"
  touch "$dest/.done"
}
ensure_py313() { ensure_python 3.13 trixie; }
ensure_py314() { ensure_python 3.14 sid; }

# A small static FFmpeg (libavformat/libavcodec/libswscale) built from
# Debian 12's own source package: only the demuxers and decoders a clip or an
# image sequence needs and no external codec libraries, so the packaged module
# does not carry x264/x265/libvpx/gnutls/... (Debian's shared FFmpeg pulls
# ~140 libraries, ~200 MB). Its symbols stay hidden inside _native.
ensure_ffmpeg() {
  local dest="$ROOTS_DIR/ffmpeg" src="$ROOTS_DIR/ffmpeg-src" d="$ROOTS_DIR/apt-bookworm-src"
  if [ -f "$dest/.done" ]; then return; fi
  if ! ls "$src"/ffmpeg_*.orig.tar.* >/dev/null 2>&1; then
    mkdir -p "$d/state/lists/partial" "$d/cache/archives/partial" "$d/none" "$src"
    : >"$d/state/status"
    echo "deb-src [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] $(debian_mirror) bookworm main" \
      >"$d/sources.list"
    local opts=(-o Dir::State="$d/state" -o Dir::State::status="$d/state/status"
      -o Dir::Cache="$d/cache" -o Dir::Etc::SourceList="$d/sources.list"
      -o Dir::Etc::SourceParts="$d/none" -o Acquire::Languages=none -o Debug::NoLocking=true)
    apt-get -q "${opts[@]}" update >/dev/null
    (cd "$src" && apt-get -q "${opts[@]}" source --download-only ffmpeg >/dev/null)
  fi
  rm -rf "$src/tree" && mkdir -p "$src/tree"
  tar -xf "$(ls "$src"/ffmpeg_*.orig.tar.* | head -1)" -C "$src/tree" --strip-components=1
  local demuxers="mov,matroska,avi,mpegts,mxf,m4v,h264,hevc,mjpeg,ivf,image2"
  demuxers+=",image_png_pipe,image_jpeg_pipe,image_tiff_pipe,image_bmp_pipe,image_webp_pipe,image_exr_pipe"
  local decoders="h264,hevc,mpeg4,mpeg1video,mpeg2video,mjpeg,prores,dnxhd,vp8,vp9,dvvideo"
  decoders+=",ffv1,rawvideo,qtrle,h263,png,tiff,bmp,webp,exr"
  local parsers="h264,hevc,mpeg4video,mpegvideo,mjpeg,png,vp8,vp9,bmp,webp,dnxhd"
  (cd "$src/tree" && ./configure --prefix="$dest" --enable-pic --enable-static --disable-shared \
      --disable-programs --disable-doc --disable-network --disable-autodetect \
      --disable-everything --disable-avdevice --disable-avfilter --disable-swresample \
      --disable-postproc --enable-zlib --enable-protocol=file \
      --enable-demuxer="$demuxers" --enable-decoder="$decoders" --enable-parser="$parsers" \
      >"$ROOTS_DIR/ffmpeg-configure.log" 2>&1 \
    && make -j"$(nproc)" >"$ROOTS_DIR/ffmpeg-make.log" 2>&1 && make install >/dev/null 2>&1) \
    || { tail -20 "$ROOTS_DIR/ffmpeg-configure.log" "$ROOTS_DIR/ffmpeg-make.log" >&2; return 1; }
  rm -rf "$src/tree"
  touch "$dest/.done"
}

# A suite's Blender with its whole closure, unpacked (its own loader runs it
# through in_root): trixie's 4.3 (Python 3.13), sid's 5.x (Python 3.14).
ensure_blender_root() {
  local suite="$1" dest="$ROOTS_DIR/$1" d="$ROOTS_DIR/apt-$1"
  if [ -f "$dest/.done" ]; then return; fi
  rm -rf "$dest"
  suite_apt_update "$suite"
  rm -rf "$d/cache/archives"/*.deb
  # patchelf 0.18+ (trixie's) renames symbols for the release packages.
  # sid's Blender 5.x imports cattrs and requests in its extension manager
  # without depending on them (without them no extension installs), and
  # renders only with an EGL (libegl1: Mesa's, software on a machine with no
  # GPU), which a desktop has and a bare root has not. xwd: the window tests'
  # screenshots (Blender's own read-back is black on llvmpipe under Xvfb).
  local extra=()
  [ "$suite" = sid ] && extra=(python3-cattr python3-requests libegl1 libgl1 x11-apps)
  suite_apt "$suite" install -y --download-only blender python3-numpy patchelf "${extra[@]}" >/dev/null
  mkdir -p "$dest"
  local n=0 deb
  for deb in "$d"/cache/archives/*.deb; do dpkg-deb -x "$deb" "$dest"; n=$((n + 1)); done
  for l in bin sbin lib lib64; do
    [ -e "$dest/$l" ] || [ -L "$dest/$l" ] || { mkdir -p "$dest/usr/$l"; ln -s "usr/$l" "$dest/$l"; }
  done
  # What maintainer scripts would do: the BLAS/LAPACK alternatives' links.
  local lib="$dest/usr/lib/x86_64-linux-gnu"
  for so in "$lib"/blas/libblas.so.3 "$lib"/lapack/liblapack.so.3; do
    [ -e "$so" ] && [ ! -e "$lib/$(basename "$so")" ] && ln -s "${so#"$lib/"}" "$lib/$(basename "$so")"
  done
  ln -sf /proc/self/mounts "$dest/etc/mtab"
  mkdir -p "$dest/tmp" "$dest/proc" "$dest/dev" "$dest/work" "$dest/root"
  chmod 1777 "$dest/tmp"
  echo "pkgroots: unpacked $n $suite packages into $dest"
  touch "$dest/.done"
}
ensure_trixie() { ensure_blender_root trixie; }
ensure_sid() { ensure_blender_root sid; }

# Debian 12 with Blender 3.4 and nothing of the build's (no -dev packages,
# no OpenCV, Ceres, ERFA ...), made by debootstrap.
ensure_bookworm() {
  local dest="$ROOTS_DIR/bookworm"
  if [ -f "$dest/.done" ]; then return; fi
  rm -rf "$dest"
  mkdir -p "$ROOTS_DIR/debootstrap-cache"
  debootstrap --variant=minbase --cache-dir="$ROOTS_DIR/debootstrap-cache" \
    bookworm "$dest" "$(debian_mirror)" >"$ROOTS_DIR/bookworm-debootstrap.log" 2>&1 \
    || { tail -20 "$ROOTS_DIR/bookworm-debootstrap.log" >&2; return 1; }
  in_root "$dest" sh -c 'DEBIAN_FRONTEND=noninteractive apt-get install -y -q \
      --no-install-recommends blender python3-numpy && apt-get clean' \
    >"$ROOTS_DIR/bookworm-blender.log" 2>&1 \
    || { tail -20 "$ROOTS_DIR/bookworm-blender.log" >&2; return 1; }
  mkdir -p "$dest/work"
  touch "$dest/.done"
}

# Runs a command chrooted in ROOT with /proc, /dev and the source tree (at
# its own path), in a private mount namespace (the mounts vanish with the
# command). /tmp is its own, unless SUNLAPSE_ROOT_SHARE_TMP=1 shares the
# machine's (an X server's socket and cookie, pytest's folders: the window
# tests). Usage: in_root ROOT CMD...
in_root() {
  local root="$1"; shift
  mkdir -p "$root$_here" "$root/proc" "$root/dev" "$root/tmp"
  unshare --mount --propagation private -- sh -c '
    root="$1"; here="$2"; share="$3"; shift 3
    if [ "$share" = 1 ]; then tmp="mount --rbind /tmp $root/tmp"; else tmp="mount -t tmpfs tmpfs $root/tmp"; fi
    mount -t proc proc "$root/proc" && mount --rbind /dev "$root/dev" &&
    $tmp && mount --bind "$here" "$root$here" &&
    cd / && exec chroot "$root" "$@"' sh "$root" "$_here" "${SUNLAPSE_ROOT_SHARE_TMP:-0}" "$@"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  for what in "$@"; do
    case "$what" in
      py313) ensure_py313 ;;
      py314) ensure_py314 ;;
      trixie) ensure_trixie ;;
      sid) ensure_sid ;;
      bookworm) ensure_bookworm ;;
      ffmpeg) ensure_ffmpeg ;;
      run)  # run NAME CMD...: a command inside a root (e.g. trixie's Blender)
        shift; name="${1:?run needs a root name}"; shift
        in_root "$ROOTS_DIR/$name" "$@"; exit $? ;;
      *) echo "pkgroots: unknown root '$what' (valid: py313, py314, trixie, sid, bookworm, ffmpeg, run)" >&2; exit 2 ;;
    esac
  done
fi
