"""The estimation pipeline, shared by the scripted run and the operators.

bpy-free: it takes what bridge.py gathered and returns a trackfile.Track.
Frames are streamed from the clip (memory does not grow with its length).
Ours (method "default") finds the Sun over the whole clip at once
(estimate/whole_clip.py); the thesis's baseline, and the tracker alone from a
given Sun, take the initial Sun on the first frame (thesis ch. 3) and track
the rest by their shadows (ch. 4). Then the angles are smoothed (§5), per
segment.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Sequence

import numpy as np

from . import acquire, native_loader
from .estimate import whole_clip
from .core import angles, frametimes, smoothing, suncircle, sunpath, trackfile, trimmed_circle

# The thesis reads the grayscale frame as shading as it is (§3.2); ours
# undoes the display gamma first, since the Lambertian model is linear.
GAMMA = {"thesis": 1.0, "default": 2.2}
# Two-pass smoothing: the thesis fits a straight line per angle; ours fits
# local quadratics to the Sun's direction (core.smoothing.
# two_pass_local_directions), which follow a whole day's path.
TWO_PASS_DEGREE = {"thesis": 1}
# Ours smooths the Sun's direction, not each angle (both the two-pass and the
# online mode): near the zenith the azimuth swings too fast for either
# (core.smoothing.two_pass_directions, online_directions).
SMOOTHING_SPACE = {"thesis": "angles", "default": "directions"}


class PipelineError(Exception):
    """The run cannot go on (unreadable clip, cancelled, ...): says why."""


@dataclass
class RunOptions:
    method: str = "default"           # "thesis" | "default"
    smoothing: str = "two_pass"        # "online" | "two_pass"
    ignore_top_rows: int = 0
    north_offset_deg: float = 0.0      # scene +Y from north (Sun Position add-on)
    ground_object_ids: List[int] = field(default_factory=list)
    # Given Sun on the first frame (zenith, azimuth as in the track file):
    # skips the initial estimate, to measure the tracker alone.
    initial_sun: Optional[tuple] = None
    # For smoothing "physical": the first frame's time (aware datetime), the
    # seconds between frames and the place (degrees, east positive).
    first_time: Optional[object] = None
    frame_seconds: Optional[float] = None
    latitude_deg: Optional[float] = None
    longitude_deg: Optional[float] = None
    # Capture time of each frame (scene frame number -> aware datetime), from
    # a times file: frames are then visited in the order they were taken and
    # smoothed over real time; physical smoothing needs no first_time or
    # frame_seconds then.
    frame_times: Optional[dict] = None
    # Physical smoothing fits the latitude too (about the given one, loosely);
    # False keeps the given latitude exactly (it is known, e.g. engraved).
    fit_latitude: bool = True


def _check_progress(progress, fraction):
    if progress is not None and progress(fraction) is False:
        raise PipelineError("cancelled")


def open_clip(path: str, index: int):
    """A VideoReader positioned at 0-based frame `index`."""
    native = native_loader.require()
    try:
        reader = native.VideoReader(path)
    except ValueError as e:
        raise PipelineError(f"cannot read the clip: {e}")
    if not reader.seek(index):
        raise PipelineError(f"the clip has no frame {index + 1}")
    return reader


def read_frame(path: str, index: int):
    """Frame `index` (0-based) of a clip as uint8 BGR, or raise PipelineError."""
    try:
        frame = open_clip(path, index).read()
    except StopIteration:
        frame = None
    if frame is None:
        raise PipelineError(f"frame {index + 1} of the clip cannot be decoded")
    return frame


class _FrameSource:
    """Frames of a clip by scene frame number, read with one seeking reader:
    sequential reads cost nothing extra, out-of-order ones seek."""

    def __init__(self, reader, clip_frame_start: int, next_index: int):
        self.reader, self.start, self.next = reader, clip_frame_start, next_index
        self.end = None  # first 0-based index past the clip's end, once known

    def why_not(self) -> str:
        """Why the last read() gave no frame (the reader's own report)."""
        report = getattr(self.reader, "last_frame", None)
        message = getattr(report, "message", "") if report is not None else ""
        return message or "frame not decodable"

    def read(self, frame: int):
        """uint8 BGR, or None when the frame cannot be decoded; raises
        StopIteration when the clip has no such frame."""
        i = frame - self.start
        if self.end is not None and i >= self.end:
            raise StopIteration
        try:
            if i != self.next and not self.reader.seek(i):
                raise StopIteration
            self.next = i + 1
            return self.reader.read()
        except StopIteration:
            self.end = i if self.end is None else min(self.end, i)
            raise


def _check_clip_size(width, height, camera):
    if (width, height) != (camera.width, camera.height):
        raise PipelineError(f"clip frames are {width}x{height} but the camera expects "
                            f"{camera.width}x{camera.height}: set the scene's resolution "
                            "to the clip's")


def _gray(bgr, camera, method):
    native = native_loader.require()
    _check_clip_size(bgr.shape[1], bgr.shape[0], camera)
    return native.to_linear_gray(bgr, GAMMA[method])


# A hint to model a missing caster needs a shadow of at least this share of
# the frame, at most this bright relative to the lit ground around (under
# direct sun a hard shadow keeps only the sky's light, a third or less, and
# the rendered presets' show 0.27-0.39; the Marseille dial's engraved
# numerals, shifted by the camera's shake, were seen at 0.50-0.65).
# Weaker ones, and those bordering the model's predicted shadow (the Sun of
# the anchor frame may put a modelled shadow a little off and leave part of
# it unexplained), are recorded in the track file only.
HINT_MIN_AREA = 5e-4
HINT_MAX_DARKENING = 0.45
# Unmodelled shadows are looked for on frames reduced to about this width
# (every n-th pixel): the regions worth a hint are a hundred pixels or more
# there, and full frames cost 0.6 s at 720p, seconds and gigabytes at 4K.
NOTE_WIDTH = 640


def note_stride(camera) -> int:
    """Every how many pixels the unmodelled-shadow note looks."""
    return max(1, -(-camera.width // NOTE_WIDTH))


def detect_unmodelled_shadows(scene, camera, ground_ids, bgr, sun_in_world, samples,
                              gamma=2.2, top=0) -> Optional[dict]:
    """Hard ground shadows on one frame (uint8 BGR) that the model does not
    cast toward `sun_in_world`: native.detect_unmodelled_shadows against the
    clip's shadow-free background (the median of `samples`, uint8 BGR frames
    spread over the clip), which tells a shadow from dark paint, stains or
    engravings. Also returns the masks used ("ground", "model_shadow").
    None when fewer than 3 samples make no background.

    Large frames are looked at every note_stride(camera)-th pixel (frame and
    samples may be given reduced so already); the regions are reported in
    the camera's pixels."""
    stride = note_stride(camera)
    h, w = -(-camera.height // stride), -(-camera.width // stride)

    def reduced(image):
        return image if image.shape[:2] == (h, w) else image[::stride, ::stride]
    back = acquire.clip_background([reduced(f) for f in samples if f is not None])
    if back is None:
        return None
    native = native_loader.require()
    ground, shadow = acquire.ground_and_model_shadow(scene, camera, ground_ids, sun_in_world, top,
                                                     stride)
    # A camera shake of about a pixel per 320 of width is forgiven.
    found = native.detect_unmodelled_shadows(
        acquire.linear_bgr(reduced(bgr), gamma), acquire.linear_bgr(back, gamma), ground, shadow,
        registration_px=max(1, round(w / 320)))
    if stride > 1:
        for r in found["regions"]:
            r["area_px"] *= stride * stride
            r["box"] = tuple(v * stride for v in r["box"])
            r["centroid_px"] = tuple(v * stride for v in r["centroid_px"])
    return dict(found, ground=ground, model_shadow=shadow)


def _note_unmodelled_shadows(track, scene, camera, frame, bgr, sun_in_world, samples, options):
    """The anchor frame's unmodelled shadows (detect_unmodelled_shadows),
    recorded in the track file (extra.unmodelled_shadows) and, when large and
    dark, turned into a hint for the artist (extra.model_hint). A clip whose
    shadows barely moved has no shadow-free background, so nothing is found.
    Advisory: a failure here only notes itself."""
    try:
        found = detect_unmodelled_shadows(scene, camera, options.ground_object_ids, bgr,
                                          sun_in_world, samples, GAMMA[options.method],
                                          options.ignore_top_rows)
    except (ValueError, RuntimeError, MemoryError) as e:
        track.extra["unmodelled_shadows"] = {"frame": frame, "error": str(e)}
        return
    if found is None:
        track.extra["unmodelled_shadows"] = {
            "frame": frame, "skipped": "too few frames for a shadow-free background"}
        return
    regions = [dict(r, box=list(r["box"]), centroid_px=list(r["centroid_px"]))
               for r in found["regions"]]
    track.extra["unmodelled_shadows"] = {"frame": frame, "regions": regions,
                                         "background_frames": len(samples)}
    big = [r for r in regions if r["area_px"] >= HINT_MIN_AREA * camera.width * camera.height
           and r["darkening"] <= HINT_MAX_DARKENING and not r["touches_model"]]
    if big:
        x, y = big[0]["centroid_px"]
        track.extra["model_hint"] = (
            f"{len(big)} hard ground shadow(s) on frame {frame} are not cast by the model "
            f"(the largest, {big[0]['area_px']} px, around pixel ({x:.0f}, {y:.0f})): model "
            f"their casters and the tracker will follow their shadows too")


def estimate_initial(scene, camera, bgr, options: RunOptions, progress=None, gray=None) -> dict:
    """The initial Sun on one frame (uint8 BGR, or its gray if already made);
    the native result dict."""
    native = native_loader.require()
    if gray is None:
        gray = _gray(bgr, camera, options.method)
    init = native.estimate_initial_sun(scene, camera, gray,
                                       method=options.method,
                                       ignore_top_rows=options.ignore_top_rows,
                                       progress=progress)
    if init["message"] == "cancelled":
        raise PipelineError("cancelled")
    return init


def _given_initial(zenith_deg, azimuth_deg, north_offset_deg):
    """An initial result dict for a Sun given by the user (world frame inside)."""
    azimuth_world_deg = angles.azimuth_world_from_geographic(azimuth_deg, north_offset_deg)
    return {"success": True, "message": "", "zenith_deg": zenith_deg,
            "azimuth_deg": azimuth_world_deg,
            "sun_in_world": tuple(angles.sun_in_world_from_angles(zenith_deg, azimuth_world_deg)),
            "residual_rms": 0.0, "confidence": 1.0, "spread_deg": 0.0, "sun_intensity": None,
            "ambient_intensity": None, "seconds": 0.0}


def _sun_circle(track, numbers, raws, options, north):
    """Physical smoothing without a place: the Sun's small circle about the
    pole fitted to the raw Suns (core.suncircle), which also says what
    latitude, declination and north the path implies. Same return as
    _physical."""
    if options.frame_times is not None:
        seconds = frametimes.seconds_since([options.frame_times[f] for f in numbers])
        t, real = seconds, True
    elif options.frame_seconds:
        t, real = [f * options.frame_seconds for f in numbers], True
    else:
        t, real = list(numbers), False
    world_az = [None if r[2] is None else (r[2] + north) % 360.0 for r in raws]
    fit = suncircle.fit_circle(t, [r[1] for r in raws], world_az, [r[3] for r in raws],
                               times_are_seconds=real)
    if not fit.success:
        track.extra["smoothing_message"] = (f"physical smoothing without a place fits the Sun's "
                                            f"circle about the pole, which failed ({fit.message}); "
                                            f"used two_pass")
        track.method["smoothing"] = "two_pass"
        return None, None, north
    track.extra["sun_circle_fit"] = {
        "latitude_deg": fit.latitude_deg, "declination_deg": fit.declination_deg,
        "north_offset_deg": fit.north_offset_deg, "median_residual_deg": fit.residual_deg,
        "hour_angle_deg_first": fit.hour_angle_deg[0], "real_time": real,
        "message": fit.message or None}
    geo = [(a - fit.north_offset_deg) % 360.0 for a in fit.azimuth_world_deg]
    return fit.zenith_deg, geo, fit.north_offset_deg


def _physical(native, track, numbers, raws, options, north):
    """Fits the Sun's path through the raw angles; returns (zenith, geographic
    azimuth, north offset) per frame, or (None, None, north) with the reason
    kept in the track when the inputs are missing or the fit fails."""
    if options.latitude_deg is None or options.longitude_deg is None:
        return _sun_circle(track, numbers, raws, options, north)
    need = (options.first_time, options.frame_seconds) if options.frame_times is None else ()
    if any(v is None for v in need):
        track.extra["smoothing_message"] = ("physical smoothing with a place needs the frames' "
                                            "times (a times file, or the first frame's time "
                                            "and the seconds per frame); used two_pass")
        track.method["smoothing"] = "two_pass"
        return None, None, north
    times = sunpath.frame_times(options.first_time, options.frame_seconds, numbers) \
        if options.frame_times is None else [options.frame_times[f] for f in numbers]

    def sun(t, lat, lon):
        return native.sun_position(t.year, t.month, t.day, t.hour, t.minute,
                                   t.second + t.microsecond * 1e-6, lat, lon)
    world_az = [None if r[2] is None else (r[2] + north) % 360.0 for r in raws]
    fit = sunpath.fit_sun_path(times, [r[1] for r in raws], world_az, [r[3] for r in raws], sun,
                               options.latitude_deg, options.longitude_deg,
                               fit_latitude=options.fit_latitude)
    if not fit.success:
        track.extra["smoothing_message"] = f"physical fit failed ({fit.message}); used two_pass"
        track.method["smoothing"] = "two_pass"
        return None, None, north
    track.extra["sun_path_fit"] = {
        "latitude_deg": fit.latitude_deg, "latitude_fitted": options.fit_latitude,
        "longitude_deg": fit.longitude_deg,
        "time_offset_s": fit.time_offset_s, "north_offset_deg": fit.north_offset_deg,
        "median_residual_deg": fit.rms_deg, "message": fit.message or None}
    return fit.zenith_deg, fit.azimuth_deg, fit.north_offset_deg


def run(scene, camera, clip_path: str, clip_frame_start: int, frames: Sequence[int],
        options: RunOptions, progress: Optional[Callable[[float], bool]] = None
        ) -> trackfile.Track:
    """Estimates the Sun on `frames` (consecutive scene frame numbers)."""
    native_loader.require()
    if not options.ground_object_ids:
        raise PipelineError("no ground object: name the ground the shadows fall on "
                            "(--ground, or Ground in the panel)")
    frames = list(frames)
    times = None
    if options.frame_times is not None:
        missing = [f for f in frames if f not in options.frame_times]
        if missing:
            more = " ..." if len(missing) > 5 else ""
            raise PipelineError(f"the times file has no time for frame(s) "
                                f"{', '.join(map(str, missing[:5]))}{more}")
        times = [options.frame_times[f] for f in frames]
    # Frames are visited in the order they were taken (decode order when the
    # times are unknown): the tracker follows the shadow between neighbours
    # in time, so an out-of-order frame is tracked where it belongs.
    visit = [frames[i] for i in frametimes.chronological(frames, times)]
    source = _FrameSource(open_clip(clip_path, visit[0] - clip_frame_start), clip_frame_start,
                          visit[0] - clip_frame_start)
    north = options.north_offset_deg
    track = trackfile.Track(
        frame_start=clip_frame_start, north_offset_deg=north,
        method={"initial": options.method, "tracking": options.method,
                "smoothing": options.smoothing,
                "options": {"gamma": GAMMA[options.method]}})
    if times is not None:
        late = frametimes.out_of_order(frames, times)
        track.extra["frame_times"] = {"first_utc": min(times).isoformat(),
                                      "last_utc": max(times).isoformat(),
                                      "out_of_order_frames": late}

    t0 = time.perf_counter()
    if options.method == "default" and options.initial_sun is None:
        return _run_whole_clip(scene, camera, clip_path, source, frames, visit, times, options,
                               track, progress, t0)
    return _run_tracked(scene, camera, source, frames, visit, times, options, track, progress, t0)


def _run_tracked(scene, camera, source, frames, visit, times, options, track, progress, t0):
    """The thesis's way (the baseline), and the tracker alone from a given
    Sun: the initial Sun on the first frame in capture order, then the
    shadow tracker frame after frame."""
    native = native_loader.require()
    north = options.north_offset_deg
    try:
        bgr0 = source.read(visit[0])
    except StopIteration:
        bgr0 = None
    if bgr0 is None:
        raise PipelineError(f"frame {visit[0]} of the clip cannot be decoded")
    gray0 = _gray(bgr0, camera, options.method)
    if options.initial_sun is not None:
        init = _given_initial(*options.initial_sun, north)
        track.method["initial"] = "given"
    else:
        init = estimate_initial(scene, camera, bgr0, options,
                                None if progress is None else (lambda f: progress(0.1 * f)),
                                gray=gray0)
    if not init["success"]:
        reason = f"initial Sun failed: {init['message']}"
        track.frames = [trackfile.FrameEstimate(frame=f, reason=reason) for f in frames]
        track.extra["message"] = reason
        return track
    az0 = (init["azimuth_deg"] - north) % 360.0
    track.initial = {"frame": visit[0], "zenith_deg": init["zenith_deg"], "azimuth_deg": az0,
                     "residual": init["residual_rms"], "confidence": init["confidence"],
                     "spread_deg": init["spread_deg"], "sun_intensity": init["sun_intensity"],
                     "ambient_intensity": init["ambient_intensity"],
                     "seconds": init["seconds"], "message": init["message"] or None}
    # Frames spread over the clip, kept as they stream past, make its
    # shadow-free background for the unmodelled-shadow note (ours only).
    sample_at = set(acquire.spread(frames)) if options.method != "thesis" else set()
    samples = {visit[0]: bgr0} if visit[0] in sample_at else {}
    if options.method == "thesis":
        tracker = native.ThesisTracker(scene, camera, options.ground_object_ids,
                                       ignore_top_rows=options.ignore_top_rows)
    else:
        tracker = native.ShadowTracker(scene, camera, options.ground_object_ids,
                                       ignore_top_rows=options.ignore_top_rows)
    first = tracker.initialize(gray0, init["sun_in_world"])
    raws = [(visit[0], init["zenith_deg"], az0, init["confidence"], None, first)]
    if not first.ok:
        track.extra["tracking_message"] = first.reason
    track_seconds = 0.0
    for k, f in enumerate(visit[1:], start=1):
        _check_progress(progress, 0.1 + 0.85 * k / len(visit))
        try:
            bgr = source.read(f)
        except StopIteration:
            raws.append((f, None, None, 0.0, "the clip ended before this frame", None))
            continue
        why = None
        if bgr is None:
            why = source.why_not()
        elif bgr.shape[0] != camera.height or bgr.shape[1] != camera.width:
            why = (f"frame is {bgr.shape[1]}x{bgr.shape[0]}, not the camera's "
                   f"{camera.width}x{camera.height}: not the scene's footage")
            bgr = None
        if bgr is not None and f in sample_at:
            samples[f] = bgr
        r = tracker.track(None if bgr is None else _gray(bgr, camera, options.method))
        track_seconds += r.seconds
        if why is not None:
            raws.append((f, None, None, 0.0, why, None))
        elif r.ok:
            raws.append((f, r.zenith_deg, (r.azimuth_deg - north) % 360.0, r.confidence, None, r))
        else:
            raws.append((f, None, None, 0.0, r.reason, r))
    raws.sort(key=lambda r: r[0])  # back to frame order for smoothing and the file
    if options.method != "thesis":
        _note_unmodelled_shadows(track, scene, camera, visit[0], bgr0, init["sun_in_world"],
                                 list(samples.values()), options)
    _finish(native, track, raws, options, times, progress, [[r[0] for r in raws]])
    track.extra["timing"] = {"initial_s": init["seconds"],
                             "tracking_ms_per_frame": 1000.0 * track_seconds
                             / max(1, len(frames) - 1),
                             "total_s": time.perf_counter() - t0}
    _check_progress(progress, 1.0)
    return track


def _finish(native, track, raws, options, times, progress, segments, pixel_scale=1.0,
            circle=None):
    """Smooths the raw angles (per segment: smoothing never crosses a jump)
    and fills the track's frames. raws: (frame, zenith, geographic azimuth,
    confidence, reason, native result) in frame order; times: capture times
    of the run's frames in frame order, or None; pixel_scale: camera pixels
    per pixel of the native results (a tracker on reduced frames); circle:
    {index into raws: (zenith, geographic azimuth) of its segment's Sun
    circle} where one was fitted (_doubt_off_circle): the two-pass fit's
    prior path and the path past a segment's confident span."""
    _check_progress(progress, 0.97)
    numbers = [r[0] for r in raws]
    north = track.north_offset_deg
    zs = azs = None
    raws = list(raws)
    if options.smoothing == "physical":
        zs, azs, north = _physical(native, track, numbers, raws, options, north)
        if zs is not None:  # azimuths are geographic now, with the fitted north
            raws = [(f, z, None if a is None else (a + track.north_offset_deg - north) % 360.0,
                     c, reason, res) for (f, z, a, c, reason, res) in raws]
            if track.initial:
                track.initial["azimuth_deg"] = (track.initial["azimuth_deg"]
                                                + track.north_offset_deg - north) % 360.0
            track.north_offset_deg = north
    if zs is None:
        mode = "two_pass" if options.smoothing == "physical" else options.smoothing
        zs, azs = _smooth_segments(numbers, raws, segments, mode, options, times, circle)
    for k, ((f, z, a, conf, reason, res), zs_f, as_f) in enumerate(zip(raws, zs, azs)):
        est = trackfile.FrameEstimate(frame=f, zenith_deg=_settled(zs_f),
                                      azimuth_deg=_settled(as_f),
                                      raw_zenith_deg=z, raw_azimuth_deg=a,
                                      confidence=conf, reason=reason,
                                      time_utc=None if times is None else times[k].isoformat())
        if res is not None and res.shadow_end_px[0] == res.shadow_end_px[0]:  # not NaN
            est.shadow_start_px = [(v + 0.5) * pixel_scale - 0.5 for v in res.shadow_start_px]
            est.shadow_end_px = [(v + 0.5) * pixel_scale - 0.5 for v in res.shadow_end_px]
        if res is not None and z is not None and 0 < res.contrast < 100:
            est.sun_ambient_ratio = res.contrast
        track.frames.append(est)


# Smoothed angles are written to this many decimals (deg): numpy's sums
# round differently with the arrays' alignment in memory, so the same
# smoothing of the same raw angles differed in the last bit between runs
# (1 in 3 runs of the March Marseille clip: test_faults' byte-compare).
SMOOTHED_DECIMALS = 9


def _settled(angle_deg):
    return None if angle_deg is None else round(float(angle_deg), SMOOTHED_DECIMALS)


# Smoothing spans a segment's frames between the first and the last with
# this much confidence. Past them the tracker followed shadows without
# evidence of their own (a sunset's fading shadows: confidence near 0), and
# a fit extrapolated onto them invents: on the Marseille January clip the
# two-pass track ended 10 deg off, below the horizon. Those frames take the
# span's end Sun moved as the segment's Sun circle moves, else their own raw
# Sun no further from the end's than the Sun can move.
SPAN_MIN_CONFIDENCE = 0.1


def _smooth_segments(numbers, raws, segments, mode, options, times, circle=None):
    """Smooths each segment on its own, only between its first and last
    frames with angles and confidence (SPAN_MIN_CONFIDENCE): nothing is
    extrapolated past them beyond the Sun's own motion, and no fit runs
    through a time jump. circle: as _finish's."""
    index = {f: k for k, f in enumerate(numbers)}
    seconds = None if times is None else frametimes.seconds_since(times)
    zs, azs = [None] * len(numbers), [None] * len(numbers)
    for seg in segments:
        ks = sorted(index[f] for f in seg)
        have = [k for k in ks if raws[k][1] is not None]
        if not have:
            continue
        least = SPAN_MIN_CONFIDENCE if options.method == "default" else 0.0  # thesis: as it was
        span = [k for k in have if raws[k][3] >= least] or have
        ks = [k for k in ks if span[0] <= k <= span[-1]]
        x = [numbers[k] for k in ks] if seconds is None else [seconds[k] for k in ks]
        if mode == "two_pass" and options.method == "default":
            # The segment's Sun circle, where one was fitted, lends the fit
            # its shape where confident frames are far (two_pass_local_directions).
            along = [None if circle is None else circle.get(k) for k in ks]
            z_s, a_s = smoothing.two_pass_local_directions(
                x, [raws[k][1] for k in ks], [raws[k][2] for k in ks], [raws[k][3] for k in ks],
                prior_zenith=[None if c is None else c[0] for c in along],
                prior_azimuth=[None if c is None else c[1] for c in along])
        else:
            z_s, a_s = smoothing.smooth_angles(
                [numbers[k] for k in ks], [raws[k][1] for k in ks], [raws[k][2] for k in ks],
                [raws[k][3] for k in ks], mode, degree=TWO_PASS_DEGREE.get(options.method, 3),
                space=SMOOTHING_SPACE[options.method],
                times_s=None if seconds is None else [seconds[k] for k in ks])
        for k, z, a in zip(ks, z_s, a_s):
            zs[k], azs[k] = z, a
        for k in have:
            if span[0] <= k <= span[-1] or zs[span[0]] is None or zs[span[-1]] is None:
                continue
            end = span[0] if k < span[0] else span[-1]
            moved = whole_clip.sun_motion_bound_deg(k, end, seconds)
            zs[k], azs[k] = _past_span(zs[end], azs[end], raws[k][1], raws[k][2], moved,
                                       None if circle is None else circle.get(end),
                                       None if circle is None else circle.get(k))
    return zs, azs


def _past_span(z_end, a_end, z_raw, a_raw, moved_deg, circle_end, circle_here):
    """A frame's Sun past its segment's smoothed span (all azimuths
    geographic): the end's Sun turned as the circle turns from the end to
    the frame, else the frame's raw Sun pulled to within moved_deg of it."""
    end = angles.sun_in_world_from_angles(z_end, a_end)
    if circle_end is not None and circle_here is not None:
        u = angles.sun_in_world_from_angles(*circle_end)
        w = angles.sun_in_world_from_angles(*circle_here)
        turned = _rotated(end, np.cross(u, w), angles.angle_between_deg(u, w))
        return tuple(float(t) for t in angles.angles_from_sun_in_world(turned))
    raw = angles.sun_in_world_from_angles(z_raw, a_raw)
    off = angles.angle_between_deg(end, raw)
    if off <= moved_deg:
        return z_raw, a_raw
    turned = _rotated(end, np.cross(end, raw), moved_deg)
    return tuple(float(t) for t in angles.angles_from_sun_in_world(turned))


def _rotated(v, axis, angle_deg):
    """v turned by angle_deg about axis (Rodrigues); v itself for a null axis."""
    n = float(np.linalg.norm(axis))
    if n < 1e-12:
        return v
    k, c, s = axis / n, math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    return v * c + np.cross(k, v) * s + k * float(k @ v) * (1.0 - c)


def _wrong_size(image, camera) -> Optional[str]:
    if image.shape[0] != camera.height or image.shape[1] != camera.width:
        return (f"frame is {image.shape[1]}x{image.shape[0]}, not the camera's "
                f"{camera.width}x{camera.height}: not the scene's footage")
    return None


# A frame's Sun further than this from the Sun's circle about the pole,
# fitted to its segment's confident frames, loses confidence with the square
# of the ratio (half at 4.2 deg, a tenth at 9.5): on the randomised suite 15
# of the 18 raw Suns more than 5 deg off at confidence >= 0.8 were over
# 3 deg from it, and 7 of the 759 good ones. The sky's evidence can be
# confidently wrong over a few frames (a pole's shadow along a paving
# joint); the Sun's path over the segment cannot bend that way, and a Sun
# far off it must not steer the smoothing either. The fit is trimmed
# (core/trimmed_circle.py): a third of a segment's Suns stuck a few degrees to
# one side (suite scene 16's low-Sun frames) pulled a Huber fit through
# them, and they kept their confidence. Suns within CIRCLE_INLIER_FLOOR_DEG
# of the circle always take part in the fit (a refined Sun's own scatter).
CIRCLE_DOUBT_DEG = 3.0
CIRCLE_INLIER_FLOOR_DEG = 1.5


def _doubt_off_circle(raws, segments, frames, times, north):
    """(raws (frame, zenith, geographic azimuth, confidence, reason,
    result) with less confidence where the Sun is off its segment's circle,
    {index into raws: (zenith, geographic azimuth) of its segment's circle}
    for the segments with one)."""
    index = {f: k for k, f in enumerate(frames)}
    seconds = None if times is None else frametimes.seconds_since(times)
    out = list(raws)
    along = {}
    for seg in segments:
        ks = sorted(index[f] for f in seg)
        t = [float(frames[k]) if seconds is None else seconds[k] for k in ks]
        suns = [angles.sun_in_world_from_geographic(out[k][1], out[k][2], north)
                if out[k][1] is not None and out[k][3] >= 0.3 else None for k in ks]
        fit = trimmed_circle.fit_trimmed(t, suns, CIRCLE_INLIER_FLOOR_DEG,
                                         [max(out[k][3], 1e-3) for k in ks],
                                         times_are_seconds=seconds is not None)
        if not fit.success:
            continue
        for i, k in enumerate(ks):
            z_fit, a_fit = angles.angles_from_sun_in_world(fit.sun_in_world[i])
            along[k] = (float(z_fit), float(angles.azimuth_geographic_from_world(a_fit, north)))
            f, z, a, conf, reason, res = out[k]
            if z is None:
                continue
            raw = angles.sun_in_world_from_geographic(z, a, north)
            off = angles.angle_between_deg(raw, fit.sun_in_world[i])
            if off > CIRCLE_DOUBT_DEG:
                out[k] = (f, z, a, conf * (CIRCLE_DOUBT_DEG / off) ** 2, reason, res)
    return out, along


def _run_whole_clip(scene, camera, clip_path, source, frames, visit, times, options, track,
                    progress, t0):
    """The default method: the Sun over the whole clip at once
    (estimate/whole_clip.py), then smoothing per segment."""
    native = native_loader.require()
    north = options.north_offset_deg
    # The frames spread over the clip for the reference levels are kept in
    # colour, at the unmodelled-shadow note's size, for the clip's shadow-free
    # background.
    samples = {}
    stride = note_stride(camera)

    def read_gray(f):
        try:
            bgr = source.read(f)
        except StopIteration:
            return "the clip ended before this frame"
        if bgr is None:
            return source.why_not()
        return _wrong_size(bgr, camera) or native.to_linear_gray(bgr, GAMMA[options.method])

    # The frames stream reduced to the estimate's working size: a clip of
    # another size than the camera's would be reduced to it silently.
    _check_clip_size(source.reader.width, source.reader.height, camera)

    def open_stream(fs, near, size):
        # The reference frames also come in colour for the note, at its size.
        try:
            return native.FrameStream(
                clip_path, [f - source.start for f in fs],
                native.FrameStreamOptions(gamma=GAMMA[options.method], near=near,
                                          keep_bgr=near, width=size[0], height=size[1],
                                          bgr_width=-(-camera.width // stride),
                                          bgr_height=-(-camera.height // stride)))
        except ValueError as e:
            raise PipelineError(f"cannot read the clip: {e}")

    def stream(fs, near, size):
        """The frames in order at `size`, decoded ahead on a native thread
        (started now, before the first is asked for)."""
        return streamed(open_stream(fs, near, size), near)

    def frame_source(fs, size):
        """The pass's frames at `size`: a native stream, and the index it
        reports for each frame (its 0-based index in the clip)."""
        pass_stream["stream"] = open_stream(fs, False, size)
        return pass_stream["stream"], {f: f - source.start for f in fs}

    def streamed(frame_stream, near):
        start = source.start
        past_end = native.StreamedFrameStatus.past_end
        for got in frame_stream:
            f = got.index + start
            if got.gray is not None:
                if near:
                    samples[f] = got.bgr
                yield f, got.gray
            elif got.status == past_end:
                yield f, "the clip ended before this frame"
            else:
                yield f, got.message or "frame not decodable"

    pass_stream = {"stream": None}

    seconds = None
    if times is not None:
        by_frame = dict(zip(frames, frametimes.seconds_since(times)))
        seconds = [by_frame[f] for f in visit]
    try:
        result = whole_clip.estimate(
            native, scene, camera, visit, read_gray, options.ground_object_ids, times_s=seconds,
            ignore_top_rows=options.ignore_top_rows,
            progress=None if progress is None else (lambda x: progress(0.95 * x)),
            stream=stream, source=frame_source, fit_circle=trimmed_circle.fit_trimmed)
    except whole_clip.Cancelled:
        raise PipelineError("cancelled")
    track.method["initial"] = track.method["tracking"] = "whole_clip"
    by_frame = {r.frame: r for r in result.frames}
    raws = []
    geographic = {}  # frame -> (zenith, geographic azimuth)
    for f in frames:
        r = by_frame[f]
        if r.sun_in_world is None:
            raws.append((f, None, None, r.confidence, r.reason, r.tracked))
            continue
        z, a_world = angles.angles_from_sun_in_world(r.sun_in_world)
        geographic[f] = (float(z), float(angles.azimuth_geographic_from_world(a_world, north)))
        raws.append((f, *geographic[f], r.confidence, r.reason, r.tracked))
    raws, circle = _doubt_off_circle(raws, result.segments, frames, times, north)
    if result.anchor is not None:
        a = by_frame[result.anchor]
        track.initial = {"frame": a.frame, "zenith_deg": geographic[a.frame][0],
                         "azimuth_deg": geographic[a.frame][1],
                         "residual": None, "confidence": a.confidence,
                         "seconds": result.timing.get("table_s", 0.0)
                         + result.timing.get("reference_s", 0.0),
                         "message": "the best-supported frame of the whole-clip path"}
        # Unmodelled shadows are looked for on the best-supported frame kept
        # in colour (no frame is decoded again for the note).
        kept = [f for f in samples if f in by_frame and by_frame[f].sun_in_world is not None]
        if kept:
            f = max(kept, key=lambda f: by_frame[f].confidence)
            _note_unmodelled_shadows(track, scene, camera, f, samples[f],
                                     by_frame[f].sun_in_world, list(samples.values()), options)
    elif result.message:
        track.extra["message"] = result.message
    track.extra["segments"] = [[seg[0], seg[-1]] for seg in result.segments]
    if result.evidence:
        track.extra["evidence"] = dict(result.evidence, frames=list(visit))
    if result.jumps:
        track.extra["jumps"] = result.jumps
    _finish(native, track, raws, options, times, progress, result.segments,
            result.tracker_pixel_scale, circle)
    wait = 0.0 if pass_stream["stream"] is None else pass_stream["stream"].wait_seconds
    pass_stream["stream"] = None
    track.extra["timing"] = dict(result.timing, decode_wait_s=wait,
                                 total_s=time.perf_counter() - t0)
    return track
