"""The scripted run: estimate the Sun on every frame of a clip.

Shared by examples/run_estimate.py (Blender 3.x and later, `--python`) and
the `sunlapse` command of Blender 4.2+ (`blender -c sunlapse ...`). Flags and
the track file are a fixed contract (the accuracy benchmarks use them):

  --out TRACK.json [--collection NAME] [--ground NAME ...] [--frames A:B]
  [--smoothing online|two_pass|physical] [--method thesis|default]
  [--apply-lamp] [--save OUT.blend] [--render-ar DIR]

Extensions (optional, later than the contract): --times CSV (each frame's
capture time, see core/frametimes.py; default: the panel's Frame Times),
--latitude/--longitude/--date/--start-time/--utc-offset/--frame-seconds/
--fixed-latitude (place and time for physical smoothing), --initial-sun Z A.

On failure: one line "sunlapse: error: <reason>" on stderr and a non-zero
code (2 bad arguments, 3 the scene lacks something, 4 internal); the track
file is written only when the run succeeds.
"""

import argparse
import os
import sys

PROG = "run_estimate.py"

EXIT_USAGE = 2
EXIT_SCENE = 3
EXIT_INTERNAL = 4


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one "sunlapse: error:" line, like every failure
        raise CliError(EXIT_USAGE, f"{message} (see --help)")


def parse_args(argv):
    p = _Parser(prog=PROG,
                                description="Estimate the Sun on a clip.")
    p.add_argument("--out", required=True, help="track file to write (*.sun.json)")
    p.add_argument("--collection", help="collection holding the model")
    p.add_argument("--ground", nargs="+", default=[], help="ground object name(s)")
    p.add_argument("--frames", help="frame range A:B (scene frames, inclusive)")
    p.add_argument("--smoothing", choices=["online", "two_pass", "physical"],
                   default="two_pass")
    p.add_argument("--method", choices=["thesis", "default"], default="default")
    p.add_argument("--apply-lamp", action="store_true",
                   help="keyframe a Sun lamp from the track")
    p.add_argument("--save", help="save the .blend here afterwards")
    p.add_argument("--render-ar", metavar="DIR", help="render the AR composite here")
    p.add_argument("--times", metavar="CSV",
                   help="each frame's capture time (columns frame,local_time; local times use "
                        "--utc-offset): frames are tracked in capture order and smoothed over "
                        "real time; default: the scene's Frame Times setting")
    place = p.add_argument_group("place and time (for --smoothing physical)")
    place.add_argument("--latitude", type=float, help="degrees, north positive")
    place.add_argument("--longitude", type=float, help="degrees, east positive")
    place.add_argument("--date", help="YYYY-MM-DD of the first frame (local)")
    place.add_argument("--start-time", help="HH:MM[:SS] local time of the first frame")
    place.add_argument("--utc-offset", type=float, default=None,
                       help="hours, e.g. 2 for CEST (default: the scene's UTC Offset, "
                            "else Sun Position's, else 0)")
    place.add_argument("--frame-seconds", type=float, help="seconds between frames")
    place.add_argument("--fixed-latitude", action="store_true",
                       help="the latitude is known exactly: fit only the time and north "
                            "offsets (default: the latitude is fitted too, near the given one)")
    p.add_argument("--initial-sun", nargs=2, type=float, metavar=("ZENITH", "AZIMUTH"),
                   help="start from this Sun on the first frame instead of estimating it "
                        "(degrees, azimuth as in the track file); for measuring the tracker")
    return p.parse_args(argv)


def parse_frames(text, clip):
    if not text:
        return clip.frame_start, clip.frame_end
    try:
        a, b = (int(v) for v in text.split(":"))
    except ValueError:
        raise ValueError(f"--frames must be A:B with integers, got '{text}'")
    if a > b:
        raise ValueError(f"--frames {text}: start after end")
    if a < clip.frame_start or b > clip.frame_end:
        raise ValueError(f"--frames {text} outside the clip's frames "
                         f"{clip.frame_start}:{clip.frame_end}")
    return a, b


