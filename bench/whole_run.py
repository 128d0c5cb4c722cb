#!/usr/bin/env python3
"""The whole run's speed and memory (issue 18): the estimate vs decoding alone.

  python3 bench/whole_run.py [--sizes 720,1080,2160] [--length 300] [--gop 25]
                             [--long 1000,10000] [--scene DIR] [--cache DIR]
                             [--blender PATH] [--suite-cache DIR]
                             [--suite-size 1080] [--suite-length 300] [--out FIGURES.json]

Clips: the plaza preset's rendered frames (640x360, 90 frames; DIR/frames/ or
DIR/clip.mp4 of --scene, by default build/accuracy/scenes/plaza-bench/, else
rendered once into CACHE/scene/ with examples/generate_scene.py), played
forward then backward (so the Sun never jumps) to the length wanted, upscaled
and encoded with ffmpeg (libx264). Clips and the scene .blend re-saved for
each (render size = clip size, the movie clip pointed at the new file) are
cached in CACHE (default build/whole-run-cache/, outside git) and re-made only
when their inputs change.

For each size in --sizes (--length frames each) and each 1080p length in
--long it prints:
  decode-only  the add-on's own reader (_native.VideoReader) reading every
               frame and doing nothing else, frames/s (BGR, and gray when the
               reader has read_gray);
  ffmpeg       `ffmpeg -i CLIP -f null -`: every frame decoded at full size,
               once (what a user compares with; issue 28), and the estimate's
               ratio to it;
  estimate     `blender -b --factory-startup SCENE.blend --python-exit-code 1
               --python examples/run_estimate.py -- --out T.json`, exactly as a
               user runs it: frames/s from the track's timing.total_s (the
               estimate's own clock) and from the command's wall time, the
               ratio to decode-only, every timing key the track holds, the
               precompute (table_s, reference_s, ... whichever exist), the
               per-frame cost after it (precompute + one such frame is the "first
               frame" of the targets), and the command's peak memory (max RSS);
then memory of the longest vs the shortest --long clip, optionally the worst
scene of the randomised suite (--suite-cache: bench/suite.py's cache, each
scene's estimate run once; on its own 320x180 clip, or with --suite-size on
its frames played forward and back to --suite-length at that size, as the
plaza's are), and a summary against issue 18's targets.

Figures only: the exit code is 0 whatever they are (non-zero only for bad
flags or a missing native build). Not part of tools/test.sh.

Time on this 2-core machine (estimate of commit 78aafb8, ~40 ms per 1080p
frame): the first run of the defaults took 27 minutes with the suite, 15 of
them encoding the clips (12 for the 10,000-frame one); re-runs use the cached
clips and take about 10 minutes (the suite adds 2); --sizes 720 --long ''
takes under a minute.
"""
import argparse
import hashlib
import json
import os
import shutil
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# 450 (issue 14's 120-frame 800x450 clip) only when asked for.
SIZES = {450: (800, 450), 720: (1280, 720), 1080: (1920, 1080), 2160: (3840, 2160)}
DEFAULT_SIZES = [720, 1080, 2160]
FPS = 25
# x264 with ffmpeg's defaults (crf 23, High profile, B-frames, keyframes at
# most 250 frames apart), but "fast" to keep the one-off encoding of the
# 10,000-frame clip to minutes on two cores. The bit rate sets the decoding
# cost: about 5-8 Mbit/s at 1080p here (the noisy render's frames upscaled).
ENCODER = ["-c:v", "libx264", "-preset", "fast", "-crf", "23", "-pix_fmt", "yuv420p"]
# Key frames every GOP frames (--gop): 25 (a second at 25 fps) as cameras and
# phones write their time-lapse movies; 250 is ffmpeg's own default, what a
# movie made from stills with a plain ffmpeg command has. The estimate reads
# its reference frames spread over the clip at key frames when there are
# enough of them (see docs/performance.md).
GOP = 25
# Timing keys that are paid once per run, before the per-frame loop (the
# whole-clip estimator's sky table and reference; the thesis method's initial
# stage). Whichever exist are summed.
PRECOMPUTE_KEYS = ("table_s", "reference_s", "tracker_start_s", "precompute_s", "setup_s",
                   "initial_s")
CACHE_VERSION = 1

