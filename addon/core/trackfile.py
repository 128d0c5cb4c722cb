"""The track file (``*.sun.json``, docs/track-format.md): writer and reader.

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
from enum import Enum
from typing import Any, Dict, List, Literal, Optional, Tuple, overload

FORMAT_TRACK = "sunlapse.track"
FORMAT_TRUTH = "sunlapse.truth"
VERSION = 1


class TrackFileError(ValueError):
    """A track file that cannot be read: says which file and what is wrong."""


class Sunlight(str, Enum):
    """Whether direct sunlight reaches the scene on a frame, as its footage
    shows: YES (shadows the Sun casts), NO (none where the Sun's shadows
    would show, or the Sun below the horizon: night, twilight, cloud, the
    scene in shade), UNKNOWN (the frame cannot tell: not readable, no
    frame of its segment shows shadows, or the model casts no shadow on the
    ground in view under the path's Sun)."""
    YES = "yes"
    NO = "no"
    UNKNOWN = "unknown"


class ConfidenceKind(str, Enum):
    """What a track's per-frame confidence is (the track's
    method["confidence"]): PROBABILITY, the chance that the frame's Sun is
    within 2 deg of the true one (ours, calibrated on the suite); SUPPORT,
    the estimator's own score (the thesis baseline's, an uncalibrated run's,
    and files written before it was calibrated)."""
    PROBABILITY = "probability within 2 deg"
    SUPPORT = "support"

    @classmethod
    def of(cls, track: "Track") -> "ConfidenceKind":
        try:
            return cls(track.method.get("confidence", cls.SUPPORT.value))
        except ValueError:
            return cls.SUPPORT


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
    # Share of the tracked shadows' band the fitted Sun leaves on the wrong
    # side of its edges (0..1): how well the model's shadows fit; optional.
    shadow_misfit: Optional[float] = None
    # How far (deg) the Sun's height could move before the tracked shadows
    # fit worse: 0.5-8, or 90 when their far ends are out of view and any
    # height fits alike; optional.
    sun_height_pinned_deg: Optional[float] = None
    # Capture time (ISO 8601, UTC) when the run was given the frames' times.
    time_utc: Optional[str] = None
    # Direct sunlight on the frame (None: not decided, e.g. the thesis
    # method, older files).
    sunlight: Optional[Sunlight] = None
    # The Sun is predicted from its segment's path, not measured on the
    # frame (its confidence is 0).
    predicted: bool = False

    @property
    def has_estimate(self) -> bool:
        return self.zenith_deg is not None and self.azimuth_deg is not None


class ProblemKind(str, Enum):
    """What a problem means for the user: a stage gave up (FAILED) or chose
    another way (FELL_BACK), both warnings; or a hint to act on (HINT)."""
    FAILED = "failed"
    FELL_BACK = "fell_back"
    HINT = "hint"


@dataclass(frozen=True)
class Problem:
    """Something a stage of the run reports to the user, in their words.
    stage: "estimate", "tracking", "smoothing", "model", "times", "confidence",
    "prediction", "clock" (docs/track-format.md)."""
    stage: str
    kind: ProblemKind
    message: str

    @property
    def is_warning(self) -> bool:
        return self.kind != ProblemKind.HINT


# The keys the track file has always carried each stage's message under
# (kept for readers of files and scripts); "problems" lists them all.
_PROBLEM_KEYS = {"estimate": "message", "tracking": "tracking_message",
                 "smoothing": "smoothing_message", "model": "model_hint"}
_LEGACY_KINDS = {"estimate": ProblemKind.FAILED, "tracking": ProblemKind.FAILED,
                 "smoothing": ProblemKind.FELL_BACK, "model": ProblemKind.HINT}


class NorthSource(str, Enum):
    """Where the track's north came from: fitted with the ephemeris (place
    and times), fitted as the Sun's circle about the pole, given with the
    scene (the Sun Position add-on's north offset), or unknown (azimuths are
    then relative to the scene's +Y)."""
    EPHEMERIS = "ephemeris"
    SUN_CIRCLE = "sun_circle"
    GIVEN = "given"
    UNKNOWN = "unknown"


@dataclass
class Track:
    clip: str = ""
    frame_start: int = 1
    north_offset_deg: float = 0.0
    format: str = FORMAT_TRACK
    method: Dict[str, Any] = field(default_factory=dict)
    initial: Optional[Dict[str, Any]] = None
    frames: List[FrameEstimate] = field(default_factory=list)
    # What the run's stages report to the user (warnings and hints).
    problems: List[Problem] = field(default_factory=list)
    # Anything a reader does not know is kept, so a round trip loses nothing.
    extra: Dict[str, Any] = field(default_factory=dict)

    def frame(self, number: int) -> Optional[FrameEstimate]:
        for f in self.frames:
            if f.frame == number:
                return f
        return None

    def report(self, stage: str, kind: ProblemKind, message: str) -> None:
        """Records a stage's problem; a stage has one message (the latest)."""
        self.problems = [p for p in self.problems if p.stage != stage]
        self.problems.append(Problem(stage, kind, message))

    def problem(self, stage: str) -> Optional[Problem]:
        return next((p for p in self.problems if p.stage == stage), None)

    def estimated(self) -> List[FrameEstimate]:
        """Frames with a Sun (smoothed)."""
        return [f for f in self.frames if f.has_estimate]

    def measured_span(self) -> Optional[Tuple[int, int]]:
        """(first, last) frame with a measured (raw) Sun, or None."""
        measured = [f.frame for f in self.frames
                    if f.raw_zenith_deg is not None and f.raw_azimuth_deg is not None]
        return (min(measured), max(measured)) if measured else None

    def extrapolated(self) -> List[int]:
        """Frames whose Sun only extrapolates the smoothing beyond the
        measured frames (a clip that ended early, frames lost at its start or
        end): no measurement backs them, so they are not keyed. Predicted
        frames are not among them: their Sun is the segment's path, said so."""
        span = self.measured_span()
        if span is None:  # no raw angles at all (a truth file): nothing tells
            return []
        return [f.frame for f in self.frames
                if f.has_estimate and not f.predicted and not span[0] <= f.frame <= span[1]]

    def keyable(self) -> List[FrameEstimate]:
        """Estimated frames within the measured span (interpolated gaps
        included) and frames whose Sun is predicted from their segment's
        path (night, twilight: the lamp keyed off there): the frames a lamp
        is keyed on."""
        skip = set(self.extrapolated())
        return [f for f in self.estimated() if f.frame not in skip]

    def without_sunlight(self) -> List[int]:
        """Frames the estimate found without direct sunlight (Sunlight.NO)."""
        return [f.frame for f in self.frames if f.sunlight == Sunlight.NO]

    def north_source(self) -> NorthSource:
        if self.extra.get("sun_path_fit"):
            return NorthSource.EPHEMERIS
        if self.extra.get("sun_circle_fit"):
            return NorthSource.SUN_CIRCLE
        if self.north_offset_deg:
            return NorthSource.GIVEN
        return NorthSource.UNKNOWN

    def north_known(self) -> bool:
        """Whether azimuth_deg is geographic (clockwise from true north)."""
        return self.north_source() != NorthSource.UNKNOWN


def frame_runs(frames: List[int]) -> List[Tuple[int, int]]:
    """Frame numbers as runs of consecutive frames: [(first, last), ...]."""
    runs: List[List[int]] = []
    for f in sorted(set(frames)):
        if runs and f == runs[-1][1] + 1:
            runs[-1][1] = f
        else:
            runs.append([f, f])
    return [(a, b) for a, b in runs]


def frame_ranges(frames: List[int]) -> str:
    """Frame numbers as runs, for messages: "1-5, 9, 57-61"."""
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in frame_runs(frames))


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
    if f.shadow_misfit is not None:
        d["shadow_misfit"] = round(float(f.shadow_misfit), 4)
    if f.sun_height_pinned_deg is not None:
        d["sun_height_pinned_deg"] = float(f.sun_height_pinned_deg)
    if f.sunlight is not None:
        d["sunlight"] = Sunlight(f.sunlight).value
    if f.predicted:
        d["predicted"] = True
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
    for p in track.problems:
        if p.stage in _PROBLEM_KEYS:
            d[_PROBLEM_KEYS[p.stage]] = p.message
    if track.problems:
        d["problems"] = [{"stage": p.stage, "kind": p.kind.value, "message": p.message}
                         for p in track.problems]
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


