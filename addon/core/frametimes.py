"""Per-frame capture times of a time-lapse (the "times file").

Time-lapse cameras rarely shoot at a fixed rate: captures get skipped,
repeated (the same image held for several video frames) or, as in the March
sundial clip, stored out of order. When the user knows each frame's time, a
CSV file gives it, one row per frame:

    frame,local_time
    1,2005-03-21 18:08
    2,2005-03-21 08:06

`frame` is the clip's frame number (1 = the clip's first frame, decode order,
the clip's own numbering, not the scene's); the time column (named
`local_time`, `time` or `utc_time`) is `YYYY-MM-DD HH:MM[:SS]` in local time
(the UTC offset is given separately) or ISO 8601 with its own offset
(`2005-03-21T08:06:00+01:00`). `utc_time` columns are read as UTC.

The estimate uses the times to visit frames in the order they were taken,
to smooth over real time instead of frame numbers and, for physical
smoothing, as the clock of each frame. bpy-free.
"""

from __future__ import annotations

import csv
import datetime as dt
import io
from typing import Dict, List, Sequence

from . import clock

TIME_COLUMNS = ("local_time", "time", "utc_time")


class FrameTimesError(ValueError):
    """A times file that cannot be used: says which file, line and why."""


def _decode(data: bytes, path: str) -> str:
    """Text of a times file: UTF-8 (with or without the byte-order mark
    Excel writes), else Windows-1252 (Excel's "CSV" on Windows in the West)."""
    if b"\x00" in data:
        raise FrameTimesError(f"times file {path}: not a text file (it holds NUL bytes); "
                              f"save it as CSV text")
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError:
        pass
    try:
        return data.decode("cp1252")
    except UnicodeDecodeError as e:
        raise FrameTimesError(f"times file {path}: neither UTF-8 nor Windows-1252 text "
                              f"(byte {e.start}); save it as UTF-8 CSV")


# Larger is not a times file (a million frames of ~30 bytes each).
MAX_BYTES = 64 * 1024 * 1024


def read_times(path: str, tz_local: dt.tzinfo = dt.timezone.utc) -> Dict[int, dt.datetime]:
    """{clip frame number: aware UTC datetime} from a times CSV whose local
    times are wall-clock times in `tz_local` (clock.zone: a fixed offset, or
    a named zone whose daylight saving each row's own date decides). Raises
    FrameTimesError (only) naming the file, the line and what is valid."""
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_BYTES + 1)
    except FileNotFoundError:
        raise FrameTimesError(f"times file {path}: no such file")
    except IsADirectoryError:
        raise FrameTimesError(f"times file {path}: is a folder, not a CSV file")
    except OSError as e:
        raise FrameTimesError(f"times file {path}: cannot be read ({e.strerror or e})")
    if len(data) > MAX_BYTES:
        raise FrameTimesError(f"times file {path}: larger than {MAX_BYTES >> 20} MB, "
                              f"not a times file")
    text = _decode(data, path)
    try:
        return _parse(io.StringIO(text, newline=""), path, tz_local)
    except csv.Error as e:
        raise FrameTimesError(f"times file {path}: not readable as CSV ({e})")


def _parse(fh, path: str, tz_local: dt.tzinfo) -> Dict[int, dt.datetime]:
    reader = csv.DictReader(fh)
    fields = [str(f).strip() for f in (reader.fieldnames or [])]
    reader.fieldnames = fields
    column = next((c for c in TIME_COLUMNS if c in fields), None)
    if "frame" not in fields or column is None:
        shown = ", ".join(f[:40] for f in fields[:8]) or "none"
        raise FrameTimesError(f"times file {path}: needs a header with 'frame' and one of "
                              f"{', '.join(TIME_COLUMNS)} (found: {shown})")
    tz = dt.timezone.utc if column == "utc_time" else tz_local
    table: Dict[int, dt.datetime] = {}
    for row in reader:
        line = reader.line_num
        if not any((v or "").strip() for v in row.values() if isinstance(v, str)):
            continue  # blank line
        try:
            frame_text = str(row["frame"] or "").strip()
            if not frame_text.lstrip("+-").isdigit() or len(frame_text) > 9:
                raise ValueError(f"frame '{frame_text[:20]}' is not a whole number")
            frame = int(frame_text)
            when = clock.parse_time(str(row[column] or "")[:64], tz)
            utc = when.astimezone(dt.timezone.utc)
        except (ValueError, TypeError, OverflowError) as e:
            raise FrameTimesError(f"times file {path}, line {line}: {e}")
        if frame in table:
            raise FrameTimesError(f"times file {path}, line {line}: frame {frame} "
                                  f"is listed twice")
        table[frame] = utc
    if not table:
        raise FrameTimesError(f"times file {path}: no frames listed")
    return table


def times_for(table: Dict[int, dt.datetime], clip_frames: Sequence[int],
              path: str = "times file") -> List[dt.datetime]:
    """The time of each of `clip_frames` (clip numbering); every one must be
    listed, else FrameTimesError names the first missing ones."""
    missing = [f for f in clip_frames if f not in table]
    if missing:
        shown = ", ".join(str(f) for f in missing[:5]) + (" ..." if len(missing) > 5 else "")
        raise FrameTimesError(f"{path} has no time for clip frame(s) {shown}")
    return [table[f] for f in clip_frames]
