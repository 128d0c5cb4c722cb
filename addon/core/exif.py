"""Capture times and place of an image sequence from its EXIF data. bpy-free.

The cameras that shoot time-lapses write, in every frame, DateTimeOriginal
(local wall-clock time, no zone), often SubSecTimeOriginal and
OffsetTimeOriginal (the zone, EXIF 2.31), and with a GPS the position. The
local times are read in the file's own offset when it has one, else in the
given zone: an IANA zone (zoneinfo, daylight saving applied on each frame's
date) or a fixed UTC offset. Pillow (Debian's python3-pil) reads the tags.
"""

from __future__ import annotations

import datetime as dt
import os
import re
from dataclasses import dataclass
from typing import List, Optional, Sequence

EXIF_IFD = 0x8769
GPS_IFD = 0x8825
DATETIME_ORIGINAL = 0x9003
OFFSET_TIME_ORIGINAL = 0x9011
SUBSEC_TIME_ORIGINAL = 0x9291
DATETIME = 0x0132  # IFD0's (last changed): a fallback only
GPS_LAT_REF, GPS_LAT, GPS_LON_REF, GPS_LON = 1, 2, 3, 4


class ExifError(ValueError):
    """Capture times that cannot be read: says which file and why."""


@dataclass
class Capture:
    path: str
    time_utc: Optional[dt.datetime]      # aware, UTC; None: no time tag
    latitude_deg: Optional[float] = None   # north positive
    longitude_deg: Optional[float] = None  # east positive
    zone_from_file: bool = False          # OffsetTimeOriginal was present


def _rational(v) -> float:
    try:
        return float(v)
    except TypeError:  # an (numerator, denominator) pair
        return v[0] / v[1] if v[1] else 0.0


def _dms(values, ref) -> Optional[float]:
    if not values or len(values) < 3:
        return None
    deg = _rational(values[0]) + _rational(values[1]) / 60.0 + _rational(values[2]) / 3600.0
    ref = (ref or "").strip().upper() if isinstance(ref, str) else \
        bytes(ref or b"").decode("ascii", "ignore").strip().upper()
    return -deg if ref in ("S", "W") else deg


def _parse_offset(text) -> Optional[dt.tzinfo]:
    m = re.match(r"^\s*([+-])(\d{2}):?(\d{2})\s*$", str(text or ""))
    if m is None:
        return None
    sign = 1 if m.group(1) == "+" else -1
    return dt.timezone(sign * dt.timedelta(hours=int(m.group(2)), minutes=int(m.group(3))))


def parse_exif_time(text: str, subsec: str = "", tz: dt.tzinfo = dt.timezone.utc) -> dt.datetime:
    """'YYYY:MM:DD HH:MM:SS' (+ sub-second digits) in `tz` -> aware UTC."""
    try:
        t = dt.datetime.strptime(str(text).strip().rstrip("\x00"), "%Y:%m:%d %H:%M:%S")
    except ValueError:
        raise ValueError(f"'{text}' is not an EXIF date and time (YYYY:MM:DD HH:MM:SS)")
    digits = re.sub(r"\D", "", str(subsec or ""))
    if digits:
        t += dt.timedelta(seconds=float("0." + digits))
    return t.replace(tzinfo=tz).astimezone(dt.timezone.utc)


def read_capture(path: str, tz: dt.tzinfo) -> Capture:
    """The capture time and GPS position of one image (None where absent);
    ExifError when the file cannot be opened or its time is malformed."""
    try:
        from PIL import Image
    except ImportError:
        raise ExifError("reading EXIF needs Pillow (Debian: python3-pil; tools/install.sh "
                        "installs it)")
    try:
        with Image.open(path) as img:
            exif = img.getexif()
    except (OSError, ValueError) as e:
        raise ExifError(f"{path}: cannot be read ({e})")
    sub = exif.get_ifd(EXIF_IFD)
    text = sub.get(DATETIME_ORIGINAL) or exif.get(DATETIME)
    own = _parse_offset(sub.get(OFFSET_TIME_ORIGINAL))
    when = None
    if text:
        try:
            when = parse_exif_time(text, sub.get(SUBSEC_TIME_ORIGINAL, ""), own or tz)
        except ValueError as e:
            raise ExifError(f"{path}: {e}")
    gps = exif.get_ifd(GPS_IFD)
    lat = _dms(gps.get(GPS_LAT), gps.get(GPS_LAT_REF))
    lon = _dms(gps.get(GPS_LON), gps.get(GPS_LON_REF))
    return Capture(path, when, lat, lon, zone_from_file=own is not None)


def read_sequence(paths: Sequence[str], tz: dt.tzinfo) -> List[Capture]:
    """Captures of a sequence's files in frame order (the names come from
    the one parser of sequence names, native find_image_sequence), up to
    the first file missing: a frame past a gap has no time of its own."""
    out = []
    for p in paths:
        if not os.path.isfile(p):
            break
        out.append(read_capture(p, tz))
    return out


def times_by_frame(captures: Sequence[Capture], first_frame: int) -> Optional[dict]:
    """{frame: aware UTC time} numbering captures from `first_frame`; None
    unless every capture has a time (a partly dated sequence is ambiguous)."""
    if not captures or any(c.time_utc is None for c in captures):
        return None
    return {first_frame + i: c.time_utc for i, c in enumerate(captures)}


def place(captures: Sequence[Capture]):
    """(latitude, longitude), the median of the frames' GPS fixes, or None."""
    fixes = [(c.latitude_deg, c.longitude_deg) for c in captures
             if c.latitude_deg is not None and c.longitude_deg is not None]
    if not fixes:
        return None
    lats = sorted(f[0] for f in fixes)
    lons = sorted(f[1] for f in fixes)
    return lats[len(lats) // 2], lons[len(lons) // 2]
