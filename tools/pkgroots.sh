#!/usr/bin/env bash
# Foreign Debian roots for the release build and the package tests, all under
# the build folder (downloads cached there; the system's apt state is never
# touched). Sourced by tools/release.sh and tools/test-packages.sh, or run:
#   bash tools/pkgroots.sh py313      Python 3.13 headers + pybind11 (trixie)
#   bash tools/pkgroots.sh trixie     Blender 4.3 + its closure, unpacked
#   bash tools/pkgroots.sh bookworm   a debootstrap root with only Blender 3.4
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

# apt with a private state (lists, cache, an empty dpkg status) for trixie.
_trixie_apt_dir="$ROOTS_DIR/apt-trixie"
trixie_apt() {
  local d="$_trixie_apt_dir"
  apt-get -q -o Dir::State="$d/state" -o Dir::State::status="$d/state/status" \
    -o Dir::Cache="$d/cache" -o Dir::Etc::SourceList="$d/sources.list" \
    -o Dir::Etc::SourceParts="$d/none" -o Dir::Etc::Preferences="$d/none/prefs" \
    -o Dir::Etc::PreferencesParts="$d/none" -o APT::Architecture=amd64 \
    -o APT::Architectures::=amd64 -o Acquire::Languages=none \
    -o APT::Install-Recommends=false -o Debug::NoLocking=true "$@"
}

trixie_apt_update() {
  local d="$_trixie_apt_dir"
  mkdir -p "$d/state/lists/partial" "$d/cache/archives/partial" "$d/none"
  : >"$d/state/status"
  echo "deb [signed-by=/usr/share/keyrings/debian-archive-keyring.gpg] $(debian_mirror) trixie main" \
    >"$d/sources.list"
  if [ ! -f "$d/updated" ] || [ -n "$(find "$d/updated" -mtime +7)" ]; then
    trixie_apt update >/dev/null && touch "$d/updated"
  fi
}

# Python 3.13 headers and a pybind11 that knows 3.13, for the second module.
ensure_py313() {
  local dest="$ROOTS_DIR/py313"
  if [ -f "$dest/.done" ]; then return; fi
  trixie_apt_update
  rm -rf "$dest" && mkdir -p "$dest/debs"
  (cd "$dest/debs" && trixie_apt download libpython3.13-dev pybind11-dev >/dev/null)
  for deb in "$dest"/debs/*.deb; do dpkg-deb -x "$deb" "$dest"; done
  test -f "$dest/usr/include/python3.13/Python.h"
  test -f "$dest/usr/include/pybind11/pybind11.h"
  touch "$dest/.done"
}

# Blender 4.3 (Python 3.13) with its whole closure, from trixie, unpacked.
ensure_trixie() {
  local dest="$ROOTS_DIR/trixie"
  if [ -f "$dest/.done" ]; then return; fi
  rm -rf "$dest"
  local d="$_trixie_apt_dir"
  trixie_apt_update
  rm -rf "$d/cache/archives"/*.deb
  trixie_apt install -y --download-only blender python3-numpy >/dev/null
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
  mkdir -p "$dest/tmp" "$dest/proc" "$dest/dev" "$dest/work" "$dest/root"
  chmod 1777 "$dest/tmp"
  echo "pkgroots: unpacked $n trixie packages into $dest"
  touch "$dest/.done"
}

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

# Runs a command chrooted in ROOT with /proc and /dev, in a private mount
# namespace (the mounts vanish with the command). Usage: in_root ROOT CMD...
in_root() {
  local root="$1"; shift
  unshare --mount --propagation private -- sh -c '
    root="$1"; shift
    mount -t proc proc "$root/proc" && mount --rbind /dev "$root/dev" &&
    mount -t tmpfs tmpfs "$root/tmp" && exec chroot "$root" "$@"' sh "$root" "$@"
}

if [ "${BASH_SOURCE[0]}" = "$0" ]; then
  for what in "$@"; do
    case "$what" in
      py313) ensure_py313 ;;
      trixie) ensure_trixie ;;
      bookworm) ensure_bookworm ;;
      *) echo "pkgroots: unknown root '$what' (valid: py313, trixie, bookworm)" >&2; exit 2 ;;
    esac
  done
fi