# Targets of issue 18.
TARGET_RATIO = 0.9
TARGET_SUITE_RATIO = 0.5
TARGET_MEMORY_GROWTH = 0.10
TARGET_FIRST_FRAME_S = 1.0
# Issue 14: the whole estimate of a 120-frame 800x450 clip, whatever the scene.
TARGET_SMALL_CLIP_S = 3.0
# Issue 28: the whole estimate of 1080p H.264 against `ffmpeg -i CLIP -f null -`
# (every frame decoded at full size, once: what a user compares with), by
# clip length (frames): at least this ratio from that length on.
TARGET_FFMPEG_1080 = ((300, 0.4), (1000, 0.6))

# Re-saves a scene for a clip: render size = clip size, every movie clip
# pointed at the clip; writes the clip's frame range to INFO (JSON).
PREPARE_BLEND = '''\
import json
import sys

import bpy

argv = sys.argv[sys.argv.index("--") + 1:]
clip_path, width, height, out, info = argv[0], int(argv[1]), int(argv[2]), argv[3], argv[4]
scene = bpy.context.scene
scene.render.resolution_x, scene.render.resolution_y = width, height
scene.render.resolution_percentage = 100
if not bpy.data.movieclips:
    raise RuntimeError("whole_run: the scene has no movie clip")
for clip in bpy.data.movieclips:
    clip.filepath = clip_path
clip = scene.active_clip or bpy.data.movieclips[0]
scene.frame_start = clip.frame_start
scene.frame_end = clip.frame_start + clip.frame_duration - 1
bpy.ops.wm.save_as_mainfile(filepath=out)
with open(info, "w") as fh:
    json.dump({"frame_start": clip.frame_start, "frame_duration": clip.frame_duration,
               "size": list(clip.size)}, fh)
'''


class BenchError(Exception):
    """A step failed; the benchmark reports it and goes on with the next."""


def pingpong(count, length):
    """0-based source frame indices for `length` frames played forward then
    backward over `count` frames (0, 1, .., count-1, count-2, .., 1, 0, 1, ..),
    so neighbouring frames are always neighbours in the source."""
    if count < 1 or length < 0:
        raise ValueError(f"pingpong needs count >= 1 and length >= 0, got {count}, {length}")
    if count == 1:
        return [0] * length
    period = 2 * (count - 1)
    return [i % period if i % period < count else period - i % period for i in range(length)]


# ---- flags


def parse_sizes(text):
    sizes = []
    for part in text.split(","):
        part = part.strip().lower().rstrip("p")
        if not part:
            continue
        if part == "4k":
            part = "2160"
        if not part.isdigit() or int(part) not in SIZES:
            raise argparse.ArgumentTypeError(
                f"'{text}': sizes are a comma-separated subset of "
                f"{','.join(map(str, SIZES))}")
        sizes.append(int(part))
    return sorted(set(sizes))


def parse_lengths(text):
    lengths = []
    for part in text.split(","):
        part = part.strip().replace("_", "")
        if not part:
            continue
        if not part.isdigit() or int(part) < 2:
            raise argparse.ArgumentTypeError(
                f"'{text}': lengths are comma-separated frame counts >= 2, or '' for none")
        lengths.append(int(part))
    return sorted(set(lengths))


def parse_length(text):
    if not text.isdigit() or int(text) < 2:
        raise argparse.ArgumentTypeError(f"'{text}' is not a frame count >= 2")
    return int(text)


def existing_dir(text):
    if not os.path.isdir(text):
        raise argparse.ArgumentTypeError(f"'{text}' is not a folder")
    return os.path.abspath(text)