def physical_inputs(args, context, options):
    """Place and time for physical smoothing: the flags first, then what the
    panel gave (`options`, filled by prepare_run), then Blender's Sun Position
    add-on (its latitude, longitude, date, time and UTC zone). With the
    frames' times known (a times file) only the place is needed."""
    import datetime as dt
    from .core import frametimes
    sp = getattr(context.scene, "sun_pos_properties", None)

    def pick(flag, from_options, from_sun_position):
        if flag is not None:
            return flag
        if from_options is not None:
            return from_options
        return getattr(sp, from_sun_position, None)
    lat = pick(args.latitude, options.latitude_deg, "latitude")
    lon = pick(args.longitude, options.longitude_deg, "longitude")
    if options.frame_times is not None:
        missing = [n for n, v in (("--latitude", lat), ("--longitude", lon)) if v is None]
        if missing:
            fail(EXIT_USAGE, "--smoothing physical needs " + ", ".join(missing))
        return {"latitude_deg": lat, "longitude_deg": lon}
    utc = args.utc_offset if args.utc_offset is not None else getattr(sp, "UTC_zone", 0.0)
    first = options.first_time if not (args.date or args.start_time) else None
    try:
        if first is None:
            if args.date:
                day = dt.date.fromisoformat(args.date)
            elif sp is not None:
                day = dt.date(sp.year, sp.month, sp.day)
            else:
                day = None
            if args.start_time:
                parts = [float(v) for v in args.start_time.split(":")]
                hours = parts[0] + (parts[1] if len(parts) > 1 else 0) / 60 + \
                    (parts[2] if len(parts) > 2 else 0) / 3600
            else:
                hours = getattr(sp, "time", None)
            if day is not None and hours is not None:
                first = frametimes.local_start(day, hours, utc)
    except ValueError as e:
        fail(EXIT_USAGE, f"bad --date or --start-time: {e}")
    seconds = args.frame_seconds if args.frame_seconds is not None else options.frame_seconds
    missing = [name for name, v in (("--latitude", lat), ("--longitude", lon),
                                    ("--date and --start-time", first),
                                    ("--frame-seconds", seconds)) if v is None]
    if missing:
        fail(EXIT_USAGE, "--smoothing physical needs " + ", ".join(missing) +
             " (or --times, or Blender's Sun Position add-on values)")
    return {"first_time": first, "frame_seconds": seconds,
            "latitude_deg": lat, "longitude_deg": lon}


class CliError(Exception):
    def __init__(self, code, message):
        super().__init__(message)
        self.code = code


def fail(code, message):
    raise CliError(code, message)


