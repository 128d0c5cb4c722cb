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
--fit-latitude, --fixed-latitude (place and time for physical smoothing),
--initial-sun Z A.

On failure: one line "sunlapse: error: <reason>" on stderr and a non-zero
code (2 a bad flag or file named on the command line, 3 the scene or clip
lacks something, 4 an internal error: a bug of ours, or an incomplete
install (no native core; examples/run_estimate.py: no numpy), 130
interrupted by Ctrl-C). Outputs are written only when the whole run succeeds, each
atomically (a temporary file in the same folder, renamed): the track file
last, after --apply-lamp, --render-ar and --save. An output may not be an
input (the .blend, the clip, the times file). A failed or interrupted run
leaves existing files as they were.

Timing fields (extra "timing", initial "seconds") differ between runs; all
else in the track file is the same for the same input and options
(core.trackfile.without_timings gives what a byte-compare should see).
"""

import argparse
import math
import os
import signal
import sys
import tempfile

from .estimate import options as estimate_options

PROG = "run_estimate.py"

EXIT_USAGE = 2
EXIT_SCENE = 3
EXIT_INTERNAL = 4
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as shells report it


class _Parser(argparse.ArgumentParser):
    def error(self, message):  # one "sunlapse: error:" line, like every failure
        raise CliError(EXIT_USAGE, f"{message} (see --help)")


def build_parser():
    """The flags (examples/run_estimate.py's docstring documents each)."""
    p = _Parser(prog=PROG, description="Estimate the Sun on a clip.")
    p.add_argument("--out", required=True, help="track file to write (*.sun.json)")
    p.add_argument("--collection", help="collection holding the model")
    p.add_argument("--ground", nargs="+", default=[], help="ground object name(s)")
    p.add_argument("--frames", help="frame range A:B (scene frames, inclusive)")
    choices = estimate_options.keys
    p.add_argument("--smoothing", choices=choices(estimate_options.SMOOTHINGS),
                   default="two_pass")
    p.add_argument("--method", choices=choices(estimate_options.METHODS), default="default")
    p.add_argument("--apply-lamp", action="store_true",
                   help="keyframe a Sun lamp from the track")
    p.add_argument("--save", help="save the .blend here afterwards")
    p.add_argument("--render-ar", metavar="DIR", help="render the AR composite here")
    p.add_argument("--times", metavar="CSV",
                   help="each frame's capture time (columns frame,local_time; local times use "
                        "--utc-offset): frames are tracked in capture order and smoothed over "
                        "real time; default: the scene's Frame Times setting")
    place = p.add_argument_group("place and time (for --smoothing physical; the place, with "
                                 "the frames' times, also says which frames are night)")
    place.add_argument("--latitude", type=float, help="degrees, north positive")
    place.add_argument("--longitude", type=float, help="degrees, east positive")
    place.add_argument("--date", help="YYYY-MM-DD of the first frame (local)")
    place.add_argument("--start-time", help="HH:MM[:SS] local time of the first frame")
    place.add_argument("--utc-offset", type=float, default=None,
                       help="hours, e.g. 2 for CEST (default: the scene's UTC Offset, "
                            "else Sun Position's, else 0)")
    place.add_argument("--frame-seconds", type=float, help="seconds between frames")
    latitude = place.add_mutually_exclusive_group()
    latitude.add_argument("--fit-latitude", action="store_true",
                          help="fit the latitude too, near the given one (default: the "
                               "latitude is used as given)")
    latitude.add_argument("--fixed-latitude", action="store_true",
                          help="use the latitude as given (the default; kept for scripts)")
    p.add_argument("--initial-sun", nargs=2, type=float, metavar=("ZENITH", "AZIMUTH"),
                   help="start from this Sun on the first frame instead of estimating it "
                        "(degrees, azimuth as in the track file); for measuring the tracker")
    refine = p.add_mutually_exclusive_group()
    refine.add_argument("--refine-model", dest="refine_model", action="store_true",
                        default=None,
                        help="refine the hand-made model by the clip first (the default, "
                             "unless the scene's Refine Model is off): each object moved, "
                             "turned and scaled and the camera turned and zoomed so that the "
                             "model's edges fall on the footage's; used only where the model "
                             "is clearly off, and then every frame's confidence stays below "
                             "0.5 unless the refined model's shadows fit the footage closely; "
                             "the track lists the corrections (the .blend is not changed)")
    refine.add_argument("--no-refine-model", dest="refine_model", action="store_false",
                        default=None, help="use the model as it is, without the refinement")
    p.add_argument("--apply-model-corrections", action="store_true",
                   help="apply the corrections the estimate used to the "
                        "objects and camera of the open .blend (kept with --save, used by "
                        "--render-ar); objects that keys, drivers or constraints move are "
                        "left as they are")
    p.add_argument("--uncalibrated-confidence", action="store_true",
                   help="write each frame's support as the estimator computes it instead of "
                        "the probability of being within 2 deg; for refitting that "
                        "calibration (bench/calibrate.py)")
    return p


def parse_args(argv):
    return build_parser().parse_args(argv)


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
        held = "" if clip.frames_in_file is None else \
            f"; the file holds {clip.frames_in_file} frame(s)"
        raise ValueError(f"--frames {text} outside the clip's frames "
                         f"{clip.frame_start}:{clip.frame_end}{held}")
    return a, b


def _finite(value, flag, low=-math.inf, high=math.inf, what=None):
    if value is None:
        return
    if not math.isfinite(value) or not low <= value <= high:
        fail(EXIT_USAGE, f"{flag} {value} is not {what or f'a number in [{low:g}, {high:g}]'}")


def parse_clock(text):
    """Hours after midnight from HH:MM[:SS]; ValueError says what is valid."""
    parts = text.split(":")
    try:
        if not 2 <= len(parts) <= 3:
            raise ValueError
        h, m = int(parts[0]), int(parts[1])
        sec = float(parts[2]) if len(parts) == 3 else 0.0
        if not (0 <= h <= 23 and 0 <= m <= 59 and 0 <= sec < 60):
            raise ValueError
    except ValueError:
        raise ValueError(f"--start-time '{text}' is not a time HH:MM[:SS] "
                         f"(00:00 to 23:59:59)")
    return h + m / 60 + sec / 3600


def check_flags(args):
    """Values the flags must have, checked before anything is read or run."""
    _finite(args.latitude, "--latitude", -90, 90, "a latitude in [-90, 90] degrees")
    _finite(args.longitude, "--longitude", -180, 360, "a longitude in [-180, 360] degrees")
    _finite(args.utc_offset, "--utc-offset", -14, 14, "a UTC offset in [-14, 14] hours")
    if args.frame_seconds is not None and not (math.isfinite(args.frame_seconds)
                                               and args.frame_seconds > 0):
        fail(EXIT_USAGE, f"--frame-seconds {args.frame_seconds} is not a positive number of "
                         f"seconds (0 would put every frame at one instant)")
    if args.refine_model and args.method == "thesis":
        fail(EXIT_USAGE, "--refine-model refines the model for the default method; the thesis "
                         "baseline (--method thesis) runs on the model as it is")
    if args.apply_model_corrections and (args.refine_model is False
                                         or args.method == "thesis"):
        fail(EXIT_USAGE, "--apply-model-corrections needs the model refined by the clip "
                         "(the default method without --no-refine-model): the corrections "
                         "come from that refinement")
    if args.initial_sun:
        z, a = args.initial_sun
        if not (math.isfinite(z) and 0 <= z < 90):
            fail(EXIT_USAGE, f"--initial-sun zenith {z} is not in [0, 90)")
        if not math.isfinite(a):
            fail(EXIT_USAGE, f"--initial-sun azimuth {a} is not a finite number of degrees")
    if args.date:
        import datetime as dt
        try:
            dt.date.fromisoformat(args.date)
        except ValueError:
            fail(EXIT_USAGE, f"--date '{args.date}' is not a date YYYY-MM-DD")
    if args.start_time:
        try:
            parse_clock(args.start_time)
        except ValueError as e:
            fail(EXIT_USAGE, str(e))
    if args.times is not None:  # a times file's faults are input faults, as its lines'
        if not os.path.exists(args.times):
            fail(EXIT_SCENE, f"--times {args.times}: no such file")
        if os.path.isdir(args.times):
            fail(EXIT_SCENE, f"--times {args.times} is a folder; give the times CSV file")
    outputs = [("--out", args.out), ("--save", args.save)]
    for flag, path in outputs:
        if path is not None:
            check_output(flag, path)
    if args.render_ar is not None:
        folder = os.path.abspath(args.render_ar)
        if os.path.exists(folder) and not os.path.isdir(folder):
            fail(EXIT_USAGE, f"--render-ar {args.render_ar} is a file; give a folder")
        parent = folder
        while not os.path.exists(parent) and os.path.dirname(parent) != parent:
            parent = os.path.dirname(parent)  # where the renders' folder will be made
        if not os.path.isdir(parent):
            fail(EXIT_USAGE, f"--render-ar {args.render_ar}: {parent} is a file, not a folder")
        if not os.access(parent, os.W_OK | os.X_OK):
            fail(EXIT_USAGE, f"--render-ar {args.render_ar}: cannot write in {parent}")
        probe_writable("--render-ar", args.render_ar, parent)
    if args.save is not None and _same(args.out, args.save):
        fail(EXIT_USAGE, f"--out and --save are the same file {args.out}")


def check_output(flag, path):
    """An output path must name a file in an existing folder we can write."""
    if not path or path.endswith(os.sep):
        fail(EXIT_USAGE, f"{flag} '{path}' is not a file name")
    full = os.path.abspath(path)
    if os.path.isdir(full):
        fail(EXIT_USAGE, f"{flag} {path} is a folder; give a file name in it")
    folder = os.path.dirname(full)
    if not os.path.isdir(folder):
        fail(EXIT_USAGE, f"{flag} {path}: the folder {folder} does not exist")
    if not os.access(folder, os.W_OK | os.X_OK):
        fail(EXIT_USAGE, f"{flag} {path}: the folder {folder} is not writable")
    if os.path.exists(full) and not os.access(full, os.W_OK):
        fail(EXIT_USAGE, f"{flag} {path} is read-only")
    probe_writable(flag, path, folder)


def probe_writable(flag, path, folder):
    """Creates and removes a file in `folder`: what the permission bits do
    not say (a read-only mount, /proc, a full quota; root passes every
    access check) is found before the estimate runs, not after it."""
    try:
        handle, probe = tempfile.mkstemp(prefix=".sunlapse-probe-", dir=folder)
    except OSError as e:
        fail(EXIT_USAGE, f"{flag} {path}: cannot write in the folder {folder} ({_reason(e)})")
    os.close(handle)
    try:
        os.remove(probe)
    except OSError:
        pass


def _reason(e):
    """An OS or Blender error as a short phrase (no trailing newline)."""
    text = getattr(e, "strerror", None) or str(e)
    return " ".join(text.split())


def _same(a, b):
    """Whether two paths name one file (links followed; files may not exist)."""
    if not a or not b:
        return False
    try:
        if os.path.exists(a) and os.path.exists(b):
            return os.path.samefile(a, b)
    except OSError:
        pass
    return os.path.normcase(os.path.realpath(a)) == os.path.normcase(os.path.realpath(b))


IMAGE_EXTENSIONS = (".png", ".jpg", ".jpeg", ".tif", ".tiff", ".exr", ".bmp", ".webp")


def check_not_inputs(args, blend_path, clip, times_path):
    """Refuses an output that would replace an input (the issue's --out
    naming the clip or the .blend, which were overwritten with JSON)."""
    inputs = [(blend_path, "the .blend being run"), (clip.filepath, "the clip"),
              (times_path, "the times file")]
    for flag, path in (("--out", args.out), ("--save", args.save)):
        if path is None:
            continue
        for source, what in inputs:
            if source and _same(path, source):
                fail(EXIT_USAGE, f"{flag} {path} is {what}, an input: give another file name")
        # Another image of the clip's sequence is an input too.
        if clip.source == "SEQUENCE" and \
                _same(os.path.dirname(os.path.abspath(path)), os.path.dirname(clip.filepath)) and \
                os.path.splitext(path)[1].lower() in IMAGE_EXTENSIONS:
            fail(EXIT_USAGE, f"{flag} {path} is an image beside the clip's sequence: "
                             f"give another file name")


class CliError(Exception):
    def __init__(self, code, message):
        super().__init__(message)
        self.code = code


def fail(code, message):
    raise CliError(code, message)


class _Interrupt:
    """Ctrl-C in a scripted run: Blender's own handler only flags the first
    one (its render loop looks; our loop never did) and kills on the second.
    Ours raises KeyboardInterrupt in the Python code running (the shadow
    search, the tracking loop) and flags it, for native work: the run's
    progress callback then cancels it, and every later step checks before it
    writes anything. Outputs are written last and atomically, so an
    interrupt at any point leaves existing files as they were."""

    def __init__(self):
        self.hit = False
        self.previous = None

    def __enter__(self):
        try:
            self.previous = signal.signal(signal.SIGINT, self._handle)
        except ValueError:  # not the main thread: nothing to catch
            self.previous = None
        return self

    def _handle(self, signum, frame):
        if self.hit:  # a second Ctrl-C: the user insists
            os._exit(EXIT_INTERRUPTED)
        self.hit = True
        raise KeyboardInterrupt

    def __exit__(self, *exc):
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        return False

    def check(self):
        if self.hit:
            fail(EXIT_INTERRUPTED, "interrupted (Ctrl-C): nothing written, "
                                   "existing files left as they were")

    def progress(self, fraction):
        return not self.hit  # False cancels the run


def save_blend_atomically(path):
    """Saves a copy of the open .blend to `path` through a temporary file in
    the same folder (an interrupted or failed save leaves `path` as it was)."""
    import uuid
    import bpy
    full = os.path.abspath(path)
    # A name not yet taken (an existing file would get a .blend1 backup).
    tmp = os.path.join(os.path.dirname(full), f".sunlapse-{uuid.uuid4().hex}.blend")
    try:
        result = bpy.ops.wm.save_as_mainfile(filepath=tmp, copy=True)
        if result != {"FINISHED"} or not os.path.getsize(tmp):
            raise RuntimeError(f"Blender did not save ({result})")
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, full)
    finally:
        for leftover in (tmp, tmp + "@", tmp + "1"):
            if os.path.exists(leftover):
                os.unlink(leftover)