def parse_args(argv):
    p = argparse.ArgumentParser(prog="whole_run.py", description=__doc__.splitlines()[0])
    p.add_argument("--sizes", type=parse_sizes, default=DEFAULT_SIZES,
                   help="clip heights to measure: a subset of 450,720,1080,2160 (default "
                        "720,1080,2160)")
    p.add_argument("--length", type=parse_length, default=300,
                   help="frames of each --sizes clip (default 300)")
    p.add_argument("--long", type=parse_lengths, default=[1000, 10000],
                   help="lengths of the 1080p memory clips (default 1000,10000; '' for none)")
    p.add_argument("--scene", type=existing_dir,
                   help="a rendered scene folder (scene.blend, frames/ or clip.mp4); default "
                        "build/accuracy/scenes/plaza-bench, else rendered into the cache")
    p.add_argument("--cache", default=os.path.join(ROOT, "build", "whole-run-cache"),
                   help="folder for clips, scenes, tracks and logs "
                        "(default build/whole-run-cache)")
    p.add_argument("--gop", type=parse_length, default=GOP,
                   help=f"frames between key frames of the clips (default {GOP}, as cameras "
                        "write; 250 is ffmpeg's default)")
    p.add_argument("--blender", default="blender", help="the Blender command (default blender)")
    p.add_argument("--suite-cache", type=existing_dir,
                   help="bench/suite.py's cache: also measure every suite scene (slow)")
    p.add_argument("--suite-size", type=int, default=0,
                   help="measure the suite scenes upscaled to this clip height (one of "
                        f"{','.join(str(h) for h in SIZES)}); default 0: their own clips")
    p.add_argument("--suite-length", type=parse_length, default=300,
                   help="frames of each --suite-size clip (default 300)")
    p.add_argument("--out", help="write every figure to this JSON file too")
    args = p.parse_args(argv)
    if args.suite_size and args.suite_size not in SIZES:
        p.error(f"--suite-size: {args.suite_size} is not one of "
                f"{', '.join(str(h) for h in SIZES)} (or 0)")
    if args.suite_size and not args.suite_cache:
        p.error("--suite-size needs --suite-cache DIR")
    if shutil.which(args.blender) is None:
        p.error(f"--blender: '{args.blender}' is not a command found on PATH")
    if args.scene and not os.path.exists(os.path.join(args.scene, "scene.blend")):
        p.error(f"--scene: {args.scene} has no scene.blend")
    if args.out and not os.path.isdir(os.path.dirname(os.path.abspath(args.out))):
        p.error(f"--out: the folder of {args.out} does not exist")
    if shutil.which("ffmpeg") is None:
        p.error("ffmpeg is not installed (run: bash tools/install.sh)")
    return args


def load_native():
    sys.path.insert(0, os.path.join(ROOT, "addon"))
    try:
        import _native  # addon/_native*.so, built by tools/install.sh
    except ImportError as e:
        raise SystemExit(f"whole_run: error: the native core is not built ({e}); "
                         "run: bash tools/install.sh")
    return _native


# ---- clips and scenes (cached)


def stamp(path):
    st = os.stat(path)
    return [os.path.abspath(path), st.st_size, int(st.st_mtime)]


def cached(path, key):
    """Whether `path` exists and was made from `key` (its .key file)."""
    try:
        with open(path + ".key") as fh:
            return os.path.exists(path) and json.load(fh) == key
    except (OSError, ValueError):
        return False


def remember(path, key):
    with open(path + ".key", "w") as fh:
        json.dump(key, fh)


def run_logged(cmd, log):
    with open(log, "w") as fh:
        return subprocess.run(cmd, stdout=fh, stderr=subprocess.STDOUT).returncode


def last_error(log):
    try:
        with open(log) as fh:
            lines = [line.strip() for line in fh if "error" in line.lower()]
        return lines[-1] if lines else "see " + log
    except OSError:
        return "see " + log


def find_scene(args, cache):
    """The rendered scene folder the clips are made from."""
    if args.scene:
        return args.scene
    default = os.path.join(ROOT, "build", "accuracy", "scenes", "plaza-bench")
    if os.path.exists(os.path.join(default, "scene.blend")):
        return default
    rendered = os.path.join(cache, "scene", "plaza-bench")
    if not os.path.exists(os.path.join(rendered, "scene.blend")):
        print(f"rendering the plaza preset into {rendered} (once; a few minutes)", flush=True)
        t0 = time.perf_counter()
        log = os.path.join(cache, "logs", "generate.log")
        rc = run_logged([args.blender, "-b", "--factory-startup", "--python-exit-code", "1",
                         "--python", os.path.join(ROOT, "examples", "generate_scene.py"), "--",
                         "--preset", "plaza", "--out", rendered], log)
        if rc != 0:
            raise SystemExit(f"whole_run: error: rendering the plaza scene failed: "
                             f"{last_error(log)}")
        print(f"rendered in {time.perf_counter() - t0:.0f} s", flush=True)
    return rendered


def source_frames(scene_dir, cache):
    """The scene's frames as PNG paths, in order (extracted from clip.mp4 once
    when the render's frames/ are not there)."""
    def listed(folder):
        if not os.path.isdir(folder):
            return []
        return [os.path.join(folder, n) for n in sorted(os.listdir(folder))
                if n.lower().endswith(".png")]

    frames = listed(os.path.join(scene_dir, "frames"))
    if frames:
        return frames
    clip = os.path.join(scene_dir, "clip.mp4")
    if not os.path.exists(clip):
        raise SystemExit(f"whole_run: error: {scene_dir} has neither frames/ nor clip.mp4")
    key = {"version": CACHE_VERSION, "clip": stamp(clip)}
    folder = os.path.join(cache, "source-" + hashlib.sha1(clip.encode()).hexdigest()[:10])
    marker = os.path.join(folder, "done")
    if not cached(marker, key):
        shutil.rmtree(folder, ignore_errors=True)
        os.makedirs(folder)
        log = os.path.join(cache, "logs", "extract.log")
        if run_logged(["ffmpeg", "-nostdin", "-y", "-i", clip,
                       os.path.join(folder, "%06d.png")], log) != 0:
            raise SystemExit(f"whole_run: error: cannot extract the frames of {clip}: "
                             f"{last_error(log)}")
        open(marker, "w").close()
        remember(marker, key)
    return listed(folder)


