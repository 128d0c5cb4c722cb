"""Validate a run and dispatch it: the whole-clip estimate (ours), or the
thesis's baseline and the tracker from a given Sun (estimate/thesis.py)."""

from __future__ import annotations

import dataclasses
import time
from typing import Any, Callable, Dict, Optional, Sequence

from . import frames as clip_frames, native_loader, thesis, whole_clip
from .errors import EstimateError
from .options import EstimateOptions, gamma
from ..core import clock, trackfile


def run(scene, camera, clip_path: str, clip_frame_start: int, frames: Sequence[int],
        options: EstimateOptions, progress: Optional[Callable[[float], bool]] = None,
        frame_cameras: Optional[Dict[int, Any]] = None) -> trackfile.Track:
    """Estimates the Sun on `frames` (consecutive scene frame numbers).
    `frame_cameras`: a moving camera's native camera on each frame (None on
    a frame without a pose), for the default method only; None: `camera`
    stays put."""
    native_loader.require()
    options.check()
    moving = frame_cameras is not None
    if moving and (options.method != "default" or options.initial_sun is not None):
        raise EstimateError("a moving camera is estimated by the default method alone "
                            "(without an initial Sun)")
    frames = list(frames)
    times = None
    if options.frame_times is not None:
        missing = [f for f in frames if f not in options.frame_times]
        if missing:
            more = " ..." if len(missing) > 5 else ""
            raise EstimateError(f"the times file has no time for frame(s) "
                                f"{', '.join(map(str, missing[:5]))}{more}")
        times = [options.frame_times[f] for f in frames]
    orderless = clock.orderless(times) if times is not None else None
    if orderless is not None:
        # Times that cannot order the frames would order them wrongly (and
        # smooth over no time at all): the run is as untimed, and says so.
        options = dataclasses.replace(options, frame_times=None)
        times = None
    # Frames are visited in the order they were taken (decode order when the
    # times are unknown): the tracker follows the shadow between neighbours
    # in time, so an out-of-order frame is tracked where it belongs.
    visit = [frames[i] for i in clock.chronological(frames, times)]
    first = visit[0] - clip_frame_start
    if options.method == "default" and options.initial_sun is None:
        source = clip_frames.FrameSource.opened_when_read(clip_path, clip_frame_start)
    else:
        source = clip_frames.FrameSource(clip_frames.open_clip(clip_path, first),
                                         clip_frame_start, first)
    north = options.north_offset_deg
    track = trackfile.Track(
        frame_start=clip_frame_start, north_offset_deg=north,
        method={"initial": options.method, "tracking": options.method,
                "smoothing": options.smoothing,
                "options": {"gamma": gamma(options.method)}})
    if orderless is not None:
        track.report("times", trackfile.ProblemKind.FELL_BACK,
                     f"the frame times were not used ({orderless}): the frames are taken in "
                     f"their order in the clip, as without times")
    if times is not None:
        late = clock.out_of_order(frames, times)
        track.extra["frame_times"] = {"first_utc": min(times).isoformat(),
                                      "last_utc": max(times).isoformat(),
                                      "out_of_order_frames": late}

    t0 = time.perf_counter()
    if options.method == "default" and options.initial_sun is None:
        return whole_clip.run(scene, camera, clip_path, source, frames, visit, times, options,
                              track, progress, t0, frame_cameras)
    return thesis.run_tracked(scene, camera, source, frames, visit, times, options, track,
                              progress, t0)
