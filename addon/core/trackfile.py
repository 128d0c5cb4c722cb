"""The track file (``*.sun.json``, DESIGN.md §3): writer and reader.

bpy-free so that scripted runs, the evaluation tools and tests share it.
Angles are degrees; ``azimuth_deg`` is clockwise from north (or from the
scene's +Y when north is unknown) and ``north_offset_deg`` says how +Y is
turned from north, as in Blender's Sun Position add-on.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional

FORMAT_TRACK = "sunlapse.track"
FORMAT_TRUTH = "sunlapse.truth"
VERSION = 1


class TrackFileError(ValueError):
    """A track file that cannot be read: says which file and what is wrong."""


@dataclass
class FrameEstimate:
    frame: int
    zenith_deg: Optional[float] = None
    azimuth_deg: Optional[float] = None
    raw_zenith_deg: Optional[float] = None
    raw_azimuth_deg: Optional[float] = None
    confidence: float = 0.0
    shadow_start_px: Optional[List[float]] = None
    shadow_end_px: Optional[List[float]] = None
    reason: Optional[str] = None
    # Sun / ambient light on the ground (from the shadow fit); optional.
    sun_ambient_ratio: Optional[float] = None
    # Capture time (ISO 8601, UTC) when the run was given the frames' times.
    time_utc: Optional[str] = None

    @property
    def has_estimate(self) -> bool:
        return self.zenith_deg is not None and self.azimuth_deg is not None


@dataclass
class Track:
    clip: str = ""
    frame_start: int = 1
    north_offset_deg: float = 0.0
    format: str = FORMAT_TRACK
    method: Dict[str, Any] = field(default_factory=dict)
    initial: Optional[Dict[str, Any]] = None
    frames: List[FrameEstimate] = field(default_factory=list)
    # Anything a reader does not know is kept, so a round trip loses nothing.
    extra: Dict[str, Any] = field(default_factory=dict)

    def frame(self, number: int) -> Optional[FrameEstimate]:
        for f in self.frames:
            if f.frame == number:
                return f
        return None


def _num(value: Any) -> Optional[float]:
    if value is None:
        return None
    value = float(value)
    return value if math.isfinite(value) else None


def _frame_to_json(f: FrameEstimate) -> Dict[str, Any]:
    d: Dict[str, Any] = {
        "frame": int(f.frame),
        "zenith_deg": _num(f.zenith_deg),
        "azimuth_deg": _num(f.azimuth_deg),
        "raw_zenith_deg": _num(f.raw_zenith_deg),
        "raw_azimuth_deg": _num(f.raw_azimuth_deg),
        "confidence": float(f.confidence),
    }
    if f.time_utc is not None:
        d["time_utc"] = str(f.time_utc)
    if f.sun_ambient_ratio is not None:
        d["sun_ambient_ratio"] = float(f.sun_ambient_ratio)
    if f.shadow_start_px is not None and f.shadow_end_px is not None:
        d["shadow"] = {"start_px": [float(v) for v in f.shadow_start_px],
                       "end_px": [float(v) for v in f.shadow_end_px]}
    if f.reason is not None or d["zenith_deg"] is None or d["azimuth_deg"] is None:
        d["reason"] = f.reason or "no estimate"
    return d


def _clean(value: Any) -> Any:
    """JSON has no NaN or infinity: such numbers become null, at any depth."""
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: _clean(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_clean(v) for v in value]
    return value


def to_json(track: Track) -> Dict[str, Any]:
    d: Dict[str, Any] = dict(track.extra)
    d.update({
        "format": track.format,
        "version": VERSION,
        "clip": track.clip,
        "frame_start": int(track.frame_start),
        "north_offset_deg": float(track.north_offset_deg),
        "method": track.method,
        "initial": track.initial,
        "frames": [_frame_to_json(f) for f in track.frames],
    })
    return _clean(d)


def write_track(path: str, track: Track) -> None:
    """Writes atomically: a crash mid-write never leaves a half file behind."""
    text = json.dumps(to_json(track), indent=1, allow_nan=False)
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".sunlapse-", suffix=".json", dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.write("\n")
        # mkstemp makes the file private; give it the usual mode.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


_KNOWN = {"format", "version", "clip", "frame_start", "north_offset_deg",
          "method", "initial", "frames"}


def from_json(d: Dict[str, Any], source: str = "<track>") -> Track:
    if not isinstance(d, dict):
        raise TrackFileError(f"{source}: not a JSON object")
    fmt = d.get("format")
    if fmt not in (FORMAT_TRACK, FORMAT_TRUTH):
        raise TrackFileError(f"{source}: format is {fmt!r}, expected "
                             f"{FORMAT_TRACK!r} or {FORMAT_TRUTH!r}")
    version = d.get("version")
    if not isinstance(version, int) or version > VERSION or version < 1:
        raise TrackFileError(f"{source}: unsupported version {version!r} "
                             f"(this reader knows 1..{VERSION})")
    frames = []
    for i, fd in enumerate(d.get("frames") or []):
        try:
            shadow = fd.get("shadow") or {}
            frames.append(FrameEstimate(
                frame=int(fd["frame"]),
                zenith_deg=_num(fd.get("zenith_deg")),
                azimuth_deg=_num(fd.get("azimuth_deg")),
                raw_zenith_deg=_num(fd.get("raw_zenith_deg")),
                raw_azimuth_deg=_num(fd.get("raw_azimuth_deg")),
                confidence=float(fd.get("confidence") or 0.0),
                shadow_start_px=shadow.get("start_px"),
                shadow_end_px=shadow.get("end_px"),
                reason=fd.get("reason"),
                sun_ambient_ratio=_num(fd.get("sun_ambient_ratio")),
                time_utc=fd.get("time_utc"),
            ))
        except (KeyError, TypeError, ValueError) as e:
            raise TrackFileError(f"{source}: frame entry {i} is malformed: {e}")
    return Track(
        clip=str(d.get("clip") or ""),
        frame_start=int(d.get("frame_start") or 1),
        north_offset_deg=float(d.get("north_offset_deg") or 0.0),
        format=fmt,
        method=d.get("method") or {},
        initial=d.get("initial"),
        frames=frames,
        extra={k: v for k, v in d.items() if k not in _KNOWN},
    )


def read_track(path: str) -> Track:
    """Reads a track or truth file; raises TrackFileError with the reason."""
    try:
        with open(path, "r", encoding="utf-8") as fh:
            d = json.load(fh)
    except FileNotFoundError:
        raise TrackFileError(f"{path}: no such file")
    except json.JSONDecodeError as e:
        raise TrackFileError(f"{path}: not valid JSON ({e})")
    return from_json(d, source=path)
