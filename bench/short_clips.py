"""Short runs of the suite's scenes: each scene estimated on a few of its
frames only (`--frames A:B`), as a user tries a clip on a handful of frames,
and its frames scored against the truth.

  python3 bench/short_clips.py [--cache DIR] [--lengths 1,2,3,5] [--starts 1,9,17,25]
                               [--scenes 1,2,twilight1 ...] [--out FIGURES.json]

For every scene of bench/suite.py's cache (rendered there first), every
length N and every start S, runs
  blender -b CACHE/<key>/scene.blend --python examples/run_estimate.py -- --out T --frames S:S+N-1
and prints, per length, how many of the frames with the Sun at least 4 deg up
got a Sun, how many are within 2 deg, and how many are more than 5 deg off at
confidence >= 0.5 (issue 25's bound; the whole clips have none). Directions
are compared in the world frame (each file's north offset), as bench/suite.py
does.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "addon"))

from core import angles, evaluation  # noqa: E402  (bpy-free)

JUDGED_MIN_ELEVATION_DEG = 4.0


def _numbers(text):
    return [int(v) for v in text.split(",") if v.strip()]


def _world(frame, north):
    return evaluation.direction(frame["zenith_deg"], frame["azimuth_deg"] + north)


def run_scene(folder, start, length, blender):
    """The run's track JSON for frames start..start+length-1, or None."""
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "short.sun.json")
        r = subprocess.run([blender, "-b", "--factory-startup", os.path.join(folder, "scene.blend"),
                            "--python-exit-code", "1", "--python",
                            os.path.join(ROOT, "examples", "run_estimate.py"), "--",
                            "--out", out, "--frames", f"{start}:{start + length - 1}"],
                           capture_output=True, text=True)
        if r.returncode != 0 or not os.path.exists(out):
            return None
        with open(out) as fh:
            return json.load(fh)


def score(track, truth):
    """[(error deg or None, confidence)] of the run's judged frames."""
    by_frame = {f["frame"]: f for f in truth["frames"]}
    north_t = truth.get("north_offset_deg") or 0.0
    north = track.get("north_offset_deg") or 0.0
    out = []
    for f in track["frames"]:
        t = by_frame.get(f["frame"])
        if t is None or t.get("zenith_deg") is None or \
                90.0 - t["zenith_deg"] < JUDGED_MIN_ELEVATION_DEG:
            continue
        if f.get("zenith_deg") is None:
            out.append((None, f.get("confidence") or 0.0))
            continue
        off = angles.angle_between_deg(_world(f, north), _world(t, north_t))
        out.append((off, f["confidence"]))
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--cache", default=os.environ.get("SUNLAPSE_SUITE_CACHE",
                                                     os.path.join(ROOT, "build", "suite-cache")),
                   help="bench/suite.py's rendered scenes (default build/suite-cache)")
    p.add_argument("--lengths", default="1,2,3,5", help="frames per run (default 1,2,3,5)")
    p.add_argument("--starts", default="1,9,17,25", help="first frames (default 1,9,17,25)")
    p.add_argument("--scenes", help="comma-separated scene keys (default: every cached scene)")
    p.add_argument("--blender", default="blender")
    p.add_argument("--out", help="write every frame's (scene, start, length, error, "
                                 "confidence) here as JSON")
    args = p.parse_args(argv)
    try:
        lengths, starts = _numbers(args.lengths), _numbers(args.starts)
    except ValueError:
        p.error("--lengths and --starts take comma-separated integers")
    if not lengths or min(lengths) < 1 or not starts or min(starts) < 1:
        p.error("--lengths and --starts must be positive")
    if not os.path.isdir(args.cache):
        p.error(f"--cache {args.cache}: no such folder (render it with bench/suite.py)")
    keys = args.scenes.split(",") if args.scenes else sorted(os.listdir(args.cache))
    keys = [k for k in keys if os.path.exists(os.path.join(args.cache, k, "cache_key"))]
    rows = []
    for n in lengths:
        for key in keys:
            folder = os.path.join(args.cache, key)
            with open(os.path.join(folder, "truth.sun.json")) as fh:
                truth = json.load(fh)
            for s in starts:
                if s + n - 1 > len(truth["frames"]):
                    continue
                track = run_scene(folder, s, n, args.blender)
                if track is None:
                    print(f"{key} {s}:{s + n - 1}: the run failed")
                    continue
                cells = score(track, truth)
                rows += [dict(scene=key, start=s, length=n, error_deg=e, confidence=c)
                         for e, c in cells]
                shown = " ".join("-" if e is None else f"{e:.1f}@{c:.2f}" for e, c in cells)
                print(f"{key} {s}:{s + n - 1}  {shown}", flush=True)
    print("\nlength  judged  with a Sun  within 2 deg  >5 deg at >= 0.5")
    for n in lengths:
        mine = [r for r in rows if r["length"] == n]
        sun = [r for r in mine if r["error_deg"] is not None]
        print(f"{n:>6}  {len(mine):>6}  {len(sun):>10}  {sum(r['error_deg'] <= 2 for r in sun):>12}"
              f"  {sum(r['error_deg'] > 5 and r['confidence'] >= 0.5 for r in sun):>16}")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(rows, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