# Fields that measure how long the run took: the only ones two runs of the
# same input and options may differ in.
TIMING_KEYS = ("timing",)            # top level
INITIAL_TIMING_KEYS = ("seconds",)   # in "initial"


def without_timings(d: Dict[str, Any]) -> Dict[str, Any]:
    """A track file's JSON without its timing fields: what a byte-compare of
    two runs should see (to_text(without_timings(json.load(...))))."""
    out = {k: v for k, v in d.items() if k not in TIMING_KEYS}
    if isinstance(out.get("initial"), dict):
        out["initial"] = {k: v for k, v in out["initial"].items()
                          if k not in INITIAL_TIMING_KEYS}
    return out


def to_text(d: Dict[str, Any]) -> str:
    """The exact text write_track writes for the JSON `d`."""
    return json.dumps(d, indent=1, allow_nan=False) + "\n"


def write_text_atomic(path: str, text: str, suffix: str = ".json", newline=None) -> None:
    """Writes `text` to `path` atomically: a temporary file in the same
    folder, renamed over it, so a crash mid-write never leaves a half file
    and an existing file stays as it was until the new one is whole."""
    folder = os.path.dirname(os.path.abspath(path))
    os.makedirs(folder, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=".sunlapse-", suffix=suffix, dir=folder)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline=newline) as fh:
            fh.write(text)
        # mkstemp makes the file private; give it the usual mode.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_track(path: str, track: Track) -> None:
    """Writes atomically: a crash mid-write never leaves a half file behind."""
    write_text_atomic(path, to_text(to_json(track)))