def _run(argv):
    import bpy
    from . import ar, bridge, native_loader, operators, pipeline, register, results
    from .core import trackfile

    args = parse_args(argv)
    try:
        native_loader.require()
    except RuntimeError as e:
        fail(EXIT_INTERNAL, str(e))
    context = bpy.context
    collection = None
    if args.collection:
        collection = bpy.data.collections.get(args.collection)
        if collection is None:
            fail(EXIT_USAGE, f"no collection named '{args.collection}'")
    try:
        clip = bridge.gather_clip(context)
        frames = parse_frames(args.frames, clip)
    except bridge.SceneError as e:
        fail(EXIT_SCENE, str(e))
    except ValueError as e:
        fail(EXIT_USAGE, str(e))

    if not hasattr(bpy.types.Scene, "sunlapse"):
        register()  # properties and operators, as in the UI
    try:
        scene_n, camera_n, clip, numbers, options, extra = operators.prepare_run(
            context, collection=collection, ground=args.ground, frames=frames,
            method=args.method, smoothing=args.smoothing,
            times_file=os.path.abspath(args.times) if args.times else None,
            utc_offset=args.utc_offset)
        if args.smoothing == "physical":
            if args.fixed_latitude:
                options.fit_latitude = False
            for key, value in physical_inputs(args, context, options).items():
                setattr(options, key, value)
        if args.initial_sun:
            z, a = args.initial_sun
            if not (0 <= z < 90):
                fail(EXIT_USAGE, f"--initial-sun zenith {z} is not in [0, 90)")
            options.initial_sun = (z, a)
        track = pipeline.run(scene_n, camera_n, clip.filepath, clip.frame_start, numbers, options)
    except bridge.SceneError as e:
        fail(EXIT_SCENE, str(e))
    except pipeline.PipelineError as e:
        fail(EXIT_SCENE, str(e))
    summary = operators.finish_run(context, track, clip, dict(extra, method=args.method,
                                                               frames=list(frames)))
    if operators.report_level(track) == {"WARNING"}:
        print(f"sunlapse: warning: {summary}")
    trackfile.write_track(args.out, track)
    init = track.initial
    if init:
        print(f"sunlapse: initial Sun zenith {init['zenith_deg']:.2f} azimuth "
              f"{init['azimuth_deg']:.2f} deg (confidence {init['confidence']:.2f}, "
              f"{init['seconds']:.2f} s){' - ' + init['message'] if init.get('message') else ''}")
    else:
        print(f"sunlapse: warning: {track.frames[0].reason}")
    if track.extra.get("model_hint"):
        print(f"sunlapse: note: {track.extra['model_hint']}")
    done = sum(1 for f in track.frames if f.has_estimate)
    timing = track.extra.get("timing", {})
    print(f"sunlapse: {done}/{len(track.frames)} frames estimated "
          f"(tracking {timing.get('tracking_ms_per_frame', 0):.1f} ms/frame); wrote {args.out}")
    if args.apply_lamp or args.render_ar:
        try:
            sun = results.apply_track(context, track, context.scene.sunlapse.sun_lamp)
        except ValueError as e:
            fail(EXIT_SCENE, str(e))
        context.scene.sunlapse.sun_lamp = sun
        print(f"sunlapse: keyed Sun lamp '{sun.name}' on {done} frames")
    if args.render_ar:
        try:
            print(f"sunlapse: {ar.setup(context)}")
        except (bridge.SceneError, ValueError) as e:
            fail(EXIT_SCENE, str(e))
        os.makedirs(args.render_ar, exist_ok=True)
        ar.render_frames(context, os.path.abspath(args.render_ar), frames)
        print(f"sunlapse: rendered AR frames {frames[0]}-{frames[1]} to {args.render_ar}")
    if args.save:
        bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.save), copy=True)
        print(f"sunlapse: saved {args.save}")


def main(argv):
    """Runs with arguments `argv`; returns the exit code (0 on success)."""
    try:
        _run(argv)
        return 0
    except CliError as e:
        message, code = str(e), e.code
    except SystemExit as e:  # argparse: usage already printed
        return int(e.code or 0) and EXIT_USAGE
    except Exception as e:  # an internal bug: still one line, non-zero exit
        import traceback
        traceback.print_exc()
        message, code = f"internal error: {type(e).__name__}: {e}", EXIT_INTERNAL
    sys.stderr.write(f"sunlapse: error: {message}\n")
    sys.stderr.flush()
    return code


def command(argv):
    """Blender 4.2+ command: blender -c sunlapse SCENE.blend --out TRACK.json ..."""
    import bpy
    if not argv or argv[0].startswith("-"):
        sys.stderr.write("sunlapse: error: usage: blender -c sunlapse SCENE.blend --out TRACK.json ...\n")
        return EXIT_USAGE
    try:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(argv[0]))
    except RuntimeError as e:
        sys.stderr.write(f"sunlapse: error: cannot open {argv[0]}: {e}\n")
        return EXIT_SCENE
    return main(argv[1:])