def make_clip(frames, length, size, cache, gop=GOP, tag=""):
    """`length` frames ping-ponged over `frames`, scaled to `size`, as H.264
    with a key frame every `gop` frames (`tag`: a prefix naming the scene
    when it is not the plaza)."""
    w, h = size
    path = os.path.join(cache, f"clip-{tag}{w}x{h}-{length}-g{gop}.mp4")
    encoder = ENCODER + ["-g", str(gop)]
    key = {"version": CACHE_VERSION, "first": stamp(frames[0]), "last": stamp(frames[-1]),
           "count": len(frames), "length": length, "size": [w, h], "fps": FPS,
           "encoder": encoder}
    if cached(path, key):
        return path
    print(f"encoding {length} frames at {w}x{h} (once; cached in {cache})", flush=True)
    t0 = time.perf_counter()
    links = path + ".frames"
    shutil.rmtree(links, ignore_errors=True)
    os.makedirs(links)
    try:
        for i, k in enumerate(pingpong(len(frames), length)):
            os.symlink(frames[k], os.path.join(links, f"{i + 1:06d}.png"))
        partial = path + ".partial.mp4"
        log = os.path.join(cache, "logs", f"encode-{tag}{w}x{h}-{length}.log")
        rc = run_logged(["ffmpeg", "-nostdin", "-y", "-loglevel", "error",
                         "-framerate", str(FPS), "-start_number", "1",
                         "-i", os.path.join(links, "%06d.png"),
                         "-vf", f"scale={w}:{h}:flags=lanczos", *encoder, partial], log)
        if rc != 0:
            raise BenchError(f"encoding failed: {last_error(log)}")
        os.replace(partial, path)
    finally:
        shutil.rmtree(links, ignore_errors=True)
    remember(path, key)
    print(f"encoded in {time.perf_counter() - t0:.0f} s", flush=True)
    return path


def make_blend(blender, scene_blend, clip, size, cache):
    """The scene re-saved for `clip`; returns (path, clip info)."""
    w, h = size
    base = os.path.splitext(os.path.basename(clip))[0].replace("clip-", "scene-")
    path = os.path.join(cache, base + ".blend")
    key = {"version": CACHE_VERSION, "scene": stamp(scene_blend), "clip": stamp(clip),
           "size": [w, h], "script": hashlib.sha1(PREPARE_BLEND.encode()).hexdigest()}
    info_path = path + ".clip.json"
    if not cached(path, key):
        script = os.path.join(cache, "prepare_scene.py")
        with open(script, "w") as fh:
            fh.write(PREPARE_BLEND)
        log = os.path.join(cache, "logs", base + "-prepare.log")
        rc = run_logged([blender, "-b", "--factory-startup", scene_blend, "--python-exit-code",
                         "1", "--python", script, "--", clip, str(w), str(h), path, info_path],
                        log)
        if rc != 0 or not os.path.exists(info_path):
            raise BenchError(f"re-saving the scene failed: {last_error(log)}")
        remember(path, key)
    with open(info_path) as fh:
        return path, json.load(fh)


# ---- measuring


def decode_only(native, clip, mode):
    """(frames, seconds) of reading every frame with the add-on's reader in
    `mode` ("bgr": read(), "gray": read_gray()) and doing nothing else; the
    best of two passes when one is short (the first also warms the page cache)."""
    best = None
    for attempt in range(2):
        t0 = time.perf_counter()
        reader = native.VideoReader(clip)
        read = reader.read if mode == "bgr" else reader.read_gray
        n = 0
        while True:
            try:
                read()
            except StopIteration:
                break
            n += 1
        seconds = time.perf_counter() - t0
        best = (n, seconds) if best is None or seconds < best[1] else best
        if seconds > 5.0:
            break
    return best


def decode_modes(native):
    return ["bgr", "gray"] if hasattr(native.VideoReader, "read_gray") else ["bgr"]


