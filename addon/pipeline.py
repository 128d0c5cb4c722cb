"""The estimation pipeline, shared by the scripted run and the operators.

bpy-free: it takes what bridge.py gathered and returns a trackfile.Track.
Stages that do not exist yet leave their frames as null with a reason.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional, Sequence

from . import native_loader
from .core import trackfile

# The thesis reads the grayscale frame as shading as it is (§3.2); ours
# undoes the display gamma first, since the Lambertian model is linear.
GAMMA = {"thesis": 1.0, "default": 2.2}


class PipelineError(Exception):
    """The run cannot go on (unreadable clip, ...); the message says why."""


@dataclass
class RunOptions:
    method: str = "default"           # "thesis" | "default"
    smoothing: str = "two_pass"        # "online" | "two_pass" | "physical"
    ignore_top_rows: int = 0
    north_offset_deg: float = 0.0      # scene +Y from north (Sun Position add-on)


def read_frame(path: str, index: int):
    """Frame `index` (0-based) of a clip as uint8 BGR, or raise PipelineError."""
    native = native_loader.require()
    try:
        reader = native.VideoReader(path)
    except ValueError as e:
        raise PipelineError(f"cannot read the clip: {e}")
    if not reader.seek(index):
        raise PipelineError(f"the clip has no frame {index + 1}")
    try:
        frame = reader.read()
    except StopIteration:
        frame = None
    if frame is None:
        raise PipelineError(f"frame {index + 1} of the clip cannot be decoded")
    return frame


def run(scene, camera, clip_path: str, clip_frame_start: int, frames: Sequence[int],
        options: RunOptions, progress: Optional[Callable[[float], bool]] = None
        ) -> trackfile.Track:
    """Estimates the Sun on `frames` (scene frame numbers) of the clip."""
    native = native_loader.require()
    first = frames[0]
    bgr = read_frame(clip_path, first - clip_frame_start)
    if bgr.shape[1] != camera.width or bgr.shape[0] != camera.height:
        raise PipelineError(f"clip frames are {bgr.shape[1]}x{bgr.shape[0]} but the camera "
                            f"expects {camera.width}x{camera.height}")
    gray = native.to_linear_gray(bgr, GAMMA[options.method])
    init = native.estimate_initial_sun(scene, camera, gray, method=options.method,
                                       ignore_top_rows=options.ignore_top_rows,
                                       progress=progress)
    if init["message"] == "cancelled":
        raise PipelineError("cancelled")
    north = options.north_offset_deg
    track = trackfile.Track(
        frame_start=clip_frame_start, north_offset_deg=north,
        method={"initial": options.method, "smoothing": options.smoothing,
                "options": {"gamma": GAMMA[options.method]}})
    if init["success"]:
        az = (init["azimuth_deg"] - north) % 360.0
        track.initial = {"zenith_deg": init["zenith_deg"], "azimuth_deg": az,
                         "residual": init["residual_rms"], "confidence": init["confidence"],
                         "spread_deg": init["spread_deg"], "sun_intensity": init["sun_intensity"],
                         "ambient_intensity": init["ambient_intensity"],
                         "seconds": init["seconds"], "message": init["message"] or None}
        track.frames.append(trackfile.FrameEstimate(
            frame=first, zenith_deg=init["zenith_deg"], azimuth_deg=az,
            raw_zenith_deg=init["zenith_deg"], raw_azimuth_deg=az,
            confidence=init["confidence"]))
    else:
        track.frames.append(trackfile.FrameEstimate(
            frame=first, reason=f"initial Sun failed: {init['message']}"))
    for f in frames[1:]:
        track.frames.append(trackfile.FrameEstimate(
            frame=f, reason="shadow tracking is not implemented yet"))
    track.extra["initial_result"] = {k: init[k] for k in ("success", "message", "num_pixels")}
    return track