_KNOWN = {"format", "version", "clip", "frame_start", "north_offset_deg",
          "method", "initial", "frames", "problems", *_PROBLEM_KEYS.values()}


def _problems_from_json(d: Dict[str, Any]) -> List[Problem]:
    """The file's problems; from the stages' own keys in a file written
    before "problems" was (its stage messages are the same text)."""
    listed = d.get("problems")
    if isinstance(listed, list):
        out = []
        for p in listed:
            if not isinstance(p, dict):
                raise ValueError("problems: an entry is not an object")
            try:
                kind = ProblemKind(p.get("kind"))
            except ValueError:
                raise ValueError(f"problems: unknown kind {p.get('kind')!r}")
            out.append(Problem(str(p.get("stage", "")), kind, str(p.get("message", ""))))
        return out
    return [Problem(stage, _LEGACY_KINDS[stage], str(d[key]))
            for stage, key in _PROBLEM_KEYS.items() if d.get(key)]


@overload
def _number(value: Any, what: str, low: float = ..., high: float = ..., *,
            allow_null: Literal[False]) -> float:
    ...


@overload
def _number(value: Any, what: str, low: float = ..., high: float = ...,
            allow_null: bool = ...) -> Optional[float]:
    ...


def _number(value: Any, what: str, low: float = -math.inf, high: float = math.inf,
            allow_null: bool = True) -> Optional[float]:
    """A finite JSON number in [low, high] (bools are not numbers), or None
    for null when allowed; raises ValueError naming `what`."""
    if value is None:
        if allow_null:
            return None
        raise ValueError(f"{what} is missing")
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f"{what} is {value!r}, not a number")
    value = float(value)
    if not math.isfinite(value):
        # JSON has no NaN (our writer turns one into null): a file with one
        # was not written by us, and a NaN read as 0 would be a wrong answer.
        raise ValueError(f"{what} is {value}, not a finite number")
    if not low <= value <= high:
        raise ValueError(f"{what} is {value}, outside [{low:g}, {high:g}]")
    return value