def place_flags(args):
    """The place and time the flags give (blender.place.place_and_time works
    them out with the panel's and the Sun Position add-on's)."""
    import datetime as dt
    from .blender.place import PlaceTimeFlags
    if args.smoothing != "physical" and (args.latitude is None or args.longitude is None):
        return None  # a place with the frames' times also says which frames are night
    return PlaceTimeFlags(
        latitude_deg=args.latitude, longitude_deg=args.longitude,
        date=dt.date.fromisoformat(args.date) if args.date else None,
        start_hours=parse_clock(args.start_time) if args.start_time else None,
        utc_offset_hours=args.utc_offset, frame_seconds=args.frame_seconds,
        fit_latitude=True if args.fit_latitude else False if args.fixed_latitude else None)


def _run(argv, interrupt):
    import bpy
    from . import register
    from .blender import ar, gather, job, keys, model_fix, report
    from .blender.place import PlaceTimeError
    from .estimate import errors, native_loader, run as estimate_run
    from .core import trackfile

    args = parse_args(argv)
    check_flags(args)
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
        clip = gather.gather_clip(context)
    except gather.SceneError as e:
        fail(EXIT_SCENE, str(e))
    if not hasattr(bpy.types.Scene, "sunlapse"):
        register()  # properties and operators, as in the UI; the panel's times file
    times_path = os.path.abspath(args.times) if args.times else None
    settings_times = getattr(getattr(context.scene, "sunlapse", None), "times_file", "")
    check_not_inputs(args, bpy.data.filepath, clip,
                     times_path or (settings_times and bpy.path.abspath(settings_times)))
    try:
        frames = parse_frames(args.frames, clip)
    except ValueError as e:
        fail(EXIT_USAGE, str(e))

    try:
        run = job.prepare_job(
            context, collection=collection, ground=args.ground, frames=frames,
            method=args.method, smoothing=args.smoothing,
            times_file=times_path, utc_offset=args.utc_offset, place=place_flags(args),
            clip=clip)
        clip, numbers, options = run.clip, run.frames, run.options
        if args.initial_sun:
            options.initial_sun = tuple(args.initial_sun)
        options.calibrated_confidence = not args.uncalibrated_confidence
        if args.refine_model is not None:  # else the scene's Refine Model
            options.refine_model = args.refine_model
        interrupt.check()
        # Flushed: a wrapper (or a test) waiting for the work to start sees it.
        print(f"sunlapse: estimating frames {numbers[0]}-{numbers[-1]} of clip '{clip.name}' "
              f"(Ctrl-C stops)", flush=True)
        track = estimate_run.run(run.scene, run.camera, clip.filepath, clip.frame_start, numbers,
                                 options, progress=interrupt.progress,
                                 frame_cameras=run.frame_cameras)
    except PlaceTimeError as e:
        fail(EXIT_USAGE, str(e))
    except gather.SceneError as e:
        fail(EXIT_SCENE, str(e))
    except errors.Cancelled:
        interrupt.check()  # Ctrl-C cancelled the run
        fail(EXIT_INTERRUPTED, "cancelled: nothing written, existing files left as they were")
    except errors.EstimateError as e:
        fail(EXIT_SCENE, str(e))
    interrupt.check()
    summary = report.finish_run(context, track, clip,
                                dict(run.record, method=args.method, frames=list(frames)))
    if report.report_level(track) == {"WARNING"}:
        print(f"sunlapse: warning: {summary}")
    init = track.initial
    if init:
        print(f"sunlapse: initial Sun zenith {init['zenith_deg']:.2f} azimuth "
              f"{init['azimuth_deg']:.2f} deg (confidence {init['confidence']:.2f}, "
              f"{init['seconds']:.2f} s){' - ' + init['message'] if init.get('message') else ''}")
    else:
        print(f"sunlapse: warning: {track.frames[0].reason}")
    for hint in (p for p in track.problems if not p.is_warning):
        print(f"sunlapse: note: {hint.message}")
    done = sum(1 for f in track.frames if f.has_estimate)
    timing = track.extra.get("timing", {})
    print(f"sunlapse: {done}/{len(track.frames)} frames estimated "
          f"(tracking {timing.get('tracking_ms_per_frame', 0):.1f} ms/frame)")
    dark = track.without_sunlight()
    if dark:
        dark_set = set(dark)
        predicted = sum(f.predicted for f in track.frames if f.frame in dark_set)
        print(f"sunlapse: no direct sunlight on {len(dark)} frame(s) "
              f"({trackfile.frame_ranges(dark)}): {predicted} of them have their Sun "
              f"predicted (from the path, or the ephemeris), at confidence 0")
    if args.apply_model_corrections:
        interrupt.check()
        try:
            said, skipped = model_fix.apply_corrections(context, track)
        except ValueError as e:
            print(f"sunlapse: note: {e}")
        else:
            print(f"sunlapse: {said}")
            for what in skipped:
                print(f"sunlapse: warning: model correction not applied to {what}")
            if not args.save and not args.render_ar:
                print("sunlapse: note: the corrected model is not saved: add --save OUT.blend")
    if args.apply_lamp or args.render_ar:
        interrupt.check()
        try:
            sun = keys.apply_track(context, track, context.scene.sunlapse.sun_lamp)
        except ValueError as e:
            fail(EXIT_SCENE, str(e))
        context.scene.sunlapse.sun_lamp = sun
        keyed = len(sun.get(keys.KEYED_FRAMES_PROP, []))
        print(f"sunlapse: keyed Sun lamp '{sun.name}' on {keyed} frames")
        if dark:
            print("sunlapse: the lamp's strength is keyed to 0 on the frames without "
                  "direct sunlight")
        skipped = track.extrapolated()
        if skipped:
            print(f"sunlapse: warning: {len(skipped)} frame(s) beyond the measured ones "
                  f"({skipped[0]}...{skipped[-1]}) only extrapolate the smoothing: not keyed")
    if args.render_ar:
        interrupt.check()
        try:
            print(f"sunlapse: {ar.setup(context)}")
        except (gather.SceneError, ValueError) as e:
            fail(EXIT_SCENE, str(e))
        try:
            os.makedirs(args.render_ar, exist_ok=True)
            ar.render_frames(context, os.path.abspath(args.render_ar), frames)
        except (OSError, RuntimeError) as e:
            fail(EXIT_USAGE, f"--render-ar {args.render_ar}: cannot write the renders there "
                             f"({_reason(e)})")
        print(f"sunlapse: rendered AR frames {frames[0]}-{frames[1]} to {args.render_ar}")
    if args.save:
        interrupt.check()
        try:
            save_blend_atomically(args.save)
        except (OSError, RuntimeError) as e:
            fail(EXIT_USAGE, f"--save {args.save}: cannot save the .blend there ({_reason(e)})")
        print(f"sunlapse: saved {args.save}")
    # The track file last: it exists only when everything above succeeded.
    interrupt.check()
    try:
        trackfile.write_track(args.out, track)
    except OSError as e:
        fail(EXIT_USAGE, f"--out {args.out}: cannot write the track file there ({_reason(e)})")
    print(f"sunlapse: wrote {args.out}")


def main(argv):
    """Runs with arguments `argv`; returns the exit code (0 on success)."""
    with _Interrupt() as interrupt:
        try:
            _run(argv, interrupt)
            return 0
        except CliError as e:
            message, code = str(e), e.code
        except SystemExit as e:  # argparse: usage already printed
            return int(e.code or 0) and EXIT_USAGE
        except KeyboardInterrupt:
            message, code = ("interrupted (Ctrl-C): nothing written, existing files left as "
                             "they were"), EXIT_INTERRUPTED
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
        sys.stderr.write("sunlapse: error: usage: "
                         "blender -c sunlapse SCENE.blend --out TRACK.json ...\n")
        return EXIT_USAGE
    try:
        bpy.ops.wm.open_mainfile(filepath=os.path.abspath(argv[0]))
    except RuntimeError as e:
        sys.stderr.write(f"sunlapse: error: cannot open {argv[0]}: {e}\n")
        return EXIT_SCENE
    return main(argv[1:])
