#!/usr/bin/env python3
"""The whole estimate on camera stills (issue 28) against ffmpeg decoding them.

  python3 bench/stills.py [--mp 24] [--length 100] [--quality 3] [--grain 12]
                          [--cache DIR] [--blender PATH] [--runs 1]

A JPEG sequence like a camera's time-lapse: bench/whole_run.py's 1080p plaza
clip (made with it first when missing) upscaled to --mp megapixels (16:9),
film grain added (ffmpeg's noise filter, --grain), written at JPEG quality
--quality (ffmpeg's -q:v: 2 best, 31 worst; 3 is about a camera's "fine"),
--length frames; the scene re-saved for it. Both cached in CACHE (default
build/whole-run-cache/).

It prints, for the same sequence:
  ffmpeg       `ffmpeg -i SEQ/IMG_%04d.jpg -f null -`: every frame decoded at
               full size, once (what a user compares with);
  estimate     `blender -b ... examples/run_estimate.py -- --out T.json`, as a
               user runs it: its wall time, and the track's total_s;
  ratio        ffmpeg's wall time / the estimate's (>= 1: the estimate keeps
               up with decoding the stills; issue 28's target is 1.5).
Each figure is the best of --runs runs. Figures only: exit code 0 whatever
they are. Not part of tools/test.sh.
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import whole_run  # noqa: E402

TARGET_RATIO = 1.5


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--mp", type=float, default=24.0, help="megapixels a frame (default 24)")
    p.add_argument("--length", type=int, default=100, help="frames (default 100)")
    p.add_argument("--quality", type=int, default=3, help="ffmpeg -q:v (default 3)")
    p.add_argument("--grain", type=int, default=12, help="noise strength (default 12)")
    p.add_argument("--cache", default=os.path.join(whole_run.ROOT, "build", "whole-run-cache"))
    p.add_argument("--blender", default="blender")
    p.add_argument("--runs", type=int, default=1, help="runs of each command (best kept)")
    args = p.parse_args(argv)
    if not (1 <= args.mp <= 60 and 2 <= args.length <= 100000 and 2 <= args.quality <= 31
            and 0 <= args.grain <= 100 and args.runs >= 1):
        p.error("--mp in [1, 60], --length >= 2, --quality in [2, 31], --grain in [0, 100], "
                "--runs >= 1")
    return args


def stills_size(mp):
    """16:9, even sides, about `mp` megapixels."""
    h = int((mp * 1e6 * 9 / 16) ** 0.5) // 2 * 2
    return h * 16 // 9 // 2 * 2, h


def make_stills(args, cache):
    """The JPEG sequence (cached): returns the first file's path."""
    w, h = stills_size(args.mp)
    folder = os.path.join(cache, f"stills-{w}x{h}-{args.length}-q{args.quality}-n{args.grain}")
    first = os.path.join(folder, "IMG_0001.jpg")
    last = os.path.join(folder, f"IMG_{args.length:04d}.jpg")
    if os.path.exists(last):
        return first, (w, h)
    frames = whole_run.source_frames(whole_run.find_scene(argparse.Namespace(
        scene=None, blender=args.blender), cache), cache)
    clip = whole_run.make_clip(frames, max(args.length, 2), (1920, 1080), cache)
    os.makedirs(folder, exist_ok=True)
    print(f"writing {args.length} JPEG stills of {w}x{h} (once; cached in {folder})",
          flush=True)
    subprocess.run(["ffmpeg", "-nostdin", "-y", "-loglevel", "error", "-i", clip,
                    "-frames:v", str(args.length), "-vf",
                    f"scale={w}:{h}:flags=lanczos,noise=alls={args.grain}:allf=t",
                    "-q:v", str(args.quality), "-start_number", "1",
                    os.path.join(folder, "IMG_%04d.jpg")], check=True)
    return first, (w, h)


def best_wall(cmd, runs, log):
    best = None
    for _ in range(runs):
        rc, wall, rss = whole_run.run_measured(cmd, log)
        if rc != 0:
            raise whole_run.BenchError(f"{cmd[0]} failed (exit {rc}): "
                                       f"{whole_run.last_error(log)}")
        best = (wall, rss) if best is None or wall < best[0] else best
    return best


def main(argv=None):
    args = parse_args(argv)
    cache = os.path.abspath(args.cache)
    for sub in ("logs", "tracks"):
        os.makedirs(os.path.join(cache, sub), exist_ok=True)
    print(whole_run.header(), flush=True)
    first, size = make_stills(args, cache)
    scene_dir = whole_run.find_scene(argparse.Namespace(scene=None, blender=args.blender), cache)
    blend, info = whole_run.make_blend(args.blender, os.path.join(scene_dir, "scene.blend"),
                                       first, size, cache)
    n = info.get("frame_duration")
    seq = os.path.join(os.path.dirname(first), "IMG_%04d.jpg")
    mb = sum(os.path.getsize(os.path.join(os.path.dirname(first), f))
             for f in os.listdir(os.path.dirname(first))) / 1e6
    print(f"\n== {n} JPEG stills of {size[0]}x{size[1]} ({mb / max(1, n):.1f} MB a frame)",
          flush=True)
    t0 = time.perf_counter()
    ff_wall, _ = best_wall(["ffmpeg", "-nostdin", "-loglevel", "error", "-i", seq, "-f", "null",
                            "-"], args.runs, os.path.join(cache, "logs", "stills-ffmpeg.log"))
    track = os.path.join(cache, "tracks", "stills.sun.json")
    est_wall, rss = best_wall(whole_run.estimate_command(args.blender, blend, track), args.runs,
                              os.path.join(cache, "logs", "stills-estimate.log"))
    with open(track) as fh:
        est = json.load(fh)
    timing = est.get("timing") or est.get("extra", {}).get("timing") or {}
    done = sum(1 for f in est.get("frames", []) if f.get("zenith_deg") is not None)
    print(f"  ffmpeg -i ... -f null -   {ff_wall:7.2f} s  ({n / ff_wall:.1f} frames/s)")
    print(f"  estimate (wall)           {est_wall:7.2f} s  ({n / est_wall:.1f} frames/s), "
          f"total_s {timing.get('total_s', float('nan')):.2f} s, {done}/{n} frames estimated, "
          f"peak {rss:.0f} MB")
    ratio = ff_wall / est_wall
    print(f"  ratio (ffmpeg / estimate) {ratio:7.2f}x  (issue 28's target {TARGET_RATIO}x: "
          f"{'met' if ratio >= TARGET_RATIO else 'not met'})")
    for key in ("table_s", "reference_s", "decode_wait_s", "tracker_start_s", "prior_s"):
        if isinstance(timing.get(key), (int, float)):
            print(f"    {key:22s} {timing[key]:.2f} s")
    print(f"  ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