def measure_decode(native, clip):
    """{mode: {"frames", "seconds", "fps"}}; a mode that fails is reported and left out."""
    out = {}
    for mode in decode_modes(native):
        try:
            n, seconds = decode_only(native, clip, mode)
        except Exception as e:  # a new read mode may take arguments we do not know
            print(f"  decode-only ({mode}) failed: {e}", flush=True)
            continue
        out[mode] = {"frames": n, "seconds": seconds, "fps": n / seconds if seconds > 0 else 0.0}
    return out


def measure_ffmpeg(clip):
    """{"seconds"} of `ffmpeg -i CLIP -f null -` (the best of two runs when
    one is short, the first also warming the page cache), or None without
    ffmpeg or when it fails."""
    if shutil.which("ffmpeg") is None:
        return None
    best = None
    for attempt in range(2):
        t0 = time.perf_counter()
        proc = subprocess.run(["ffmpeg", "-nostdin", "-loglevel", "error", "-i", clip,
                               "-f", "null", "-"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)
        seconds = time.perf_counter() - t0
        if proc.returncode != 0:
            return None
        best = seconds if best is None else min(best, seconds)
        if seconds > 5.0:
            break
    return {"seconds": best}


def ffmpeg_figures(f, ffmpeg):
    """The estimate's ratio to ffmpeg's decode (its throughput over ffmpeg's:
    total_s, and the command's wall time) into figures f."""
    if not ffmpeg or not f.get("frames"):
        return
    f["ffmpeg"] = dict(ffmpeg, fps=f["frames"] / ffmpeg["seconds"])
    if f.get("total_s"):
        f["ratio_ffmpeg"] = ffmpeg["seconds"] / f["total_s"]
    f["ratio_ffmpeg_wall"] = ffmpeg["seconds"] / f["wall_s"]


def reference_mode(decode):
    """The decode mode the ratio is taken against: gray when the reader has it
    (the estimate needs only gray pixels, and the faster reference is the
    stricter one), else BGR."""
    return "gray" if "gray" in decode else "bgr"


def run_measured(cmd, log):
    """(exit code, wall seconds, peak RSS in MB) of a command."""
    with open(log, "w") as fh:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=fh, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(proc.pid, 0)
        wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    return proc.returncode, wall, usage.ru_maxrss / 1024.0  # ru_maxrss: kB on Linux


def estimate_command(blender, blend, track, extra=()):
    return [blender, "-b", "--factory-startup", blend, "--python-exit-code", "1",
            "--python", os.path.join(ROOT, "examples", "run_estimate.py"), "--",
            "--out", track, *extra]


def measure_estimate(blender, blend, name, cache, extra=()):
    """Runs the estimate as a user does; figures from the track and the process."""
    track = os.path.join(cache, "tracks", name + ".sun.json")
    log = os.path.join(cache, "logs", name + "-estimate.log")
    if os.path.exists(track):
        os.unlink(track)
    rc, wall, rss_mb = run_measured(estimate_command(blender, blend, track, extra), log)
    if rc != 0 or not os.path.exists(track):
        raise BenchError(f"the estimate failed (exit {rc}): {last_error(log)}")
    with open(track) as fh:
        d = json.load(fh)
    timing = d.get("timing") or d.get("extra", {}).get("timing") or {}
    frames = d.get("frames", [])
    return {"wall_s": wall, "max_rss_mb": rss_mb, "timing": timing,
            "frames": len(frames),
            "estimated": sum(1 for f in frames if f.get("zenith_deg") is not None),
            "track": track, "log": log}


def figures_of(decode, est):
    """Throughputs and ratios of one clip."""
    n = est["frames"]
    timing = est["timing"]
    total = timing.get("total_s")
    pre_keys = [k for k in PRECOMPUTE_KEYS if isinstance(timing.get(k), (int, float))]
    pre = sum(timing[k] for k in pre_keys)
    f = {"frames": n, "estimated": est["estimated"], "decode": decode,
         "wall_s": est["wall_s"], "wall_fps": n / est["wall_s"], "max_rss_mb": est["max_rss_mb"],
         "timing": timing, "precompute_keys": pre_keys, "precompute_s": pre}
    mode = reference_mode(decode) if decode else None
    f["decode_mode"] = mode
    if isinstance(total, (int, float)) and total > 0 and n:
        per_frame = max(0.0, total - pre) / n
        f.update(total_s=total, fps=n / total, per_frame_ms=1000.0 * per_frame,
                 precompute_plus_first_s=pre + per_frame)
        if mode:
            ref = decode[mode]
            f["ratio"] = f["fps"] / ref["fps"] if ref["fps"] else None
            f["ratio_wall"] = f["wall_fps"] / ref["fps"] if ref["fps"] else None
            # Steady state: the per-frame loop alone against decoding.
            f["ratio_steady"] = (ref["seconds"] / max(1e-9, total - pre)
                                 if ref["frames"] == n else None)
            f["ratios_by_mode"] = {m: f["fps"] / d["fps"] for m, d in decode.items() if d["fps"]}
    return f


# ---- printing


def fmt(value, spec=".2f", none="-"):
    return none if value is None else format(value, spec)


def print_clip(label, f):
    n = f["frames"]
    print(f"  frames {n} (estimated {f['estimated']}/{n})")
    for mode, d in f["decode"].items():
        print(f"  decode-only ({mode})   {d['fps']:8.1f} frames/s  ({d['seconds']:.2f} s)")
    if "fps" in f:
        print(f"  estimate (total_s)  {f['fps']:8.1f} frames/s  ({f['total_s']:.2f} s)")
    print(f"  blender command     {f['wall_fps']:8.1f} frames/s  ({f['wall_s']:.2f} s wall)")
    if f.get("ffmpeg"):
        print(f"  ffmpeg -i ... -f null -  {f['ffmpeg']['fps']:8.1f} frames/s  "
              f"({f['ffmpeg']['seconds']:.2f} s): the estimate {fmt(f.get('ratio_ffmpeg'))}x "
              f"(wall {fmt(f.get('ratio_ffmpeg_wall'))}x)")
    if f.get("ratio") is not None:
        others = ", ".join(f"{m} {r:.2f}x" for m, r in f["ratios_by_mode"].items()
                           if m != f["decode_mode"])
        print(f"  ratio estimate/decode-only ({f['decode_mode']}): {f['ratio']:.2f}x"
              f"  (wall {fmt(f['ratio_wall'])}x; per-frame loop alone "
              f"{fmt(f['ratio_steady'])}x{'; ' + others if others else ''})")
    keys = ", ".join(f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
                     for k, v in f["timing"].items())
    print(f"  timing: {keys}")
    if "per_frame_ms" in f:
        print(f"  precompute {f['precompute_s']:.2f} s ({' + '.join(f['precompute_keys']) or '-'})"
              f", per frame after it {f['per_frame_ms']:.1f} ms, precompute + first frame "
              f"{f['precompute_plus_first_s']:.2f} s")
    print(f"  peak memory (max RSS of blender) {f['max_rss_mb']:.0f} MB", flush=True)


def summary_lines(fig):
    """(target, measured, verdict) rows."""
    rows = []

    def verdict(ok):
        return "-" if ok is None else ("met" if ok else "not met")

    for size in (1080, 2160):
        if not any(f.get("height") == size and f.get("ratio") is not None
                   for f in list(fig["sizes"].values()) + list(fig["long"].values())):
            rows.append((f"estimate >= {TARGET_RATIO}x decode-only at {SIZES[size][1]}p",
                         "not measured", "-"))
        for name, f in fig["sizes"].items():
            if f.get("height") == size and f.get("ratio") is not None:
                rows.append((f"estimate >= {TARGET_RATIO}x decode-only, {name}",
                             f"{f['ratio']:.2f}x (loop alone {fmt(f['ratio_steady'])}x)",
                             verdict(f["ratio"] >= TARGET_RATIO)))
        if size == 1080:
            for name, f in fig["long"].items():
                if f.get("ratio") is not None:
                    rows.append((f"estimate >= {TARGET_RATIO}x decode-only, {name}",
                                 f"{f['ratio']:.2f}x (loop alone {fmt(f['ratio_steady'])}x)",
                                 verdict(f["ratio"] >= TARGET_RATIO)))
    for name, f in fig["sizes"].items():
        if f.get("height") == 450 and f.get("total_s") is not None:
            rows.append((f"estimate <= {TARGET_SMALL_CLIP_S:g} s, {name} (issue 14)",
                         f"{f['total_s']:.2f} s", verdict(f["total_s"] <= TARGET_SMALL_CLIP_S)))
    for name, f in list(fig["sizes"].items()) + list(fig["long"].items()):
        if f.get("height") != 1080 or f.get("ratio_ffmpeg") is None:
            continue
        wanted = [r for n, r in TARGET_FFMPEG_1080 if f["frames"] >= n]
        if wanted:
            rows.append((f"estimate >= {wanted[-1]}x ffmpeg's decode (issue 28), {name}",
                         f"{f['ratio_ffmpeg']:.2f}x (wall {fmt(f.get('ratio_ffmpeg_wall'))}x)",
                         verdict(f["ratio_ffmpeg"] >= wanted[-1])))
    suite = fig.get("suite")
    if suite and suite.get("worst_ratio"):
        w = suite["worst_ratio"]
        on = (f", {suite['size'][0]}x{suite['size'][1]}, {suite['length']} frames"
              if suite.get("size") else ", its own clip")
        rows.append((f"worst suite scene >= {TARGET_SUITE_RATIO}x decode-only{on}",
                     f"{w['ratio']:.2f}x (scene {w['key']}; loop alone "
                     f"{fmt(w.get('ratio_steady'))}x)", verdict(w["ratio"] >= TARGET_SUITE_RATIO)))
    else:
        rows.append((f"worst suite scene >= {TARGET_SUITE_RATIO}x decode-only",
                     "not measured (--suite-cache DIR)", "-"))
    mem = fig.get("memory")
    if mem:
        rows.append((f"memory: {mem['long']} frames within {TARGET_MEMORY_GROWTH:.0%} of "
                     f"{mem['short']}", f"{mem['growth']:+.1%} ({mem['long_mb']:.0f} MB vs "
                     f"{mem['short_mb']:.0f} MB)",
                     verdict(abs(mem["growth"]) <= TARGET_MEMORY_GROWTH)))
    else:
        rows.append(("memory flat in clip length", "not measured (needs two --long)", "-"))
    firsts = [(name, f) for part in ("sizes", "long") for name, f in fig[part].items()
              if f.get("height") == 1080 and "precompute_plus_first_s" in f]
    if firsts:
        name, f = firsts[0]
        rows.append((f"precompute + first frame <= {TARGET_FIRST_FRAME_S:g} s at 1080p",
                     f"{f['precompute_plus_first_s']:.2f} s ({name})",
                     verdict(f["precompute_plus_first_s"] <= TARGET_FIRST_FRAME_S)))
    return rows


# ---- the parts


def measure_clip(native, args, scene_blend, frames, height, length, cache, failures):
    size = SIZES[height]
    name = f"{size[0]}x{size[1]}, {length} frames"
    print(f"\n== {name}", flush=True)
    try:
        clip = make_clip(frames, length, size, cache, args.gop)
        blend, info = make_blend(args.blender, scene_blend, clip, size, cache)
        if info.get("frame_duration") != length:
            print(f"  note: Blender sees {info.get('frame_duration')} frames in the clip",
                  flush=True)
        decode = measure_decode(native, clip)
        ffmpeg = measure_ffmpeg(clip)
        est = measure_estimate(args.blender, blend, f"{size[0]}x{size[1]}-{length}-g{args.gop}",
                               cache)
    except BenchError as e:
        print(f"  {e}", flush=True)
        failures.append(f"{name}: {e}")
        return name, None
    f = figures_of(decode, est)
    ffmpeg_figures(f, ffmpeg)
    f.update(height=height, clip=clip, blend=blend)
    print_clip(name, f)
    return name, f


def measure_suite(native, args, cache, failures):
    keys = sorted((k for k in os.listdir(args.suite_cache)
                   if os.path.exists(os.path.join(args.suite_cache, k, "scene.blend"))
                   and os.path.exists(os.path.join(args.suite_cache, k, "clip.mp4"))),
                  key=lambda k: (not k.isdigit(), int(k) if k.isdigit() else 0, k))
    size = SIZES.get(args.suite_size)
    on = (f"on {size[0]}x{size[1]} clips of {args.suite_length} frames (their frames "
          "played forward and back, upscaled)") if size else "on their own clips"
    print(f"\n== randomised suite: {len(keys)} scenes in {args.suite_cache}, "
          f"each estimated once {on}", flush=True)
    print(f"  {'scene':>12} {'frames':>6} {'decode f/s':>10} {'total_s':>8} {'est f/s':>8} "
          f"{'ratio':>6} {'loop alone':>10} {'max RSS MB':>10}")
    scenes = {}
    for key in keys:
        folder = os.path.join(args.suite_cache, key)
        try:
            clip, blend, name = (os.path.join(folder, "clip.mp4"),
                                 os.path.join(folder, "scene.blend"), f"suite-{key}")
            if size:
                clip = make_clip(source_frames(folder, cache), args.suite_length, size, cache,
                                 args.gop, tag=f"suite{key}-")
                blend, _ = make_blend(args.blender, blend, clip, size, cache)
                name = f"suite-{key}-{size[0]}x{size[1]}-{args.suite_length}"
            decode = measure_decode(native, clip)
            est = measure_estimate(args.blender, blend, name, cache)
        except BenchError as e:
            print(f"  {key:>12} {e}", flush=True)
            failures.append(f"suite scene {key}: {e}")
            continue
        f = figures_of(decode, est)
        scenes[key] = f
        ref = decode[f["decode_mode"]] if f["decode_mode"] else {"fps": 0.0}
        print(f"  {key:>12} {f['frames']:>6} {ref['fps']:>10.1f} {fmt(f.get('total_s')):>8} "
              f"{fmt(f.get('fps'), '.1f'):>8} {fmt(f.get('ratio')):>6} "
              f"{fmt(f.get('ratio_steady')):>10} {f['max_rss_mb']:>10.0f}", flush=True)
    out = {"scenes": scenes, "size": list(size) if size else None,
           "length": args.suite_length if size else None}
    timed = {k: f for k, f in scenes.items() if f.get("ratio") is not None}
    if timed:
        slow = max(timed, key=lambda k: timed[k]["total_s"])
        worst = min(timed, key=lambda k: timed[k]["ratio"])
        out["slowest"] = {"key": slow, "total_s": timed[slow]["total_s"],
                          "ratio": timed[slow]["ratio"]}
        out["worst_ratio"] = {"key": worst, "ratio": timed[worst]["ratio"],
                              "ratio_steady": timed[worst]["ratio_steady"]}
        print(f"  slowest scene by total_s: {slow} ({timed[slow]['total_s']:.2f} s), ratio "
              f"{timed[slow]['ratio']:.2f}x; worst ratio: scene {worst}, "
              f"{timed[worst]['ratio']:.2f}x", flush=True)
    return out


def header():
    try:
        commit = subprocess.run(["git", "-C", ROOT, "describe", "--always", "--dirty"],
                                capture_output=True, text=True).stdout.strip()
    except OSError:
        commit = ""
    load = ", ".join(f"{v:.2f}" for v in os.getloadavg())
    return (f"whole_run: tree {commit or '?'} ({ROOT}), {os.cpu_count()} cores, "
            f"load average {load}")


def main(argv=None):
    args = parse_args(argv)
    native = load_native()
    cache = os.path.abspath(args.cache)
    for sub in ("logs", "tracks"):
        os.makedirs(os.path.join(cache, sub), exist_ok=True)
    t_start = time.perf_counter()
    print(header(), flush=True)
    fig = {"tree": header(), "sizes": {}, "long": {}, "failures": []}
    failures = fig["failures"]
    if args.sizes or args.long:
        scene_dir = find_scene(args, cache)
        frames = source_frames(scene_dir, cache)
        scene_blend = os.path.join(scene_dir, "scene.blend")
        print(f"source: {len(frames)} frames of {scene_dir}, played forward and back; "
              f"decode modes: {', '.join(decode_modes(native))}", flush=True)
        for height in args.sizes:
            name, f = measure_clip(native, args, scene_blend, frames, height, args.length,
                                   cache, failures)
            if f:
                fig["sizes"][name] = f
        for length in args.long:
            name, f = measure_clip(native, args, scene_blend, frames, 1080, length, cache,
                                   failures)
            if f:
                fig["long"][name] = f
    measured = [(f["frames"], f["max_rss_mb"]) for f in fig["long"].values()]
    if len(measured) >= 2:
        (short, short_mb), (long_, long_mb) = min(measured), max(measured)
        fig["memory"] = {"short": short, "long": long_, "short_mb": short_mb,
                         "long_mb": long_mb, "growth": long_mb / short_mb - 1.0}
        print(f"\n== memory: {long_} frames {long_mb:.0f} MB vs {short} frames "
              f"{short_mb:.0f} MB ({fig['memory']['growth']:+.1%})", flush=True)
    if args.suite_cache:
        fig["suite"] = measure_suite(native, args, cache, failures)

    print("\n== issue 18 targets (this machine; figures only, never a failure)")
    rows = summary_lines(fig)
    width = max(len(r[0]) for r in rows)
    for target, value, verdict in rows:
        print(f"  {target.ljust(width)}  {value}  [{verdict}]")
    for failure in failures:
        print(f"  failed: {failure}")
    print(f"  ({time.perf_counter() - t_start:.0f} s; clips, tracks and logs in {cache})")
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(fig, fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
