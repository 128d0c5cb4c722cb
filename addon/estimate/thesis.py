"""The thesis's way (the baseline, chapters 3 and 4), and the tracker alone
from a given Sun: the initial Sun on the first frame in capture order, then
the shadow tracker frame after frame."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Dict, List, Optional

import numpy as np

from . import finish, frames as clip_frames, native_loader, notes
from .errors import Cancelled, EstimateError, check_progress
from .options import EstimateOptions
from .raw import RawSun
from ..core import angles, trackfile


def estimate_initial(scene, camera, bgr, options: EstimateOptions, progress=None, gray=None):
    """The initial Sun on one frame (uint8 BGR, or its gray if already made):
    the native InitialSunResult (status SUCCESS, or why not); raises
    Cancelled when the progress callback stopped it."""
    native = native_loader.require()
    if gray is None:
        gray = clip_frames.gray(bgr, camera, options.method)
    init = native.estimate_initial_sun(scene, camera, gray,
                                       method=options.method,
                                       ignore_top_rows=options.ignore_top_rows,
                                       progress=progress)
    if init.status == native.InitialSunStatus.CANCELLED:
        raise Cancelled("cancelled")
    return init


@dataclass
class GivenSun:
    """A Sun the user gave for the first frame, in the terms of the native
    InitialSunResult (world azimuth, a unit vector toward the Sun)."""
    status: Any
    zenith_deg: float
    azimuth_deg: float
    sun_in_world: np.ndarray
    message: str = ""
    residual_rms: float = 0.0
    confidence: float = 1.0
    spread_deg: float = 0.0
    sun_intensity: Optional[float] = None
    ambient_intensity: Optional[float] = None
    seconds: float = 0.0


def _given_initial(zenith_deg, azimuth_deg, north_offset_deg) -> GivenSun:
    azimuth_world_deg = angles.azimuth_world_from_geographic(azimuth_deg, north_offset_deg)
    return GivenSun(native_loader.require().InitialSunStatus.SUCCESS, zenith_deg,
                    azimuth_world_deg,
                    angles.sun_in_world_from_angles(zenith_deg, azimuth_world_deg))


def run_tracked(scene, camera, source, frames, visit, times, options, track, progress, t0):
    """The thesis's way (the baseline), and the tracker alone from a given
    Sun: the initial Sun on the first frame in capture order, then the
    shadow tracker frame after frame; smoothing over the one segment."""
    native = native_loader.require()
    try:
        bgr0 = source.read(visit[0])
    except StopIteration:
        bgr0 = None
    if bgr0 is None:
        raise EstimateError(f"frame {visit[0]} of the clip cannot be decoded")
    gray0 = clip_frames.gray(bgr0, camera, options.method)
    init = _initial_sun(scene, camera, visit[0], bgr0, gray0, options, track, progress)
    if init.status != native.InitialSunStatus.SUCCESS:
        reason = f"initial Sun failed: {init.message}"
        track.frames = [trackfile.FrameEstimate(frame=f, reason=reason) for f in frames]
        track.report("estimate", trackfile.ProblemKind.FAILED, reason)
        return track
    # Frames spread over the clip, kept as they stream past, make its
    # shadow-free background for the unmodelled-shadow note (ours only).
    samples: Dict[int, np.ndarray] = {}
    sample_at = set(notes.spread(frames)) if options.method != "thesis" else set()
    if visit[0] in sample_at:
        samples[visit[0]] = bgr0
    raws, track_seconds = _track_frames(scene, camera, source, visit, gray0, init, options,
                                        track, progress, sample_at, samples)
    raws.sort(key=lambda r: r.frame)  # back to frame order for smoothing and the file
    if options.method != "thesis":
        notes.note_unmodelled_shadows(track, scene, camera, visit[0], bgr0, init.sun_in_world,
                                      list(samples.values()), options)
    finish.finish(native, track, raws, options, times, progress, [[r.frame for r in raws]])
    track.extra["timing"] = {"initial_s": init.seconds,
                             "tracking_ms_per_frame": 1000.0 * track_seconds
                             / max(1, len(frames) - 1),
                             "total_s": time.perf_counter() - t0}
    check_progress(progress, 1.0)
    return track


def _initial_sun(scene, camera, frame, bgr0, gray0, options, track, progress):
    """The first frame's Sun, given or estimated; recorded as the track's
    initial Sun when there is one."""
    north = options.north_offset_deg
    if options.initial_sun is not None:
        zenith_deg, azimuth_deg = options.initial_sun
        init = _given_initial(zenith_deg, azimuth_deg, north)
        track.method["initial"] = "given"
    else:
        init = estimate_initial(scene, camera, bgr0, options,
                                None if progress is None else (lambda f: progress(0.1 * f)),
                                gray=gray0)
    if init.status == native_loader.require().InitialSunStatus.SUCCESS:
        track.initial = {"frame": frame, "zenith_deg": init.zenith_deg,
                         "azimuth_deg": angles.azimuth_geographic_from_world(init.azimuth_deg,
                                                                             north),
                         "residual": init.residual_rms, "confidence": init.confidence,
                         "spread_deg": init.spread_deg, "sun_intensity": init.sun_intensity,
                         "ambient_intensity": init.ambient_intensity,
                         "seconds": init.seconds, "message": init.message or None}
    return init


def _track_frames(scene, camera, source, visit, gray0, init, options, track, progress,
                  sample_at, samples):
    """The tracker from the first frame's Sun over the others in capture
    order: (raw Suns in capture order, tracking seconds)."""
    native = native_loader.require()
    north = options.north_offset_deg
    if options.method == "thesis":
        tracker = native.ThesisTracker(scene, camera, options.ground_object_ids,
                                       ignore_top_rows=options.ignore_top_rows)
    else:
        tracker = native.ShadowTracker(scene, camera, options.ground_object_ids,
                                       ignore_top_rows=options.ignore_top_rows)
    first = tracker.initialize(gray0, init.sun_in_world)
    raws: List[RawSun] = [RawSun(visit[0], init.zenith_deg, angles.azimuth_geographic_from_world(
        init.azimuth_deg, north), init.confidence, tracked=first)]
    if not first.ok:
        track.report("tracking", trackfile.ProblemKind.FAILED, first.reason)
    seconds = 0.0
    for k, f in enumerate(visit[1:], start=1):
        check_progress(progress, 0.1 + 0.85 * k / len(visit))
        try:
            bgr = source.read(f)
        except StopIteration:
            raws.append(RawSun(f, reason="the clip ended before this frame"))
            continue
        why = None
        if bgr is None:
            why = source.why_not()
        elif bgr.shape[0] != camera.height or bgr.shape[1] != camera.width:
            why = clip_frames.wrong_size(bgr, camera)
            bgr = None
        if bgr is not None and f in sample_at:
            samples[f] = bgr
        r = tracker.track(None if bgr is None else clip_frames.gray(bgr, camera, options.method))
        seconds += r.seconds
        if why is not None:
            raws.append(RawSun(f, reason=why))
        elif r.ok:
            raws.append(RawSun(f, r.zenith_deg, angles.azimuth_geographic_from_world(
                r.azimuth_deg, north), r.confidence, tracked=r))
        else:
            raws.append(RawSun(f, reason=r.reason, tracked=r))
    return raws, seconds
