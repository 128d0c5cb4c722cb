#!/usr/bin/env bash
# Sets everything up (tools/install.sh) and runs the main job on the bundled
# demo: render a small preset with a known Sun, run the scripted estimate on
# it exactly as a user would, and print the accuracy report.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${SUNLAPSE_BUILD_DIR:-$here/build}"
"$here/tools/install.sh"
/usr/bin/python3 "$here/bench/accuracy.py" --presets "${SUNLAPSE_DEMO_PRESET:-plaza}" \
  --size small --out "$build_dir/demo" "$@"
