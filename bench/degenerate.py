"""Degenerate inputs real footage brings, built from one rendered suite scene
and run as a user runs them (issue 25's list):

  /usr/bin/python3 bench/degenerate.py [--scene plaza14] [--cache DIR] [--work DIR]

- loop: the scene's first LOOP_FRAMES frames played LOOP_TIMES times, no
  times (the Sun goes back 8 deg at each loop: a step the untimed path
  allows); scored on segments found and the error against the truth;
- pingpong: the scene's frames played forward, backward and forward again
  (a boomerang edit), no times; scored on segments found (target 3) and
  the error against the truth;
- interval: the scene's first half frame by frame, then every other frame
  (the interval doubles, as in a day-to-night ramp), no times; scored on
  frames without a Sun and the error against the truth;
- same_time / date_only: a times file giving every frame the same time, or
  the date alone; scored against the run without times (as accurate);
- corrupt: frame CORRUPT_FRAME replaced by noise; scored on frames more
  than 5 deg off at confidence >= 0.5 (target 0);
- bollard: a caster named as the ground; scored on the warning naming it.

The scene comes from bench/suite.py's cache (render it there first:
`python3 bench/suite.py --seeds plaza14 --render-only`). Prints one line a
case and exits 0 whatever the figures (1 only when the scene is missing).
"""
import argparse
import csv
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "addon"))

from core import evaluation, trackfile  # noqa: E402

LOOP_FRAMES, LOOP_TIMES = 6, 8
CORRUPT_FRAME = 16
CONFIDENT, WRONG_DEG = 0.5, 5.0
BLENDER_ENV = dict(os.environ, PATH="/usr/bin:" + os.environ.get("PATH", ""))
# Points the .blend's clip at another file and sets the scene's frame range.
SET_CLIP = ("import bpy, sys; a = sys.argv[sys.argv.index('--') + 1:]; "
            "[setattr(c, 'filepath', a[0]) for c in bpy.data.movieclips]; "
            "s = bpy.context.scene; s.frame_start, s.frame_end = 1, int(a[1]); "
            "bpy.ops.wm.save_as_mainfile(filepath=a[2])")


def ffmpeg(*args):
    subprocess.run(["ffmpeg", "-loglevel", "error", "-y", *args], check=True)


