"""What a finished run tells the user: the track stored and summarised in
their words (its problems, the commonest reason frames lack a Sun), the
report's level, and a frame's capture time."""

import datetime as dt
from collections import Counter

from . import store
from .place import settings_zone
from ..core import clock, trackfile


def finish_run(context, track, clip, extra):
    """Main thread: keeps the result in the .blend and summarises it."""
    track.clip = clip.filepath
    track.method["options"].update(extra)
    store.store_track(track)
    done = len(track.estimated())
    raw = sum(1 for f in track.frames if _measured(f))
    dark = sum(1 for f in track.frames if _dark(f))
    guessed = sum(1 for f in track.frames if f.predicted and f.has_estimate and not _dark(f))
    msg = (f"Sun estimated on {done}/{len(track.frames)} frames ({raw} measured"
           + (f", {dark} predicted without direct sunlight" if dark else "")
           + (f", {guessed} predicted without a Sun measured there" if guessed else "")
           + (", the rest from smoothing)" if done > raw + dark + guessed else ")"))
    # What kept frames from a measurement, in the user's words (night is
    # no fault: said above).
    problems = [p.message for p in track.problems if p.is_warning]
    reasons = Counter(f.reason for f in track.frames
                      if not _measured(f) and f.reason and not _dark(f))
    if reasons and track.problem("estimate") is None:
        reason, count = reasons.most_common(1)[0]
        problems.append(f"{count} frame(s): {reason}")
    if problems:
        msg += ": " + "; ".join(problems)
    for hint in (p for p in track.problems if not p.is_warning):  # advisory: not a warning
        msg += ". Note: " + hint.message
    context.scene.sunlapse.last_report = msg
    return msg


def _measured(f):
    """A frame whose Sun is its own measurement, smoothed (a track file
    may carry raw angles on a predicted frame: not this add-on's)."""
    return f.raw_zenith_deg is not None and not f.predicted


def _dark(f):
    """A frame without direct sunlight whose Sun is its path's: told, not
    a shortcoming of the run."""
    return f.predicted and f.sunlight == trackfile.Sunlight.NO


def report_level(track):
    """WARNING when frames lack a measurement or a stage had to give up."""
    short = any(not _measured(f) and not _dark(f) for f in track.frames)
    troubled = any(p.is_warning for p in track.problems)
    return {"WARNING"} if short or troubled else {"INFO"}


def frame_time_utc(settings, track, frame):
    """The capture time (aware UTC) of `frame`: the track's own (times file,
    EXIF) or the panel's date, start time and seconds per frame; None."""
    est = track.frame(frame) if track is not None else None
    if est is not None and est.time_utc:
        return dt.datetime.fromisoformat(est.time_utc)
    if not settings.date or settings.frame_seconds <= 0:
        return None
    try:
        day = dt.date.fromisoformat(settings.date)
    except ValueError:
        return None
    first = track.frames[0].frame if track is not None and track.frames else frame
    start = clock.local_start(day, settings.start_hour, settings_zone(settings))
    return (start + dt.timedelta(seconds=settings.frame_seconds * (frame - first))).astimezone(
        dt.timezone.utc)