def _integer(value: Any, what: str) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or \
            not math.isfinite(value) or value != int(value) or abs(value) > 2 ** 31:
        raise ValueError(f"{what} is {value!r}, not a whole number")
    return int(value)


def _text(value: Any, what: str) -> Optional[str]:
    if value is None or isinstance(value, str):
        return value
    raise ValueError(f"{what} is {value!r}, not text")


def _pixel(value: Any, what: str) -> List[float]:
    if not isinstance(value, list) or len(value) != 2:
        raise ValueError(f"{what} is {value!r}, not a pixel [x, y]")
    return [_number(v, what, allow_null=False) for v in value]


def _sunlight(value: Any) -> Optional[Sunlight]:
    if value is None:
        return None
    try:
        return Sunlight(value)
    except ValueError:
        raise ValueError(f"sunlight is {value!r}, not one of "
                         f"{', '.join(repr(s.value) for s in Sunlight)}") from None


def _flag(value: Any, what: str) -> bool:
    if value is None:
        return False
    if not isinstance(value, bool):
        raise ValueError(f"{what} is {value!r}, not true or false")
    return value


def _frame_from_json(fd: Any) -> FrameEstimate:
    if not isinstance(fd, dict):
        raise ValueError("not an object")
    shadow = fd.get("shadow")
    start = end = None
    if shadow is not None:
        if not isinstance(shadow, dict):
            raise ValueError(f"shadow is {shadow!r}, not an object")
        start = _pixel(shadow.get("start_px"), "shadow.start_px")
        end = _pixel(shadow.get("end_px"), "shadow.end_px")
    if "frame" not in fd:
        raise ValueError("it has no frame number")
    f = FrameEstimate(
        frame=_integer(fd["frame"], "frame"),
        zenith_deg=_number(fd.get("zenith_deg"), "zenith_deg", 0.0, 180.0),
        azimuth_deg=_number(fd.get("azimuth_deg"), "azimuth_deg", -1e6, 1e6),
        raw_zenith_deg=_number(fd.get("raw_zenith_deg"), "raw_zenith_deg", 0.0, 180.0),
        raw_azimuth_deg=_number(fd.get("raw_azimuth_deg"), "raw_azimuth_deg", -1e6, 1e6),
        confidence=_number(fd.get("confidence"), "confidence", 0.0, 1.0) or 0.0,
        shadow_start_px=start, shadow_end_px=end,
        reason=_text(fd.get("reason"), "reason"),
        sun_ambient_ratio=_number(fd.get("sun_ambient_ratio"), "sun_ambient_ratio", 0.0),
        shadow_misfit=_number(fd.get("shadow_misfit"), "shadow_misfit", 0.0, 1.0),
        sun_height_pinned_deg=_number(fd.get("sun_height_pinned_deg"),
                                      "sun_height_pinned_deg", 0.0, 90.0),
        time_utc=_text(fd.get("time_utc"), "time_utc"),
        sunlight=_sunlight(fd.get("sunlight")),
        predicted=_flag(fd.get("predicted"), "predicted"))
    # One angle without the other is no estimate.
    if (f.zenith_deg is None) != (f.azimuth_deg is None):
        f.zenith_deg = f.azimuth_deg = None
        f.reason = f.reason or "no estimate"
    return f


_INITIAL_NUMBERS = ("zenith_deg", "azimuth_deg", "residual", "confidence", "spread_deg",
                    "sun_intensity", "ambient_intensity", "seconds")


