#!/usr/bin/env bash
# Sets up a Debian 12 machine for sunlapse and builds it. Idempotent: packages
# already installed are skipped and the CMake build is incremental.
#   tools/install.sh            install what is missing, configure, build
#   SUNLAPSE_BUILD_DIR=dir      build somewhere other than ./build
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${SUNLAPSE_BUILD_DIR:-$here/build}"

packages=(
  build-essential cmake ninja-build pkg-config
  libopencv-dev libeigen3-dev libceres-dev libembree-dev libtbb-dev
  liberfa-dev pybind11-dev libgtest-dev libgmock-dev
  libavformat-dev libavcodec-dev libavutil-dev libswscale-dev libturbojpeg0-dev
  patchelf debootstrap nasm unzip ccache
  python3-dev python3-numpy python3-pytest python3-matplotlib python3-hypothesis python3-pil
  blender ffmpeg xvfb xauth
  clang-format python3-flake8 mypy
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" \
    || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "[install] installing: ${missing[*]}"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -q
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
else
  echo "[install] all Debian packages present"
fi

# Blender 3.4 on Debian runs on the system Python; build the module for it,
# never for a python3 that happens to be first on PATH (pyenv, venv, conda).
cmake -S "$here" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DPython_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
echo "[install] built in $build_dir"