def blend_with_clip(scene_blend, clip, frames, out):
    subprocess.run(["blender", "-b", scene_blend, "--factory-startup", "--python-expr",
                    SET_CLIP, "--", clip, str(frames), out], check=True, env=BLENDER_ENV,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def estimate(blend, out, *flags):
    """Runs the scripted estimate; (track or None, its output)."""
    proc = subprocess.run(["nice", "-n", "10", "blender", "-b", blend, "--python-exit-code", "1",
                           "--python", os.path.join(ROOT, "examples", "run_estimate.py"), "--",
                           "--out", out, *flags], capture_output=True, text=True, env=BLENDER_ENV)
    text = proc.stdout + proc.stderr
    return (trackfile.read_track(out) if proc.returncode == 0 else None), text


def errors(track, truth, period=None, source=None):
    """Per frame (error deg or None, confidence) against the truth (its
    frames repeated every `period` frames, or the truth's position of each
    frame: source(frame))."""
    out = []
    for e in track.frames:
        t = truth.frames[source(e.frame) if source is not None else
                         (e.frame - 1) % (period or len(truth.frames))]
        if not e.has_estimate:
            out.append((None, e.confidence))
            continue
        out.append((evaluation.angle_between_deg(
            evaluation.direction(e.zenith_deg, e.azimuth_deg + track.north_offset_deg),
            evaluation.direction(t.zenith_deg, t.azimuth_deg + truth.north_offset_deg)),
            e.confidence))
    return out


def figures(errs):
    got = [d for d, _ in errs if d is not None]
    wrong = sum(1 for d, c in errs if d is not None and d > WRONG_DEG and c >= CONFIDENT)
    if not got:
        return "no frame estimated"
    return (f"{len(got)}/{len(errs)} frames, mean {sum(got) / len(got):.2f} max {max(got):.2f} "
            f"deg, {wrong} more than {WRONG_DEG:g} deg off at confidence >= {CONFIDENT:g}")


def write_times(path, frames, stamp):
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["frame", "local_time"])
        for k in range(1, frames + 1):
            w.writerow([k, stamp])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="plaza14", help="a suite scene key (default plaza14)")
    p.add_argument("--cache", default=os.environ.get(
        "SUNLAPSE_SUITE_CACHE", os.path.join(ROOT, "build", "suite-cache")),
        help="bench/suite.py's rendered scenes (default build/suite-cache)")
    p.add_argument("--work", default=os.path.join(ROOT, "build", "degenerate"),
                   help="clips, tracks and logs (default build/degenerate)")
    args = p.parse_args(argv)
    folder = os.path.join(args.cache, args.scene)
    if not os.path.exists(os.path.join(folder, "scene.blend")):
        print(f"degenerate: error: no rendered scene '{args.scene}' in {args.cache} "
              f"(render it: python3 bench/suite.py --seeds {args.scene} --render-only)",
              file=sys.stderr)
        return 1
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    truth = trackfile.read_track(os.path.join(folder, "truth.sun.json"))
    scene_blend, clip = os.path.join(folder, "scene.blend"), os.path.join(folder, "clip.mp4")
    n = len(truth.frames)

    def out(name):
        return os.path.join(work, name)

    def played(name, parts, frames):
        """The clips in `parts` one after the other, as H.264, estimated."""
        with open(out(f"{name}.txt"), "w") as f:
            f.writelines(f"file '{c}'\n" for c in parts)
        ffmpeg("-f", "concat", "-safe", "0", "-i", out(f"{name}.txt"), "-c:v", "libx264",
               "-crf", "18", "-pix_fmt", "yuv420p", out(f"{name}.mp4"))
        blend_with_clip(scene_blend, out(f"{name}.mp4"), frames, out(f"{name}.blend"))
        return estimate(out(f"{name}.blend"), out(f"{name}.sun.json"))[0]

    def said_segments(label, track, target, **truth_at):
        if track is None:
            print(f"{label}: the run failed")
        else:
            print(f"{label}: {len(track.extra.get('segments', []))} segments (target {target}); "
                  f"{figures(errors(track, truth, **truth_at))}")

    # Loop: the first frames played again and again, no times.
    ffmpeg("-i", clip, "-vf", f"select='lt(n\\,{LOOP_FRAMES})',setpts=N/25/TB", "-an",
           out("slice.mp4"))
    said_segments(f"loop ({LOOP_FRAMES} frames x {LOOP_TIMES})",
                  played("loop", [out("slice.mp4")] * LOOP_TIMES, LOOP_FRAMES * LOOP_TIMES),
                  LOOP_TIMES, period=LOOP_FRAMES)

    # Forward, backward and forward again, no times.
    ffmpeg("-i", clip, "-vf", "reverse", "-an", out("reversed.mp4"))

    def back(f):  # the truth's position of frame f
        return f - 1 if f <= n else 2 * n - f if f <= 2 * n else f - 2 * n - 1
    said_segments(f"pingpong ({n} frames forward, back, forward)",
                  played("pingpong", [clip, out("reversed.mp4"), clip], 3 * n), 3, source=back)

    # The interval doubles halfway, no times.
    half = n // 2
    ffmpeg("-i", clip, "-vf", f"select='lt(n\\,{half})+gte(n\\,{half})*not(mod(n\\,2))',"
           "setpts=N/25/TB", "-an", "-c:v", "libx264", "-crf", "18", "-pix_fmt", "yuv420p",
           out("interval.mp4"))
    kept = half + (n - half + 1) // 2

    def doubled(f):  # the truth's position of frame f
        return f - 1 if f <= half else half + 2 * (f - 1 - half)
    blend_with_clip(scene_blend, out("interval.mp4"), kept, out("interval.blend"))
    track, _ = estimate(out("interval.blend"), out("interval.sun.json"))
    if track is None:
        print("interval: the run failed")
    else:
        print(f"interval ({half} frames, then every other frame): "
              f"{figures(errors(track, truth, source=doubled))}")

    # Times without information, against no times.
    plain, _ = estimate(scene_blend, out("plain.sun.json"))
    base = figures(errors(plain, truth)) if plain is not None else "the run failed"
    print(f"no times: {base}")
    day = truth.extra["local_times"][0][:10]
    for name, stamp in (("same_time", f"{day} 12:00"), ("date_only", day)):
        write_times(out(f"{name}.csv"), n, stamp)
        track, text = estimate(scene_blend, out(f"{name}.sun.json"), "--times", out(f"{name}.csv"))
        said = [ln for ln in text.splitlines() if "times" in ln and "warning" in ln]
        print(f"{name}: " + (figures(errors(track, truth)) if track is not None else
                             "the run failed: " + text.strip().splitlines()[-1])
              + (f"; said: {said[0]}" if said else "; said nothing"))

    # One corrupt frame: noise in place of frame CORRUPT_FRAME.
    ffmpeg("-i", clip, "-f", "lavfi", "-i", "nullsrc=s=320x180,geq=random(1)*255:128:128",
           "-filter_complex", f"[1][0]scale2ref[n][v];[v][n]overlay=enable='eq(n\\,"
           f"{CORRUPT_FRAME - 1})':shortest=1", "-c:v", "libx264", "-crf", "18",
           "-pix_fmt", "yuv420p", out("corrupt.mp4"))
    blend_with_clip(scene_blend, out("corrupt.mp4"), n, out("corrupt.blend"))
    track, _ = estimate(out("corrupt.blend"), out("corrupt.sun.json"))
    print(f"corrupt frame {CORRUPT_FRAME}: " + (figures(errors(track, truth))
                                                if track is not None else "the run failed"))

    # A caster named as the ground.
    spec = truth.extra.get("random_scene", {})
    caster = next((c["name"] for c in spec.get("casters", [])), None)
    if caster is not None:
        track, text = estimate(scene_blend, out("bollard.sun.json"), "--ground", caster)
        named = [ln for ln in text.splitlines() if "warning" in ln and f"'{caster}'" in ln]
        print(f"ground '{caster}' (a caster): {len(named)} warning(s) naming it; "
              + (figures(errors(track, truth)) if track is not None else "the run failed"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