def from_json(d: Dict[str, Any], source: str = "<track>") -> Track:
    """A Track from parsed JSON, validated once here: every number finite and
    in range, every pixel a pair of numbers, frames unique and sorted, so
    that code downstream (panel, overlay, Apply, Export) may trust it.
    Raises TrackFileError (and nothing else) naming `source` and the fault."""
    if not isinstance(d, dict):
        raise TrackFileError(f"{source}: not a JSON object")
    fmt = d.get("format")
    if fmt not in (FORMAT_TRACK, FORMAT_TRUTH):
        shown = fmt if isinstance(fmt, (str, int, float, type(None))) else type(fmt).__name__
        raise TrackFileError(f"{source}: format is {shown!r}, expected "
                             f"{FORMAT_TRACK!r} or {FORMAT_TRUTH!r}")
    version = d.get("version")
    if isinstance(version, bool) or not isinstance(version, int) or \
            version > VERSION or version < 1:
        shown = version if isinstance(version, (int, float, str, type(None))) else \
            type(version).__name__
        raise TrackFileError(f"{source}: unsupported version {shown!r} "
                             f"(this reader knows 1..{VERSION})")
    try:
        clip = _text(d.get("clip"), "clip") or ""
        frame_start = 1 if d.get("frame_start") is None else \
            _integer(d.get("frame_start"), "frame_start")
        north = _number(d.get("north_offset_deg"), "north_offset_deg", -1e6, 1e6) or 0.0
        method = d.get("method")
        if method is None:
            method = {}
        if not isinstance(method, dict):
            raise ValueError(f"method is {type(method).__name__}, not an object")
        initial = d.get("initial")
        if initial is not None:
            if not isinstance(initial, dict):
                raise ValueError(f"initial is {type(initial).__name__}, not an object")
            initial = dict(initial)
            for key in _INITIAL_NUMBERS:
                if key in initial:
                    initial[key] = _number(initial[key], f"initial.{key}")
            if "frame" in initial and initial["frame"] is not None:
                initial["frame"] = _integer(initial["frame"], "initial.frame")
            if initial.get("zenith_deg") is not None and not 0 <= initial["zenith_deg"] <= 180:
                raise ValueError(f"initial.zenith_deg is {initial['zenith_deg']}, "
                                 f"outside [0, 180]")
        problems = _problems_from_json(d)
        raw_frames = d.get("frames")
        if raw_frames is None:
            raw_frames = []
        if not isinstance(raw_frames, list):
            raise ValueError(f"frames is {type(raw_frames).__name__}, not a list")
    except ValueError as e:
        raise TrackFileError(f"{source}: {e}")
    frames = []
    seen = set()
    for i, fd in enumerate(raw_frames):
        try:
            f = _frame_from_json(fd)
        except ValueError as e:
            raise TrackFileError(f"{source}: frame entry {i} is malformed: {e}")
        if f.frame in seen:
            raise TrackFileError(f"{source}: frame {f.frame} is listed twice")
        seen.add(f.frame)
        frames.append(f)
    frames.sort(key=lambda f: f.frame)
    return Track(
        clip=clip,
        frame_start=frame_start,
        north_offset_deg=north,
        format=fmt,
        method=method,
        initial=initial,
        frames=frames,
        problems=problems,
        extra={k: v for k, v in d.items() if k not in _KNOWN},
    )


def loads(text: str, source: str = "<track>") -> Track:
    """A Track from JSON text; raises TrackFileError only."""
    try:
        d = json.loads(text)
    except json.JSONDecodeError as e:
        raise TrackFileError(f"{source}: not valid JSON ({e})")
    except (RecursionError, MemoryError, TypeError, ValueError) as e:
        raise TrackFileError(f"{source}: not readable JSON ({type(e).__name__})")
    return from_json(d, source=source)


def read_track(path: str) -> Track:
    """Reads a track or truth file; raises TrackFileError with the reason."""
    try:
        with open(path, "rb") as fh:
            data = fh.read()
    except FileNotFoundError:
        raise TrackFileError(f"{path}: no such file")
    except IsADirectoryError:
        raise TrackFileError(f"{path}: is a folder, not a track file")
    except OSError as e:
        raise TrackFileError(f"{path}: cannot be read ({e.strerror or e})")
    try:
        text = data.decode("utf-8-sig")  # a byte-order mark from an editor is fine
    except UnicodeDecodeError as e:
        raise TrackFileError(f"{path}: not UTF-8 text (byte {e.start})")
    return loads(text, source=path)
