#!/usr/bin/env python3
"""A moving camera's cost (issue 26): the whole estimate on a moving-camera
clip against the same clip with the camera held still.

  python3 bench/moving_run.py [--scene DIR] [--size 1080] [--length 300]
                              [--cache DIR] [--blender PATH] [--out FIGURES.json]

The scene is a moving member of the randomised suite (default: moving2 in
bench/suite.py's cache, $SUNLAPSE_SUITE_CACHE or build/suite-cache; render it
with `python3 bench/suite.py --seeds moving2 --render-only`): its frames
played forward then backward to --length and upscaled to --size as
bench/whole_run.py makes its clips, with the scene.blend re-saved for it
and the camera keyed on every frame as the clip's frames were shot (the
solve's keys of the source frame each shows); and the same scene rendered
once more from a tripod (generate_scene.py --still-camera, into CACHE), made
into a clip the same way, its camera still: "moving" and "still". Both are
estimated as a user runs it (examples/run_estimate.py in blender -b);
printed: total_s, per-frame cost, the warp's time (timing.warp_s), the cost
ratio moving / still (target <= 1.5) and each run's direction error against
the truth on the frames the Sun is at least 4 deg up. (The clip plays its
frames forward and back, so the Sun turns back: the errors are a check
that the runs worked, not the estimate's accuracy.)

Figures only: the exit code is 0 whatever they are. Not part of
tools/test.sh. Clips and .blends are cached in CACHE (default
build/whole-run-cache/).
"""
import argparse
import json
import math
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "bench"))
sys.path.insert(0, os.path.join(ROOT, "addon"))

import whole_run  # noqa: E402
from core import evaluation, trackfile  # noqa: E402

TARGET_RATIO = 1.5
SIZES = {720: (1280, 720), 1080: (1920, 1080), 2160: (3840, 2160)}

# Run inside Blender on the scene's scene.blend before whole_run's
# PREPARE_BLEND (which sets the clip and the render size and saves): a
# moving camera keyed per new frame from the source frame it shows (argv:
# PREPARE_BLEND's five, then the source frames as JSON and "moving" or
# "still"; a still twin's camera has no keys).
KEY_CAMERA = '''\
import json
import sys

import bpy

shows, mode = json.loads(sys.argv[-2]), sys.argv[-1]
scene, cam = bpy.context.scene, bpy.context.scene.camera
poses = {}
for f in sorted(set(shows)):
    scene.frame_set(f + 1)
    poses[f] = (tuple(cam.location), tuple(cam.rotation_euler))
if mode == "moving":
    cam.animation_data_clear()
    for i, f in enumerate(shows):
        cam.location, cam.rotation_euler = poses[f]
        cam.keyframe_insert("location", frame=i + 1)
        cam.keyframe_insert("rotation_euler", frame=i + 1)
'''
PREPARE = KEY_CAMERA + whole_run.PREPARE_BLEND


def parse_args(argv):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    suite_cache = os.environ.get("SUNLAPSE_SUITE_CACHE",
                                 os.path.join(ROOT, "build", "suite-cache"))
    p.add_argument("--scene", default=os.path.join(suite_cache, "moving2"),
                   help="a rendered moving member of the suite (default: moving2 in the "
                        "suite's cache)")
    p.add_argument("--size", type=int, default=1080, choices=sorted(SIZES),
                   help="clip height: 720, 1080 or 2160 (default 1080)")
    p.add_argument("--length", type=whole_run.parse_length, default=300,
                   help="frames in the clip (default 300)")
    p.add_argument("--cache", default=os.path.join(ROOT, "build", "whole-run-cache"),
                   help="clips and scenes (default build/whole-run-cache)")
    p.add_argument("--blender", default="blender", help="the Blender command (default blender)")
    p.add_argument("--out", help="write the figures to this JSON file too")
    args = p.parse_args(argv)
    for name in ("scene.blend", "truth.sun.json"):
        if not os.path.exists(os.path.join(args.scene, name)):
            p.error(f"--scene {args.scene} has no {name}: render a moving member with "
                    f"python3 bench/suite.py --seeds moving2 --render-only")
    return args


def still_twin(args):
    """The scene rendered from a tripod (generate_scene.py --still-camera),
    once, into CACHE."""
    spec_path = os.path.join(args.scene, "spec.json")
    with open(spec_path) as fh:
        key_name = json.load(fh)["key"]
    out = os.path.join(args.cache, f"still-{key_name}")
    key = {"spec": whole_run.stamp(spec_path)}
    marker = os.path.join(out, "done")
    if not whole_run.cached(marker, key):
        print(f"rendering {key_name} from a tripod (once; cached in {out})", flush=True)
        log = os.path.join(args.cache, "logs", f"render-still-{key_name}.log")
        rc = whole_run.run_logged(
            [args.blender, "-b", "--factory-startup", "--python-exit-code", "1", "--python",
             os.path.join(ROOT, "examples", "generate_scene.py"), "--", "--random", key_name,
             "--still-camera", "--out", out], log)
        if rc != 0:
            raise SystemExit(f"moving_run: error: rendering the still twin failed: "
                             f"{whole_run.last_error(log)}")
        open(marker, "w").close()
        whole_run.remember(marker, key)
    return out


