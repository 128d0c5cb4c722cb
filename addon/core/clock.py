"""The clock: zones, local wall-clock time, and the frames' capture times as
seconds and order. One home for time, shared by the times file, EXIF, the
panel, the CLI and the estimate. bpy-free; times are aware datetimes."""

from __future__ import annotations

import datetime as dt
import math
from collections import Counter
from typing import List, Optional, Sequence


class ClockError(ValueError):
    """A zone or a time that cannot be: says what is valid."""


def zone(name: str = "", utc_offset_hours: float = 0.0) -> dt.tzinfo:
    """The IANA zone `name` (daylight saving applied on each date), or the
    fixed UTC offset when `name` is empty."""
    if name:
        try:
            from zoneinfo import ZoneInfo, ZoneInfoNotFoundError
        except ImportError:  # Python < 3.9
            raise ClockError("time zones by name need Python 3.9 or later (zoneinfo)")
        try:
            return ZoneInfo(name.strip())
        except (ZoneInfoNotFoundError, ValueError):
            raise ClockError(f"Time Zone '{name}' is not a known zone (an IANA name such as "
                             f"Europe/Paris or America/New_York)")
    try:
        hours = float(utc_offset_hours)
        if not -14.0 <= hours <= 14.0:
            raise ValueError
    except (TypeError, ValueError, OverflowError):
        raise ClockError(f"UTC offset {utc_offset_hours} is not a number of hours in [-14, 14]")
    return dt.timezone(dt.timedelta(hours=hours))


def utc_offset_hours(tz: dt.tzinfo, when: dt.datetime) -> float:
    """The zone's offset from UTC at `when` (daylight saving included), hours."""
    local = when.astimezone(tz) if when.tzinfo else when.replace(tzinfo=tz)
    offset = local.utcoffset()
    if offset is None:
        raise ClockError(f"time zone {tz!r} gives no UTC offset")
    return offset.total_seconds() / 3600.0


def local_start(day: dt.date, hours: float, tz: dt.tzinfo) -> dt.datetime:
    """`hours` of wall-clock time after midnight of `day` in `tz` (the
    offset of that day), aware."""
    wall = dt.datetime(day.year, day.month, day.day) + dt.timedelta(hours=hours)
    return wall.replace(tzinfo=tz)


def parse_time(text: str, tz: dt.tzinfo) -> dt.datetime:
    """An aware datetime from 'YYYY-MM-DD HH:MM[:SS]' (wall-clock time in
    `tz`) or ISO 8601 with an offset (kept)."""
    text = text.strip()
    try:
        t = dt.datetime.fromisoformat(text.replace(" ", "T", 1) if "T" not in text else text)
    except (ValueError, OverflowError):
        raise ValueError(f"'{text}' is not a date and time (YYYY-MM-DD HH:MM[:SS])")
    return t if t.tzinfo is not None else t.replace(tzinfo=tz)


def frame_times(first: dt.datetime, frame_seconds: float,
                frames: Sequence[int]) -> List[dt.datetime]:
    """UTC time of each frame, the first of `frames` at `first` (aware),
    `frame_seconds` apart."""
    if frame_seconds is None or not math.isfinite(frame_seconds) or frame_seconds <= 0:
        # 0 s puts every frame at one instant: a fixed Sun, confidently wrong.
        raise ValueError(f"seconds between frames must be a positive number, got {frame_seconds}")
    f0 = frames[0]
    return [(first + dt.timedelta(seconds=(f - f0) * frame_seconds)).astimezone(dt.timezone.utc)
            for f in frames]


def chronological(frames: Sequence[int], times: Optional[Sequence[dt.datetime]]) -> List[int]:
    """Positions 0..n-1 of `frames` in the order they were taken (ties keep
    the frame order); the frame order itself when the times are unknown."""
    n = len(frames)
    if times is None:
        return list(range(n))
    known: Sequence[dt.datetime] = times
    return sorted(range(n), key=lambda i: (known[i], frames[i]))


def orderless(times: Sequence[dt.datetime]) -> Optional[str]:
    """Why `times` say nothing of the order the frames were taken in, or
    None when they do. They do not when every frame has the same time, or
    when at least half the frames share their time with another and the
    times are whole days apart (dates without times of day) or a time's
    frames lie apart. A capture repeated over consecutive frames (the
    Marseille January clip shows each capture 13 times) still orders them."""
    if len(times) < 2:
        return None
    counts = Counter(times)
    if len(counts) == 1:
        return "every frame has the same time"
    shared = sum(c for c in counts.values() if c > 1)
    if 2 * shared < len(times):
        return None
    first = min(counts)
    if all((t - first).total_seconds() % 86400.0 == 0.0 for t in counts):
        return (f"{shared} of {len(times)} frames share their time with another, "
                f"{len(counts)} different times whole days apart: dates without times of day?")
    runs = 1 + sum(times[i] != times[i - 1] for i in range(1, len(times)))
    if runs == len(counts):
        return None  # each time's frames together: a capture repeated
    return (f"{shared} of {len(times)} frames share their time with another, "
            f"in {runs} runs of {len(counts)} different times")


def seconds_since(times: Sequence[dt.datetime]) -> List[float]:
    """Seconds of each time after the earliest."""
    t0 = min(times)
    return [(t - t0).total_seconds() for t in times]


def out_of_order(frames: Sequence[int], times: Sequence[dt.datetime]) -> List[int]:
    """Frames taken before the frame decoded just ahead of them."""
    return [frames[i] for i in range(1, len(frames)) if times[i] < times[i - 1]]
