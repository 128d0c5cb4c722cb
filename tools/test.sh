#!/usr/bin/env bash
# Sets everything up (tools/install.sh) and runs every test:
#   house-habit checks (tools/lint.py), GoogleTest (ctest), bpy-free Python
#   tests, tests inside Blender (background) and in a Blender window under Xvfb.
# Ends with one line "tests: N passed, N failed" summed over all runners.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${SUNLAPSE_BUILD_DIR:-$here/build}"
"$here/tools/install.sh"

reports="$build_dir/test-reports"
rm -rf "$reports" && mkdir -p "$reports"
status=0
echo "== Lint"
/usr/bin/python3 "$here/tools/lint.py" --junit "$reports/lint.xml" || status=1
echo "== GoogleTest"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)" \
  --output-junit "$reports/ctest.xml" || status=1
echo "== Python (bpy-free)"
(cd "$here" && /usr/bin/python3 -m pytest -q -p no:cacheprovider \
  --junitxml="$reports/python.xml" tests/python) || status=1
echo "== Blender"
(cd "$here" && blender -b --factory-startup --python-exit-code 1 \
  --python tests/blender/run_pytest.py -- -q --junitxml="$reports/blender.xml" \
  tests/blender) || status=1

echo "== Blender with a window (Xvfb)"
(cd "$here" && /usr/bin/python3 -m pytest -q -p no:cacheprovider \
  --junitxml="$reports/ui.xml" tests/ui) || status=1

/usr/bin/python3 - "$reports" <<'PY'
import glob, sys, xml.etree.ElementTree as ET
passed = failed = skipped = 0
for path in glob.glob(sys.argv[1] + "/*.xml"):
    for case in ET.parse(path).getroot().iter("testcase"):
        kinds = {c.tag for c in case}
        if kinds & {"failure", "error"}:
            failed += 1
        elif "skipped" in kinds:
            skipped += 1
        else:
            passed += 1
print(f"tests: {passed} passed, {failed} failed, {skipped} skipped")
PY
exit $status