def prepare(args, scene, clip, shows, mode):
    w, h = SIZES[args.size]
    path = os.path.join(args.cache, f"moving-{os.path.basename(args.scene)}-{h}-"
                                    f"{args.length}-{mode}.blend")
    key = {"scene": whole_run.stamp(os.path.join(scene, "scene.blend")),
           "clip": whole_run.stamp(clip), "mode": mode, "script": PREPARE}
    if not whole_run.cached(path, key):
        script = os.path.join(args.cache, "prepare_moving.py")
        with open(script, "w") as fh:
            fh.write(PREPARE)
        log = os.path.join(args.cache, "logs", f"prepare-moving-{mode}.log")
        rc = whole_run.run_logged(
            [args.blender, "-b", "--factory-startup", os.path.join(scene, "scene.blend"),
             "--python-exit-code", "1", "--python", script, "--", clip, str(w), str(h), path,
             path + ".clip.json", json.dumps(shows), mode], log)
        if rc != 0:
            raise SystemExit(f"moving_run: error: re-saving the scene failed: "
                             f"{whole_run.last_error(log)}")
        whole_run.remember(path, key)
    return path


def errors_deg(track_path, truth, shows):
    """Direction errors (deg) of the moving run's frames with a Sun of their
    own, where the truth's Sun is at least 4 deg up."""
    track = trackfile.read_track(track_path)
    out = []
    for f in track.frames:
        t = truth.frames[shows[f.frame - 1]]
        if f.zenith_deg is None or f.predicted or t.zenith_deg > 86.0:
            continue
        a = evaluation.direction(f.zenith_deg, f.azimuth_deg + track.north_offset_deg)
        b = evaluation.direction(t.zenith_deg, t.azimuth_deg + truth.north_offset_deg)
        out.append(math.degrees(math.acos(min(1.0, sum(x * y for x, y in zip(a, b))))))
    return out


def main(argv=None):
    args = parse_args(argv)
    os.makedirs(os.path.join(args.cache, "logs"), exist_ok=True)
    os.makedirs(os.path.join(args.cache, "tracks"), exist_ok=True)
    truth = trackfile.read_track(os.path.join(args.scene, "truth.sun.json"))
    figures = {"scene": args.scene, "size": SIZES[args.size], "length": args.length}
    for mode in ("still", "moving"):
        scene = args.scene if mode == "moving" else still_twin(args)
        frames = whole_run.source_frames(scene, args.cache)
        shows = whole_run.pingpong(len(frames), args.length)
        clip = whole_run.make_clip(frames, args.length, SIZES[args.size], args.cache,
                                   tag=f"{os.path.basename(scene)}-")
        blend = prepare(args, scene, clip, shows, mode)
        est = whole_run.measure_estimate(args.blender, blend, f"moving-{mode}", args.cache)
        t = est["timing"]
        errors = errors_deg(est["track"], truth, shows)
        figures[mode] = {"total_s": t.get("total_s"), "wall_s": est["wall_s"],
                         "max_rss_mb": est["max_rss_mb"], "timing": t,
                         "per_frame_ms": 1000.0 * t.get("total_s", 0.0) / max(1, est["frames"]),
                         "error_mean_deg": sum(errors) / max(1, len(errors)),
                         "error_max_deg": max(errors, default=float("nan"))}
        f = figures[mode]
        print(f"{mode:7s} total_s {t.get('total_s', float('nan')):6.2f}  wall "
              f"{est['wall_s']:6.2f} s  {f['per_frame_ms']:5.1f} ms/frame  warp_s "
              f"{t.get('warp_s', 0.0):5.2f}  peak {est['max_rss_mb']:.0f} MB  direction error "
              f"mean {f['error_mean_deg']:.2f} max {f['error_max_deg']:.2f} deg "
              f"({len(errors)} frames)", flush=True)
    ratio = figures["moving"]["total_s"] / figures["still"]["total_s"]
    figures["ratio"] = ratio
    print(f"moving / still: {ratio:.2f}x (target <= {TARGET_RATIO}: "
          f"{'met' if ratio <= TARGET_RATIO else 'NOT met'})")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(figures, fh, indent=1)


if __name__ == "__main__":
    main()
