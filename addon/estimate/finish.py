"""Per-segment finishing of the raw Suns: doubt off the Sun's circle,
smoothing (online, two-pass, physical) within each segment's span, and the
track's frames filled."""

from __future__ import annotations

import math

import numpy as np

from . import motion
from .errors import check_progress
from ..core import angles, frametimes, smoothing, suncircle, sunpath, trackfile, trimmed_circle
from .options import SMOOTHING_SPACE, TWO_PASS_DEGREE


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
        track.report("smoothing", trackfile.ProblemKind.FELL_BACK,
                     f"physical smoothing without a place fits the Sun's circle about the pole, "
                     f"which failed ({fit.message}); used two_pass")
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
        track.report("smoothing", trackfile.ProblemKind.FELL_BACK,
                     "physical smoothing with a place needs the frames' times (a times file, "
                     "or the first frame's time and the seconds per frame); used two_pass")
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
        track.report("smoothing", trackfile.ProblemKind.FELL_BACK,
                     f"physical fit failed ({fit.message}); used two_pass")
        track.method["smoothing"] = "two_pass"
        return None, None, north
    track.extra["sun_path_fit"] = {
        "latitude_deg": fit.latitude_deg, "latitude_fitted": options.fit_latitude,
        "longitude_deg": fit.longitude_deg,
        "time_offset_s": fit.time_offset_s, "north_offset_deg": fit.north_offset_deg,
        "median_residual_deg": fit.rms_deg, "message": fit.message or None}
    return fit.zenith_deg, fit.azimuth_deg, fit.north_offset_deg


def finish(native, track, raws, options, times, progress, segments, pixel_scale=1.0,
           circle=None):
    """Smooths the raw angles (per segment: smoothing never crosses a jump)
    and fills the track's frames. raws: (frame, zenith, geographic azimuth,
    confidence, reason, native result) in frame order; times: capture times
    of the run's frames in frame order, or None; pixel_scale: camera pixels
    per pixel of the native results (a tracker on reduced frames); circle:
    {index into raws: (zenith, geographic azimuth) of its segment's Sun
    circle} where one was fitted (doubt_off_circle): the two-pass fit's
    prior path and the path past a segment's confident span."""
    check_progress(progress, 0.97)
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
    through a time jump. circle: as finish's."""
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
            moved = motion.sun_motion_bound_deg(k, end, seconds)
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


def doubt_off_circle(raws, segments, frames, times, north):
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
