"""Scores sunlapse on the real clips (the Marseille sundial, AMOS webcams) against the ephemeris.

  /usr/bin/python3 bench/real.py [--out DIR] [--methods default thesis] [--footage DIR]
      [--clips CLIP ...] [--amos-footage DIR]

For each clip it runs the scripted estimate (examples/run_estimate.py,
exactly as a user would) on examples/real/<clip>.blend, builds the truth from
the frames' local time stamps (*.times.csv, UTC+1) at 43 deg 18' N,
5 deg 24' E with the native ephemeris, and prints the thesis's Table 5.1 for
every method. The January clip repeats each capture for 13 frames: each
capture is scored once, on its first frame. Rows "(confident)" leave out
frames whose track confidence is below 0.5 (the track marks them). The
footage is read from ../shared/real/marseille-sundial beside the work tree
(the .blend files point there); a missing folder skips the run with a note.

The AMOS webcam clips (amos-mulhouse, amos-stlouis; footage in
../shared/real/amos, filled by examples/real/amos_fetch.py; a missing folder
skips them with a note) have one capture per frame with UTC stamps
(utc_time); they are scored on the frames where the Sun is at least 4 deg up.
Their north is given with the scene (the Sun Position add-on's north offset,
so their runs enable that add-on: `--addons sun_position`), and their
azimuths are scored in that north: a run's geographic azimuth plus the north
offset it used (physical smoothing fits its own) minus the given one, so a
fitted north that disagrees with the scene's costs azimuth. A line per run
lists how the frames with the Sun below the horizon were flagged, and the
north physical smoothing fitted. Each clip's truth is written beside its
tracks as DIR/<clip>.truth.sun.json (with the scene's north), for
bench/sky_costs.py.
"""
import argparse
import csv
import dataclasses
import datetime as dt
import math
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "addon"))

from core import evaluation, trackfile  # noqa: E402

# Per clip: its footage family (the --footage / --amos-footage folder), the
# short name of its rows, the place, the times file's column and the offset of
# its times from UTC, whether its north is known, and the lowest Sun scored.
# A clip with `north_offset_deg` has its north given with the scene (the Sun
# Position add-on's north offset in its .blend, which its runs enable).
MARSEILLE = dict(footage="marseille", lat=43.3, lon=5.4, column="local_time", utc_offset=1.0,
                 north_known=True, min_elevation=None)
CLIP_SPECS = {
    "marseille-2005-01-13": dict(MARSEILLE, short="2005-01-13"),
    "marseille-2005-03-21": dict(MARSEILLE, short="2005-03-21"),
    "amos-mulhouse": dict(footage="amos", short="mulhouse", lat=47.7467, lon=7.3386,
                          column="utc_time", utc_offset=0.0, north_known=True,
                          north_offset_deg=-28.0, min_elevation=4.0),
    "amos-stlouis": dict(footage="amos", short="stlouis", lat=38.6260, lon=-90.1905,
                         column="utc_time", utc_offset=0.0, north_known=True,
                         north_offset_deg=0.0, min_elevation=4.0),
}
CLIPS = tuple(CLIP_SPECS)
CONFIDENT = 0.5


def truth_track(times_csv, sun_position, spec=CLIP_SPECS["marseille-2005-01-13"]):
    """One truth frame per capture (the first frame showing each time stamp)."""
    seen, frames = set(), []
    with open(times_csv) as f:
        for row in csv.DictReader(f):
            stamp = row[spec["column"]].strip()
            if stamp in seen:
                continue
            seen.add(stamp)
            fmt = "%Y-%m-%d %H:%M:%S" if stamp.count(":") == 2 else "%Y-%m-%d %H:%M"
            utc = dt.datetime.strptime(stamp, fmt) - dt.timedelta(hours=spec["utc_offset"])
            z, a = sun_position(utc.year, utc.month, utc.day, utc.hour, utc.minute,
                                float(utc.second), spec["lat"], spec["lon"])
            frames.append(trackfile.FrameEstimate(frame=int(row["frame"]), zenith_deg=z,
                                                  azimuth_deg=a, confidence=1.0))
    return trackfile.Track(frames=frames)


def sun_up(truth, min_elevation):
    """The truth frames with the Sun at least `min_elevation` deg up."""
    out = trackfile.Track(north_offset_deg=truth.north_offset_deg)
    out.frames = [f for f in truth.frames if 90.0 - f.zenith_deg >= min_elevation]
    return out


