"""Scores sunlapse on the real Marseille sundial clips against the ephemeris.

  /usr/bin/python3 bench/real.py [--out DIR] [--methods default thesis] [--footage DIR]

For each clip it runs the scripted estimate (examples/run_estimate.py,
exactly as a user would) on examples/real/<clip>.blend, builds the truth from
the frames' local time stamps (*.times.csv, UTC+1) at 43 deg 18' N,
5 deg 24' E with the native ephemeris, and prints the thesis's Table 5.1 for
every method. The January clip repeats each capture for 13 frames: each
capture is scored once, on its first frame. Rows "(confident)" leave out
frames whose track confidence is below 0.5 (the track marks them). The
footage is read from ../shared/real/marseille-sundial beside the work tree
(the .blend files point there); a missing folder skips the run with a note.
"""
import argparse
import csv
import datetime as dt
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "addon"))

from core import evaluation, trackfile  # noqa: E402

LAT, LON, UTC_OFFSET = 43.3, 5.4, 1.0
CLIPS = ("marseille-2005-01-13", "marseille-2005-03-21")
CONFIDENT = 0.5


def truth_track(times_csv, sun_position):
    """One truth frame per capture (the first frame showing each time stamp)."""
    seen, frames = set(), []
    with open(times_csv) as f:
        for row in csv.DictReader(f):
            stamp = row["local_time"].strip()
            if stamp in seen:
                continue
            seen.add(stamp)
            utc = dt.datetime.strptime(stamp, "%Y-%m-%d %H:%M") - dt.timedelta(hours=UTC_OFFSET)
            z, a = sun_position(utc.year, utc.month, utc.day, utc.hour, utc.minute, 0.0, LAT, LON)
            frames.append(trackfile.FrameEstimate(frame=int(row["frame"]), zenith_deg=z,
                                                  azimuth_deg=a, confidence=1.0))
    return trackfile.Track(frames=frames)


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
         "physical": ["--method", "default", "--smoothing", "physical", "--fit-latitude"],
         "physical_lat": ["--method", "default", "--smoothing", "physical", "--fixed-latitude"]}


def run_clip(blend, out_json, method, log):
    cmd = ["blender", "-b", blend, "--python-exit-code", "1", "--python",
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


def raw_view(track):
    """The tracker's own angles (before smoothing), as a track."""
    out = trackfile.Track(north_offset_deg=0.0, initial=track.initial, extra=track.extra)
    out.frames = [trackfile.FrameEstimate(frame=f.frame, zenith_deg=f.raw_zenith_deg,
                                          azimuth_deg=f.raw_azimuth_deg, confidence=f.confidence)
                  for f in track.frames]
    return out


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", default=os.path.join(ROOT, "build", "real"))
    p.add_argument("--methods", nargs="+",
                   default=["default", "physical", "physical_lat", "thesis"],
                   choices=sorted(FLAGS))
    p.add_argument("--clips", nargs="+", default=list(CLIPS), choices=CLIPS)
    p.add_argument("--footage", default=os.path.join(os.path.dirname(ROOT), "shared", "real",
                                                     "marseille-sundial"))
    p.add_argument("--plots", action="store_true", help="write one PNG per clip and method")
    args = p.parse_args(argv)
    if not os.path.isdir(args.footage):
        print(f"real: no footage at {args.footage}: skipped")
        return []
    import _native as native  # built by tools/install.sh into addon/
    os.makedirs(args.out, exist_ok=True)
    reports = []
    for clip in args.clips:
        truth = truth_track(os.path.join(args.footage, f"{clip}.times.csv"), native.sun_position)
        blend = os.path.join(ROOT, "examples", "real", f"{clip}.blend")
        for method in args.methods:
            name = f"{clip[10:]}/{method}"
            out_json = os.path.join(args.out, f"{clip}.{method}.sun.json")
            code = run_clip(blend, out_json, method, out_json + ".log")
            if code != 0 or not os.path.exists(out_json):
                reports.append(evaluation.evaluate(name, None, truth,
                                                   message=f"run failed (see {out_json}.log)"))
                continue
            track = trackfile.read_track(out_json)
            for label, view in ((name + " raw", raw_view(track)),
                                (name + " smoothed", geographic(track)),
                                (name + " raw, confident", confident_only(raw_view(track)))):
                r = evaluation.evaluate(label, view, truth)
                reports.append(r)
                if args.plots and label.endswith("smoothed"):
                    evaluation.plot(r, os.path.join(args.out, f"{clip}.{method}.png"))
    print(evaluation.format_table(reports))
    return reports


if __name__ == "__main__":
    main()
