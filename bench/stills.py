#!/usr/bin/env python3
"""The whole estimate on camera stills and intra-only video (issue 28)
against ffmpeg decoding them.

  python3 bench/stills.py [--format jpeg|tiff|prores] [--mp MP] [--any-size] [--length 100]
                          [--quality 3] [--grain 12] [--cache DIR]
                          [--blender PATH] [--runs 1]

A sequence like a camera's time-lapse: bench/whole_run.py's 1080p plaza clip
(made with it first when missing) upscaled to --mp megapixels (16:9; both
sides multiples of 8 as a camera's, unless --any-size), film
grain added (ffmpeg's noise filter, --grain), --length frames, written as
  jpeg    JPEG stills at quality --quality (ffmpeg's -q:v: 2 best, 31 worst;
          3 is about a camera's "fine"); --mp default 24;
  tiff    16-bit RGB TIFF stills, uncompressed (a raw converter's export);
          --mp default 8.3 (3840x2160);
  prores  one ProRes 422 HQ movie (10-bit 4:2:2, an intra-only codec: every
          frame stands alone); --mp default 8.3 (3840x2160);
and the scene re-saved for it. Both cached in CACHE (default
build/whole-run-cache/).

It prints, for the same sequence:
  ffmpeg       `ffmpeg -i SEQ/IMG_%04d.jpg -f null -`: every frame decoded at
               full size, once (what a user compares with; on a movie
               `ffmpeg -i CLIP.mov -f null -`);
  estimate     `blender -b ... examples/run_estimate.py -- --out T.json`, as a
               user runs it: its wall time, and the track's total_s;
  ratio        ffmpeg's wall time / the estimate's (>= 1: the estimate keeps
               up with decoding the stills; issue 28's targets: 1.5 for
               JPEG, 1.0 for TIFF and ProRes).
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

# Issue 28's targets: the whole estimate's throughput against ffmpeg's full
# decode; JPEG stills can be decoded reduced, TIFF and ProRes cannot.
TARGET_RATIO = {"jpeg": 1.5, "tiff": 1.0, "prores": 1.0}
DEFAULT_MP = {"jpeg": 24.0, "tiff": 8.3, "prores": 8.3}


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--format", choices=sorted(TARGET_RATIO), default="jpeg",
                   help="jpeg (default), tiff (16-bit stills) or prores (a 4:2:2 movie)")
    p.add_argument("--mp", type=float, help="megapixels a frame (default 24 for jpeg, 8.3: "
                                            "3840x2160 for tiff and prores)")
    p.add_argument("--any-size", action="store_true",
                   help="keep --mp's size with even sides (default: both sides multiples of "
                        "8, as cameras write them)")
    p.add_argument("--length", type=int, default=100, help="frames (default 100)")
    p.add_argument("--quality", type=int, default=3, help="ffmpeg -q:v (default 3)")
    p.add_argument("--grain", type=int, default=12, help="noise strength (default 12)")
    p.add_argument("--cache", default=os.path.join(whole_run.ROOT, "build", "whole-run-cache"))
    p.add_argument("--blender", default="blender")
    p.add_argument("--runs", type=int, default=1, help="runs of each command (best kept)")
    args = p.parse_args(argv)
    if args.mp is None:
        args.mp = DEFAULT_MP[args.format]
    if not (1 <= args.mp <= 60 and 2 <= args.length <= 100000 and 2 <= args.quality <= 31
            and 0 <= args.grain <= 100 and args.runs >= 1):
        p.error("--mp in [1, 60], --length >= 2, --quality in [2, 31], --grain in [0, 100], "
                "--runs >= 1")
    return args


def stills_size(mp, any_size=False):
    """16:9, about `mp` megapixels, both sides multiples of 8 as cameras
    write them (JPEG's 8x8 blocks: 24 MP is 6528x3672); with `any_size`
    even sides only (24 MP: 6530x3674, which no camera writes and whose
    working pixels cut through the blocks, so its JPEGs are decoded whole)."""
    step = 2 if any_size else 8
    h = int((mp * 1e6 * 9 / 16) ** 0.5) // step * step
    return h * 16 // 9 // step * step, h


# How each format is written: the name (a printf pattern for stills) and
# ffmpeg's output options.
FORMATS = {
    "jpeg": ("IMG_%04d.jpg", lambda a: ["-q:v", str(a.quality), "-start_number", "1"]),
    "tiff": ("TIF_%04d.tif", lambda a: ["-pix_fmt", "rgb48le", "-compression_algo", "raw",
                                        "-start_number", "1"]),
    "prores": ("clip-prores.mov", lambda a: ["-c:v", "prores_ks", "-profile:v", "3",
                                             "-pix_fmt", "yuv422p10le"]),
}


def make_stills(args, cache):
    """The sequence or movie (cached): returns (the path the clip opens,
    the path ffmpeg reads, size)."""
    w, h = stills_size(args.mp, args.any_size)
    name, output = FORMATS[args.format]
    quality = f"-q{args.quality}" if args.format == "jpeg" else ""
    folder = os.path.join(cache, f"{args.format}-{w}x{h}-{args.length}{quality}-n{args.grain}")
    target = os.path.join(folder, name)
    first = target % 1 if "%" in name else target
    done = os.path.join(folder, "complete")
    if not os.path.exists(done):
        frames = whole_run.source_frames(whole_run.find_scene(argparse.Namespace(
            scene=None, blender=args.blender), cache), cache)
        clip = whole_run.make_clip(frames, max(args.length, 2), (1920, 1080), cache)
        os.makedirs(folder, exist_ok=True)
        print(f"writing {args.length} frames of {w}x{h} as {args.format} (once; cached in "
              f"{folder})", flush=True)
        subprocess.run(["ffmpeg", "-nostdin", "-y", "-loglevel", "error", "-i", clip,
                        "-frames:v", str(args.length), "-vf",
                        f"scale={w}:{h}:flags=lanczos,noise=alls={args.grain}:allf=t",
                        *output(args), target], check=True)
        open(done, "w").close()
    return first, target, (w, h)


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
    first, seq, size = make_stills(args, cache)
    scene_dir = whole_run.find_scene(argparse.Namespace(scene=None, blender=args.blender), cache)
    blend, info = whole_run.make_blend(args.blender, os.path.join(scene_dir, "scene.blend"),
                                       first, size, cache)
    n = info.get("frame_duration")
    mb = sum(os.path.getsize(os.path.join(os.path.dirname(first), f))
             for f in os.listdir(os.path.dirname(first))) / 1e6
    print(f"\n== {n} frames of {size[0]}x{size[1]} as {args.format} ({mb / max(1, n):.1f} MB "
          f"a frame)", flush=True)
    t0 = time.perf_counter()
    ff_log = os.path.join(cache, "logs", f"{args.format}-ffmpeg.log")
    ff_wall, _ = best_wall(["ffmpeg", "-nostdin", "-loglevel", "error", "-i", seq, "-f", "null",
                            "-"], args.runs, ff_log)
    track = os.path.join(cache, "tracks", f"{args.format}.sun.json")
    est_wall, rss = best_wall(whole_run.estimate_command(args.blender, blend, track), args.runs,
                              os.path.join(cache, "logs", f"{args.format}-estimate.log"))
    with open(track) as fh:
        est = json.load(fh)
    timing = est.get("timing") or est.get("extra", {}).get("timing") or {}
    done = sum(1 for f in est.get("frames", []) if f.get("zenith_deg") is not None)
    print(f"  ffmpeg -i ... -f null -   {ff_wall:7.2f} s  ({n / ff_wall:.1f} frames/s)")
    print(f"  estimate (wall)           {est_wall:7.2f} s  ({n / est_wall:.1f} frames/s), "
          f"total_s {timing.get('total_s', float('nan')):.2f} s, {done}/{n} frames estimated, "
          f"peak {rss:.0f} MB")
    ratio = ff_wall / est_wall
    target = TARGET_RATIO[args.format]
    print(f"  ratio (ffmpeg / estimate) {ratio:7.2f}x  (issue 28's target {target}x: "
          f"{'met' if ratio >= target else 'not met'})")
    for key in ("table_s", "reference_s", "decode_wait_s", "tracker_start_s", "prior_s"):
        if isinstance(timing.get(key), (int, float)):
            print(f"    {key:22s} {timing[key]:.2f} s")
    print(f"  ({time.perf_counter() - t0:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