def azimuth_offset(track, truth):
    """The circular median of truth minus estimate (deg) over the truth's
    frames: the one rotation an unknown north leaves between them."""
    est = {f.frame: f.azimuth_deg for f in track.frames if f.azimuth_deg is not None}
    diffs = sorted(((t.azimuth_deg - est[t.frame] + 180.0) % 360.0) - 180.0
                   for t in truth.frames if t.frame in est)
    if not diffs:
        return 0.0
    # The median of the differences about their circular mean.
    mean = math.degrees(math.atan2(sum(math.sin(math.radians(d)) for d in diffs),
                                   sum(math.cos(math.radians(d)) for d in diffs)))
    rel = sorted(((d - mean + 180.0) % 360.0) - 180.0 for d in diffs)
    return mean + rel[len(rel) // 2]


def rotated(track, offset):
    out = trackfile.Track(north_offset_deg=0.0, initial=None, extra=track.extra)
    out.frames = [trackfile.FrameEstimate(
        frame=f.frame, zenith_deg=f.zenith_deg,
        azimuth_deg=None if f.azimuth_deg is None else (f.azimuth_deg + offset) % 360.0,
        confidence=f.confidence) for f in track.frames]
    return out


def sunlight_summary(track, truth):
    """How the frames with the Sun below the horizon, and the frames flagged
    without direct sunlight, came back."""
    by = {f.frame: f for f in track.frames}
    below = [t.frame for t in truth.frames if t.zenith_deg > 90.0]
    parts = []
    for n in below:
        f = by.get(n)
        state = "missing" if f is None else (
            f"{f.sunlight.value if f.sunlight is not None else '-'}"
            f"{', predicted' if f.predicted else ''}")
        parts.append(f"{n} ({state})")
    flags = {}
    for f in track.frames:
        if f.sunlight is not None and f.sunlight.value != "yes":
            flags.setdefault(f.sunlight.value, []).append(f.frame)
    return (f"Sun below the horizon: {', '.join(parts) or 'none'}; "
            + "; ".join(f"sunlight {k}: {len(v)} frame(s) {v}" for k, v in sorted(flags.items())))


def confident_only(track):
    out = trackfile.Track(north_offset_deg=track.north_offset_deg, initial=track.initial,
                          extra=track.extra)
    out.frames = [f for f in track.frames if f.confidence >= CONFIDENT]
    return out


# What each "method" runs: the thesis baseline, ours with two-pass smoothing
# and ours with physical smoothing (the Sun's path through the raw angles,
# clocked by the frames' times; the place comes from the .blend).
FLAGS = {"default": ["--method", "default"],
         "thesis": ["--method", "thesis"],
         # The hand-made model refined by the clip first (issue 25 item 5;
         # the default since 2026-11-29), and the model as it is.
         "refined": ["--method", "default", "--refine-model"],
         "unrefined": ["--method", "default", "--no-refine-model"],
         "physical": ["--method", "default", "--smoothing", "physical", "--fit-latitude"],
         "physical_lat": ["--method", "default", "--smoothing", "physical", "--fixed-latitude"]}


def run_clip(blend, out_json, method, log, addons=()):
    cmd = ["blender", "-b", blend] + (["--addons", ",".join(addons)] if addons else []) + [
           "--python-exit-code", "1", "--python",
           os.path.join(ROOT, "examples", "run_estimate.py"), "--",
           "--out", out_json] + FLAGS[method]
    with open(log, "w") as f:
        return subprocess.run(cmd, stdout=f, stderr=subprocess.STDOUT).returncode


def geographic(track):
    """The track scored on its geographic azimuths (azimuth_deg), whatever
    north offset it states: the ephemeris is geographic, and the dial's own
    noon line (the scene's +Y) is not known to point true north. (Physical
    smoothing fits a north offset; scoring world azimuths would credit it.)"""
    out = trackfile.Track(north_offset_deg=0.0, initial=track.initial, extra=track.extra)
    out.frames = track.frames
    return out


def in_given_north(view, track_north_deg, given_north_deg):
    """A view's azimuths turned into the scene's given north: the run's
    geographic azimuth plus the north offset it used (physical smoothing fits
    its own) is the world azimuth, and the world azimuth minus the given
    north offset is geographic in the scene's north."""
    return rotated(view, track_north_deg - given_north_deg)


def raw_view(track):
    """The tracker's own angles (before smoothing), as a track."""
    out = trackfile.Track(north_offset_deg=0.0, initial=track.initial, extra=track.extra)
    out.frames = [trackfile.FrameEstimate(frame=f.frame, zenith_deg=f.raw_zenith_deg,
                                          azimuth_deg=f.raw_azimuth_deg, confidence=f.confidence)
                  for f in track.frames]
    return out


def clip_truth(times_csv, sun_position, spec):
    """(truth, scored, kept): the ephemeris at each capture (geographic:
    north offset 0, as scored_views turns the runs), its frames scored (the
    Sun high enough), and the truth kept beside the runs in the scene's
    north (for the sky's costs against it: bench/sky_costs.py TRUTH)."""
    truth = truth_track(times_csv, sun_position, spec)
    scored = truth if spec["min_elevation"] is None else sun_up(truth, spec["min_elevation"])
    kept = dataclasses.replace(truth, north_offset_deg=spec.get("north_offset_deg") or 0.0)
    return truth, scored, kept


def scored_views(name, track, spec, scored):
    """[(label, view)] of a run's track, scored against `scored` (the
    ephemeris, geographic: north offset 0): its raw angles, smoothed, and
    raw where confident; in the scene's given north where it has one
    (in_given_north), or each turned by the rotation an unknown north
    leaves (azimuth_offset)."""
    views = [(name + " raw", raw_view(track)),
             (name + " smoothed", geographic(track)),
             (name + " raw, confident", confident_only(raw_view(track)))]
    given = spec.get("north_offset_deg")
    if given is not None:
        views = [(label, in_given_north(view, track.north_offset_deg, given))
                 for label, view in views]
    if not spec["north_known"]:
        views = [(f"{label} (azimuth +{off:.1f})", rotated(view, off))
                 for label, view in views
                 for off in [azimuth_offset(view, scored)]]
    return views


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join(ROOT, "build", "real"))
    p.add_argument("--methods", nargs="+",
                   default=["default", "physical", "physical_lat", "thesis"],
                   choices=sorted(FLAGS))
    p.add_argument("--clips", nargs="+", default=list(CLIPS), choices=CLIPS)
    p.add_argument("--footage", default=os.path.join(os.path.dirname(ROOT), "shared", "real",
                                                     "marseille-sundial"))
    p.add_argument("--amos-footage", default=os.path.join(os.path.dirname(ROOT), "shared", "real",
                                                          "amos"))
    p.add_argument("--plots", action="store_true", help="write one PNG per clip and method")
    args = p.parse_args(argv)
    folders = {"marseille": args.footage, "amos": args.amos_footage}
    clips = []
    for clip in args.clips:
        folder = folders[CLIP_SPECS[clip]["footage"]]
        if os.path.isdir(folder):
            clips.append(clip)
        else:
            print(f"real: no footage at {folder}: {clip} skipped")
    if not clips:
        return []
    import _native as native  # built by tools/install.sh into addon/
    os.makedirs(args.out, exist_ok=True)
    reports, notes = [], []
    for clip in clips:
        spec = CLIP_SPECS[clip]
        folder = folders[spec["footage"]]
        truth, scored, kept = clip_truth(os.path.join(folder, f"{clip}.times.csv"),
                                         native.sun_position, spec)
        trackfile.write_track(os.path.join(args.out, f"{clip}.truth.sun.json"), kept)
        blend = os.path.join(ROOT, "examples", "real", f"{clip}.blend")
        for method in args.methods:
            name = f"{spec['short']}/{method}"
            out_json = os.path.join(args.out, f"{clip}.{method}.sun.json")
            given = spec.get("north_offset_deg")
            code = run_clip(blend, out_json, method, out_json + ".log",
                            addons=("sun_position",) if given is not None else ())
            if code != 0 or not os.path.exists(out_json):
                reports.append(evaluation.evaluate(name, None, truth,
                                                   message=f"run failed (see {out_json}.log)"))
                continue
            track = trackfile.read_track(out_json)
            views = scored_views(name, track, spec, scored)
            if given is not None:
                fit = track.extra.get("sun_path_fit")
                notes.append(f"{name}: north offset used {track.north_offset_deg:+.1f} deg "
                             f"({'fitted' if fit else 'given'}; scene {given:+.1f})")
            if spec["min_elevation"] is not None and method != "thesis":
                notes.append(f"{name}: {sunlight_summary(track, truth)}")
            for label, view in views:
                r = evaluation.evaluate(label, view, scored)
                reports.append(r)
                if args.plots and " smoothed" in label:
                    evaluation.plot(r, os.path.join(args.out, f"{clip}.{method}.png"))
    print(evaluation.format_table(reports))
    for note in notes:
        print(note)
    return reports


if __name__ == "__main__":
    main()
