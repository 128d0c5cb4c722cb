"""The AR light measured on large stills against the same footage at the
suite's size (issue 25's per-frame light, on the 20-45 MP JPEG sequences of
issue 28):

  /usr/bin/python3 bench/ar_light_stills.py [--scenes twilight3,twilight4,overcast2]
      [--suite-cache DIR] [--stills-cache DIR] [--root TREE]

For each scene, Set Up AR Render's light measurement (the footage's shadow
over the lit ground beside it, per frame; bench/blender_light.py) runs twice
in Blender: on the scene's own 320x180 clip (bench/suite.py's cache) and on
the same clip as 24 MP JPEG stills with film grain (bench/suite_stills.py's
cache: run `python3 bench/suite_stills.py --scenes KEYS` first). The stills
are the clip enlarged, so a measure that does not depend on the footage's
size gives the same ratios. Prints per scene the frames measured on both,
how many agree within 0.05 (the largest channel difference), the median,
90th percentile and largest difference and the seconds each measurement
took; then the totals. --root measures with the add-on of another tree (a
checkout of an earlier commit, for a before/after; its addon/ needs a built
_native). Figures only: exit 0 whatever they are (1 when a scene or its
stills are missing).
"""
import argparse
import json
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from ar_light import BLENDER_ENV, ROOT, TOLERANCE  # noqa: E402  (bench/ar_light.py's)


def measure(blend, root):
    proc = subprocess.run(
        ["nice", "-n", "10", "blender", "-b", "--factory-startup", blend, "--python-exit-code",
         "1", "--python", os.path.join(ROOT, "bench", "blender_light.py"), "--", root],
        capture_output=True, text=True, env=BLENDER_ENV)
    for line in proc.stdout.splitlines():
        if line.startswith("LIGHT "):
            return json.loads(line[len("LIGHT "):]), None
    return None, (proc.stderr or proc.stdout)[-1500:]


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenes", default="twilight3,twilight4,overcast2",
                   help="comma-separated suite keys")
    p.add_argument("--suite-cache", default=os.environ.get(
        "SUNLAPSE_SUITE_CACHE", os.path.join(ROOT, "build", "suite-cache")),
        help="bench/suite.py's render cache")
    p.add_argument("--stills-cache", default=os.path.join(ROOT, "build", "suite-stills-cache"),
                   help="bench/suite_stills.py's cache (its --cache)")
    p.add_argument("--root", default=ROOT, help="the tree whose add-on measures")
    args = p.parse_args(argv)
    keys = [k.strip() for k in args.scenes.split(",") if k.strip()]
    total, within, all_diffs = 0, 0, []
    for key in keys:
        clip_blend = os.path.join(args.suite_cache, key, "scene.blend")
        stills_blend = os.path.join(args.stills_cache, key, "scene", "scene.blend")
        for path, how in ((clip_blend, "python3 bench/suite.py --seeds KEY --render-only"),
                          (stills_blend, "python3 bench/suite_stills.py --scenes KEY")):
            if not os.path.isfile(path):
                print(f"{key}: {path} is missing (make it with {how.replace('KEY', key)})")
                return 1
        clip, err = measure(clip_blend, args.root)
        stills, err2 = (None, None) if clip is None else measure(stills_blend, args.root)
        if clip is None or stills is None:
            print(f"{key}: Blender failed: {err or err2}")
            continue
        diffs = [max(abs(a - b) for a, b in zip(r, stills["ratios"][f]))
                 for f, r in clip["ratios"].items()
                 if r is not None and stills["ratios"].get(f) is not None]
        if not diffs:
            print(f"{key}: no frame measured on both")
            continue
        d = np.array(diffs)
        ok = int(np.sum(d <= TOLERANCE))
        total, within = total + len(d), within + ok
        all_diffs += diffs
        print(f"{key}: {ok}/{len(d)} frames within {TOLERANCE}; median {np.median(d):.3f}, "
              f"p90 {np.quantile(d, 0.9):.3f}, max {d.max():.3f}; measured in "
              f"{clip['seconds']:.1f} s (clip) and {stills['seconds']:.1f} s (stills)")
    if all_diffs:
        d = np.array(all_diffs)
        print(f"ALL: {within}/{total} frames within {TOLERANCE}; median {np.median(d):.3f}, "
              f"p90 {np.quantile(d, 0.9):.3f}, max {d.max():.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
