#!/usr/bin/env bash
# Fuzzes the native frame reader (native/src/video) with libFuzzer, ASan and
# UBSan for a bounded time. Not part of tools/test.sh.
#   bash tools/fuzz-reader.sh [SECONDS]    (default 300)
# Builds build/fuzz/video_reader_fuzz, seeds build/fuzz/seeds with tiny clips
# made by ffmpeg, writes new inputs to build/fuzz/corpus and any crash to
# build/fuzz/crash-*. Exits non-zero when the fuzzer found a crash, a hang
# over 10 s or one allocation over 512 MB (a frame at the reader's size limit
# needs less).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-300}"
out=build/fuzz
mkdir -p "$out/seeds" "$out/corpus"

"$PWD/tools/install.sh" >/dev/null  # the project's packages (FFmpeg, OpenCV)
# Not in tools/install.sh's list: only this script needs them.
if ! command -v clang++-14 >/dev/null ||
  ! ls /usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a \
    >/dev/null 2>&1; then
  echo "fuzz-reader: installing clang 14 with libFuzzer (clang-14, libclang-rt-14-dev)"
  sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  export DEBIAN_FRONTEND=noninteractive
  "${sudo_cmd[@]}" apt-get update -q >/dev/null
  "${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends clang-14 libclang-rt-14-dev \
    >/dev/null || { echo "fuzz-reader: could not install clang-14 libclang-rt-14-dev" >&2; exit 2; }
fi
# Only FFmpeg and OpenCV's core are linked: the reader needs nothing else.
# shellcheck disable=SC2054  # the commas are inside one flag
flags=(-std=c++17 -g -O1 -fno-omit-frame-pointer
  -fsanitize=fuzzer,address,undefined -fno-sanitize-recover=undefined)
# shellcheck disable=SC2046  # pkg-config's flags are meant to split
clang++-14 "${flags[@]}" -Inative/include \
  $(pkg-config --cflags opencv4 libavformat) \
  native/src/video/video_reader_fuzz.cc native/src/video/video_reader.cc \
  native/src/video/image_sequence.cc native/src/video/jpeg_scaled.cc \
  native/src/video/tiff_plain.cc \
  -o "$out/video_reader_fuzz" \
  $(pkg-config --libs libavformat libavcodec libswscale libavutil) \
  $(pkg-config --libs libturbojpeg) -lopencv_imgproc -lopencv_core

# Seeds: 4 frames of 32x24 in every container the target names (the first
# byte picks the extension: 0 .mp4, 1 .mpg, 2 .gif, 3 .png, 4 .jpg, 5 .avi,
# 6 .tif).
seed() {  # index extension ffmpeg-output-args...
  local i="$1" ext="$2"
  shift 2
  local tmp="$out/seeds/tmp$ext"
  ffmpeg -loglevel error -y -f lavfi -i testsrc=size=32x24:rate=4 "$@" "$tmp"
  { printf '%b' "\\x$(printf %02x "$i")"; cat "$tmp"; } >"$out/seeds/seed$ext"
  rm -f "$tmp"
}
seed 0 .mp4 -frames:v 4 -pix_fmt yuv420p -c:v libx264 -g 2
seed 1 .mpg -frames:v 4 -c:v mpeg1video -r 24
seed 2 .gif -frames:v 4
seed 3 .png -frames:v 1
seed 4 .jpg -frames:v 1
seed 5 .avi -frames:v 4 -c:v mjpeg
seed 6 .tif -frames:v 1 -pix_fmt rgb48le -compression_algo raw
# A tiny PNG whose header claims 16000x16000: the reader must refuse it
# without allocating the frame (FFmpeg skips the header CRC by default).
ffmpeg -loglevel error -y -f lavfi -i testsrc=size=8x8 -frames:v 1 "$out/seeds/tmp.png"
{ printf '\x03'; cat "$out/seeds/tmp.png"; } >"$out/seeds/huge.png"
printf '\x00\x00\x3e\x80\x00\x00\x3e\x80' |
  dd of="$out/seeds/huge.png" bs=1 seek=17 conv=notrunc status=none
rm -f "$out/seeds/tmp.png"

log="$out/fuzz.log"
set +e
(cd "$out" && ./video_reader_fuzz -max_total_time="$seconds" \
  -rss_limit_mb=2048 -malloc_limit_mb=512 -timeout=10 -max_len=65536 -print_final_stats=1 \
  corpus seeds) >"$log" 2>&1
status=$?
set -e
runs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || true)
# Findings of this run only (earlier crash files are kept, not counted).
found=$(grep -o 'Test unit written to [^ ]*' "$log" | sed 's/.* //' || true)
echo "fuzz-reader: ${runs:-?} executions in ${seconds} s, exit ${status}," \
  "$(printf '%s' "$found" | grep -c . || true) finding(s)${found:+: $found} (log: $log)"
exit "$status"
