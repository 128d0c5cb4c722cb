"""Per-segment finishing of the raw Suns: smoothing (online, two-pass,
physical) within each segment's span, and the track's frames filled."""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, replace
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from . import calibration, motion, sun_circle
from .errors import check_progress
from .options import SMOOTHING_SPACE, TWO_PASS_DEGREE, EstimateOptions
from .raw import RawSun
from ..core import angles, clock, smoothing, sunpath, trackfile
from ..core.trackfile import Sunlight


def _sun_circle(track, numbers, raws, options, north):
    """Physical smoothing without a place: the Sun's small circle about the
    pole fitted to the raw Suns (sun_circle.py), which also says what
    latitude, declination and north the path implies. Same return as
    _physical."""
    if options.frame_times is not None:
        seconds = clock.seconds_since([options.frame_times[f] for f in numbers])
        t, real = seconds, True
    elif options.frame_seconds:
        t, real = [f * options.frame_seconds for f in numbers], True
    else:
        t, real = list(numbers), False
    fit = sun_circle.fit_circle(t, [r.zenith_deg for r in raws], _world_azimuths(raws, north),
                                [r.confidence for r in raws], times_are_seconds=real)
    if not fit.success:
        track.report("smoothing", trackfile.ProblemKind.FELL_BACK,
                     f"physical smoothing without a place fits the Sun's circle about the pole, "
                     f"which failed ({fit.message}); used two_pass")
        track.method["smoothing"] = "two_pass"
        return None, north
    track.extra["sun_circle_fit"] = {
        "latitude_deg": fit.latitude_deg, "declination_deg": fit.declination_deg,
        "north_offset_deg": fit.north_offset_deg, "median_residual_deg": fit.residual_deg,
        "hour_angle_deg_first": fit.hour_angle_deg[0], "real_time": real,
        "message": fit.message or None}
    geo = [angles.azimuth_geographic_from_world(a, fit.north_offset_deg)
           for a in fit.azimuth_world_deg]
    return (fit.zenith_deg, geo), fit.north_offset_deg


def ephemeris_sun(native, t, latitude_deg: float, longitude_deg: float) -> Tuple[float, float]:
    """(zenith, geographic azimuth) of the Sun at capture time `t` (UTC)."""
    return native.sun_position(t.year, t.month, t.day, t.hour, t.minute,
                               t.second + t.microsecond * 1e-6, latitude_deg, longitude_deg)


def _physical(native, track, numbers, raws, options, north):
    """Fits the Sun's path through the raw angles; returns ((zeniths,
    geographic azimuths) per frame, north offset), or (None, north) with the
    reason kept in the track when the inputs are missing or the fit fails."""
    if options.latitude_deg is None or options.longitude_deg is None:
        return _sun_circle(track, numbers, raws, options, north)
    need = (options.first_time, options.frame_seconds) if options.frame_times is None else ()
    if any(v is None for v in need):
        track.report("smoothing", trackfile.ProblemKind.FELL_BACK,
                     "physical smoothing with a place needs the frames' times (a times file, "
                     "or the first frame's time and the seconds per frame); used two_pass")
        track.method["smoothing"] = "two_pass"
        return None, north
    times = clock.frame_times(options.first_time, options.frame_seconds, numbers) \
        if options.frame_times is None else [options.frame_times[f] for f in numbers]
    fit = sunpath.fit_sun_path(times, [r.zenith_deg for r in raws], _world_azimuths(raws, north),
                               [r.confidence for r in raws],
                               lambda t, lat, lon: ephemeris_sun(native, t, lat, lon),
                               options.latitude_deg, options.longitude_deg,
                               fit_latitude=options.fit_latitude)
    if not fit.success:
        track.report("smoothing", trackfile.ProblemKind.FELL_BACK,
                     f"physical fit failed ({fit.message}); used two_pass")
        track.method["smoothing"] = "two_pass"
        return None, north
    track.extra["sun_path_fit"] = {
        "latitude_deg": fit.latitude_deg, "latitude_fitted": options.fit_latitude,
        "longitude_deg": fit.longitude_deg,
        "time_offset_s": fit.time_offset_s, "north_offset_deg": fit.north_offset_deg,
        "median_residual_deg": fit.rms_deg, "message": fit.message or None}
    return (fit.zenith_deg, fit.azimuth_deg), fit.north_offset_deg


# Why a clip's model is doubted (calibration.model_doubted), by whether the
# clip refined it.
_MODEL_DOUBT = {False: "does not fit the footage", True: "was refined by the clip"}


def finish(native, track: trackfile.Track, raws: List[RawSun], options: EstimateOptions,
           times, progress, segments: Sequence[Sequence[int]], pixel_scale: float = 1.0,
           circle: Optional[Dict[int, Tuple[float, float]]] = None,
           paced: Optional[Dict[int, float]] = None) -> None:
    """Smooths the raw Suns (per segment: smoothing never crosses a jump)
    and fills the track's frames. raws: in frame order; times: capture times
    of the run's frames in frame order, or None; pixel_scale: camera pixels
    per pixel of the native results (a tracker on reduced frames); circle:
    {index into raws: (zenith, geographic azimuth) of its segment's Sun
    circle} where one was fitted (the whole-clip estimate's): the two-pass
    fit's prior path and the path past a segment's confident span; paced:
    without times, {frame number: clock} of the segments whose circle
    follows the Sun's pace (untimed.pace_clock): the two-pass fit runs
    on that clock there, not on frame numbers."""
    check_progress(progress, 0.97)
    numbers = [r.frame for r in raws]
    north = track.north_offset_deg
    # The whole clip's support is reported as a probability (calibration.py)
    # where the map was measured to hold: two-pass and physical smoothing
    # (ECE 0.074 and 0.081 on the suite). Online smoothing's causal angles
    # stray further (ECE 0.255 with the map), and the thesis's tracker keeps
    # its own score: both report the support, labelled as such.
    calibrated = (options.calibrated_confidence and options.method == "default"
                  and options.smoothing != "online"
                  and track.method.get("tracking") == "whole_clip")
    track.method["confidence"] = (trackfile.ConfidenceKind.PROBABILITY if calibrated else
                                  trackfile.ConfidenceKind.SUPPORT).value
    # A frame without direct sunlight, or whose camera looks away from where
    # the shadows fall, could not show the Sun.
    could_show = [r for r in raws if r.sunlight != Sunlight.NO and r.shadows_in_view]
    measured = sum(r.has_sun for r in could_show)
    share = measured / len(could_show) if could_show else 1.0
    track.extra["sun_measured_share"] = round(share, 4)
    misfit = calibration.model_misfit(
        r.tracked.misfit for r in raws if r.has_sun and r.tracked is not None
    ) if options.method == "default" else None  # the thesis's tracker measures none
    if misfit is not None:
        track.extra["model_misfit"] = round(misfit, 4)
    refined = bool((track.extra.get("model_refinement") or {}).get("used"))
    misfits = calibration.model_doubted(misfit)  # whatever the refinement
    model_off = calibration.model_doubted(misfit, refined)
    few_measured = calibration.clip_doubted(share)
    clock_north, unexplained = _clock_rules(native, raws, times, options, few_measured,
                                            model_off)
    contradicted = 0
    if unexplained:
        raws, contradicted = _set_aside_off_the_clock(track, raws, clock_north.turn)
    smoothed = None
    if options.smoothing == "physical":
        smoothed, north = _physical(native, track, numbers, raws, options, north)
        if smoothed is not None:  # azimuths are geographic now, with the fitted north
            turn = track.north_offset_deg - north
            raws = [r if r.azimuth_deg is None else
                    replace(r, azimuth_deg=angles.wrap_azimuth_deg(r.azimuth_deg + turn))
                    for r in raws]
            if track.initial:
                track.initial["azimuth_deg"] = angles.wrap_azimuth_deg(
                    track.initial["azimuth_deg"] + turn)
            track.north_offset_deg = north
            clock_north = ClockNorth()  # the fitted north is the ephemeris's
    if smoothed is None:
        mode = "two_pass" if options.smoothing == "physical" else options.smoothing
        smoothed = _smooth_segments(numbers, raws, segments, mode, options, times, circle,
                                    paced)
    if model_off and not misfits:
        shares = "" if misfit is None else (
            f": its shadows still miss the footage's by {misfit:.0%} of the pixels by their "
            f"edges on a typical frame (a refined model that fits leaves under "
            f"{calibration.REFINED_MISFIT_MAX:.0%})")
        track.report("model", trackfile.ProblemKind.HINT,
                     f"the clip refined a hand-made model (see model_refinement){shares}; what "
                     f"it could not see of the model (a caster's height, an object whose edges "
                     f"the footage does not show) still biases every frame's Sun alike. Check "
                     f"the casters' places and sizes against the footage")
    elif misfits:
        # Shadows the model does not cast (notes.note_unmodelled_shadows,
        # reported before this) also leave the model's shadows missing the
        # footage's: that hint is kept, as a cause.
        unmodelled = track.problem("model")
        cause = ("a caster or the camera is off in the model, which biases every "
                 "frame's Sun" if unmodelled is None else
                 "a caster or the camera off in the model, or shadows it does not "
                 f"cast, bias every frame's Sun ({unmodelled.message})")
        track.report("model", trackfile.ProblemKind.HINT,
                     f"the model's shadows miss the footage's: on a typical frame "
                     f"{misfit:.0%} of the pixels by their edges are lit where the model "
                     f"shades them or the other way round, whatever the Sun (a true model "
                     f"leaves under {calibration.MODEL_MISFIT_MAX:.0%}); {cause}. Check "
                     f"the casters' places and sizes against the footage"
                     + ("" if options.refine_model else
                        ", or let the clip refine them (Refine Model, --refine-model)"))
    seldom_measured = calibrated and few_measured
    model_doubted = calibrated and model_off
    doubted = seldom_measured or model_doubted
    if seldom_measured:
        track.report("confidence", trackfile.ProblemKind.FELL_BACK,
                     f"the Sun was measured on {measured} of the {len(could_show)} frames that "
                     f"could show it ({share:.0%}): the estimate does not explain this clip "
                     f"well, so no frame's confidence reaches 0.5")
    elif model_doubted:
        track.report("confidence", trackfile.ProblemKind.FELL_BACK,
                     f"the model {_MODEL_DOUBT[refined]} (see the model's hint), so no "
                     f"frame's confidence goes above {calibration.MODEL_DOUBTED_PROBABILITY:.2f} "
                     f"(the share of such frames within 2 deg on the test scenes)")

    sunlit = {r.frame for r in raws if r.sunlight == Sunlight.YES}
    short = calibration.short_segment_frames(segments, sunlit) if calibrated else set()
    unchecked = calibration.unchecked_frames(
        (r.frame, r.circle_checked) for r in raws if r.has_sun) if calibrated else set()
    if unchecked and not doubted:
        track.report("confidence", trackfile.ProblemKind.FELL_BACK,
                     f"{len(unchecked)} frame(s) with a Sun "
                     f"({trackfile.frame_ranges(sorted(unchecked))}) could not be checked "
                     f"against the Sun's path (fewer than {sun_circle.min_frames()} frames "
                     f"whose shadows pin the Sun's height in their stretch of the clip): "
                     f"their confidence stays below 0.5")
    # Both hold a frame below 0.5 alike (calibration.probability's short_segment).
    held = short | unchecked

    def reported(support: float, frame: Optional[int] = None) -> float:
        return calibration.probability(support, doubted_clip=doubted, short_segment=frame in held,
                                       model_doubted_clip=model_doubted) if calibrated else support
    if track.initial and track.initial.get("confidence") is not None:
        track.initial["confidence"] = reported(track.initial["confidence"],
                                               track.initial.get("frame"))
    # A frame the clock puts at night has its Sun where the ephemeris puts
    # it, below the horizon. So has every predicted frame of a clip the
    # estimate does not explain: a path through so few Suns bounds nothing
    # (the AMOS webcams: 1 of 43 measured, predicted Suns 60-130 deg off),
    # nor does one through Suns a misplaced model biases. Where that clip's
    # measured Suns agree on a north of their own (a north offset left at 0),
    # the ephemeris is turned to it; so are the measured Suns the clock
    # contradicts, set aside above.
    by_ephemeris = [_predicted(r) and r.clock_sun is not None and
                    (r.clock_night or unexplained) for r in raws]
    _report_clock(track, raws, by_ephemeris, clock_north, few_measured, contradicted)
    for k, (r, z_s, a_s) in enumerate(zip(raws, *smoothed)):
        by_clock = by_ephemeris[k]
        if by_clock:
            z_s, a_s = r.clock_sun
            if clock_north.turn is not None:
                a_s = angles.wrap_azimuth_deg(a_s + clock_north.turn)
        predicted = _predicted(r) and z_s is not None and a_s is not None
        reason = r.reason
        if predicted:
            source = "the ephemeris at its time and place" if by_clock else "its segment's path"
            reason = f"{r.reason or 'no direct sunlight'}; its Sun is predicted from {source}"
        elif _predicted(r):
            reason = f"{r.reason or 'no direct sunlight'}, and nothing bounds where the Sun is"
        est = trackfile.FrameEstimate(frame=r.frame, zenith_deg=_settled(z_s),
                                      azimuth_deg=_settled(a_s),
                                      raw_zenith_deg=r.zenith_deg, raw_azimuth_deg=r.azimuth_deg,
                                      confidence=0.0 if predicted else
                                      reported(r.confidence, r.frame),
                                      reason=reason,
                                      time_utc=None if times is None else times[k].isoformat(),
                                      sunlight=r.sunlight, predicted=predicted)
        tracked = r.tracked
        if tracked is not None and tracked.shadow_end_px[0] == tracked.shadow_end_px[0]:  # NaN?
            est.shadow_start_px = [(v + 0.5) * pixel_scale - 0.5 for v in tracked.shadow_start_px]
            est.shadow_end_px = [(v + 0.5) * pixel_scale - 0.5 for v in tracked.shadow_end_px]
        if tracked is not None and r.has_sun and 0 < tracked.contrast < 100:
            est.sun_ambient_ratio = tracked.contrast
            if options.method == "default":  # the thesis's tracker measures none
                est.shadow_misfit = tracked.misfit
                est.sun_height_pinned_deg = min(smoothing.UNPINNED_HEIGHT_SPREAD_DEG,
                                                float(tracked.elevation_pinned_deg))
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
# Without capture times a frame without direct sunlight past the span gets
# its segment's circle only this share of the span's length (in frames)
# beyond it: the circle's rate is then per frame, which a pause in the
# captures (the night between two days) breaks.
PREDICT_PAST_SPAN_SHARE = 0.5


def _smooth_segments(numbers, raws, segments, mode, options, times, circle=None, paced=None):
    """Smooths each segment on its own, only between its first and last
    frames with angles and confidence (SPAN_MIN_CONFIDENCE): nothing is
    extrapolated past them beyond the Sun's own motion, and no fit runs
    through a time jump. circle, paced: as finish's."""
    index = {f: k for k, f in enumerate(numbers)}
    paced = paced or {}
    seconds = None if times is None else clock.seconds_since(times)
    zs, azs = [None] * len(numbers), [None] * len(numbers)
    for seg in segments:
        ks = sorted(index[f] for f in seg)
        whole = ks
        have = [k for k in ks if raws[k].has_sun]
        if not have:
            continue
        least = SPAN_MIN_CONFIDENCE if options.method == "default" else 0.0  # thesis: as it was
        span = [k for k in have if raws[k].confidence >= least] or have
        ks = [k for k in ks if span[0] <= k <= span[-1]]
        x = [paced.get(numbers[k], numbers[k]) for k in ks] if seconds is None else \
            [seconds[k] for k in ks]
        if mode == "two_pass" and options.method == "default":
            # The segment's Sun circle, where one was fitted, lends the fit
            # its shape where confident frames are far (two_pass_local_directions).
            along = [None if circle is None else circle.get(k) for k in ks]
            z_s, a_s = smoothing.two_pass_local_directions(
                x, *_columns([raws[k] for k in ks]),
                prior_zenith=[None if c is None else c[0] for c in along],
                prior_azimuth=[None if c is None else c[1] for c in along],
                height_spread_deg=[raws[k].height_spread_deg for k in ks])
        else:
            z_s, a_s = smoothing.smooth_angles(
                [numbers[k] for k in ks], *_columns([raws[k] for k in ks]), mode,
                degree=TWO_PASS_DEGREE.get(options.method, 3),
                space=SMOOTHING_SPACE[options.method],
                times_s=None if seconds is None else [seconds[k] for k in ks])
        for k, z, a in zip(ks, z_s, a_s):
            zs[k], azs[k] = z, a
        length = numbers[span[-1]] - numbers[span[0]]
        for k in whole:
            if span[0] <= k <= span[-1] or zs[span[0]] is None or zs[span[-1]] is None:
                continue
            end = span[0] if k < span[0] else span[-1]
            circle_end = None if circle is None else circle.get(end)
            circle_here = None if circle is None else circle.get(k)
            if not raws[k].has_sun:
                # Predicted (no direct sunlight): the segment's circle, and
                # without capture times only near the span.
                near = seconds is not None or \
                    abs(numbers[k] - numbers[end]) <= PREDICT_PAST_SPAN_SHARE * length
                if _predicted(raws[k]) and circle_end and circle_here and near:
                    zs[k], azs[k] = _past_span(zs[end], azs[end], None, None, 0.0,
                                               circle_end, circle_here)
                continue
            moved = motion.sun_motion_bound_deg(k, end, seconds)
            zs[k], azs[k] = _past_span(zs[end], azs[end], raws[k].zenith_deg,
                                       raws[k].azimuth_deg, moved, circle_end, circle_here)
    return zs, azs


# In a clip the estimate does not explain, a measured Sun more than this far
# from the ephemeris's is not the Sun's: the clock is trusted there (whole_clip's
# CLOCK_WRONG check), and so is the north the ephemeris is turned to (the
# measured Suns' own where they agree on one, else the scene's). On the
# AMOS webcams the measured Suns were 0.8-50 deg off in zenith and 5-165 deg
# in azimuth, the scenes' north measured.
CLOCK_SLACK_DEG = 10.0

# The measured Suns tell whether the scene's north offset holds: if only
# north is off, one turn of the ephemeris's azimuths takes them onto the
# measured ones. Their circular
# median turn is north when it keeps (within CLOCK_SLACK_DEG) at least
# CLOCK_NORTH_SHARE of CLOCK_NORTH_FRAMES or more measured frames with the
# clock's Sun 10-80 deg up, and more of them than the scene's north does;
# else the ephemeris stays in the scene's north. A user's scene often keeps
# the north offset at 0. On the suite's rough members given their times and
# place (the scenes' north 56-165 deg off 0, measured Suns 2-10 deg off),
# the median turn kept 71-100% of the measured Suns and was within 0.2-5
# deg of the true north. Asking for 75% within 5 deg, as this did first,
# found no north on rough9 or rough10, and the ephemeris in the scene's north
# put their every frame's Sun 85-94 deg off. On the AMOS webcams (their
# north measured) the measured Suns agree on no turn.
CLOCK_NORTH_FRAMES = 3
CLOCK_NORTH_SHARE = 0.5
CLOCK_NORTH_CANDIDATES = 200


@dataclass(frozen=True)
class ClockNorth:
    """How the measured Suns stand against the ephemeris (_clock_north)."""
    turn: Optional[float] = None  # deg added to its azimuths: the north they agree on
    measured: int = 0             # measured Suns with the clock's Sun 10-80 deg up
    kept: int = 0                 # of them within CLOCK_SLACK_DEG of it (turned by turn)
    # Hours the capture times look off by (_clock_shift), or None.
    times_off_hours: Optional[int] = None

    @property
    def contradicted(self) -> bool:
        """Enough of them to tell, and most far from it whatever north."""
        return self.measured >= CLOCK_NORTH_FRAMES and \
            self.kept < CLOCK_NORTH_SHARE * self.measured

    @property
    def confirms_scene_north(self) -> bool:
        """Enough of them to tell, most near it in the scene's north, and no
        turn nearer."""
        return self.measured >= CLOCK_NORTH_FRAMES and self.turn is None and \
            not self.contradicted and self.times_off_hours is None


# (measured Sun, the ephemeris's Sun at its time), each (zenith, azimuth).
SunPair = Tuple[Tuple[float, float], Tuple[float, float]]


def _clock_pairs(raws: Sequence[RawSun]) -> List[SunPair]:
    """The frames' measured Suns beside the ephemeris's."""
    return [((r.zenith_deg, r.azimuth_deg), r.clock_sun) for r in raws
            if r.zenith_deg is not None and r.azimuth_deg is not None
            and r.clock_sun is not None]


def _clock_rules(native, raws: Sequence[RawSun], times, options: EstimateOptions,
                 few_measured: bool, model_off: bool) -> Tuple[ClockNorth, bool]:
    """How the measured Suns stand against the clock (ClockNorth: the north
    they agree on, times that look hours off), and whether the clip is one
    the estimate does not explain, whose measured Suns the clock contradicts
    are set aside before any smoothing (_off_the_clock) and whose frames
    without a measured Sun take the ephemeris's: one whose Sun was seldom
    measured (`few_measured`), or whose model's shadows miss the footage's
    (`model_off`) where the clock agrees with most of its measured Suns in
    the scene's own north. A clock that keeps few of them is as likely wrong
    as the model (rough9's true model given times an hour late: every Sun
    set aside and predicted 68 deg off), and a north turn may be taking up a
    clock an hour off (seven rough-suite runs given such times went 0.3-2.3
    -> 2.2-6.0 deg). Times a whole number of hours off can pass for a north
    turn (an hour near noon is mostly azimuth): where shifted times explain
    the measured Suns better (_clock_shift), the clock sets nothing aside
    and the hint names the shift."""
    clock_north = _clock_north(raws)
    times_off = _clock_shift(native, raws, times, options)
    if times_off is not None:
        return ClockNorth(None, clock_north.measured, clock_north.kept, times_off), False
    return clock_north, few_measured or (model_off and clock_north.confirms_scene_north)


def _clock_north(raws: Sequence[RawSun]) -> ClockNorth:
    """The turn of the ephemeris's geographic azimuths on which the measured
    Suns agree (see CLOCK_NORTH_FRAMES), and how many it keeps."""
    return _north_of(_clock_pairs(raws))


def _north_of(pairs: Sequence[SunPair]) -> ClockNorth:
    """_clock_north of (measured, ephemeris) pairs."""
    measured = [(sun, clock_sun) for sun, clock_sun in pairs if 10.0 <= clock_sun[0] <= 80.0]
    if len(measured) < CLOCK_NORTH_FRAMES:
        return ClockNorth(measured=len(measured))
    turns = np.array([float(angles.wrap_signed_deg(sun[1] - clock_sun[1]))
                      for sun, clock_sun in measured])
    # The circular median: the measured turn nearest all others, among at
    # most CLOCK_NORTH_CANDIDATES of them spread over their order (a long
    # clip's thousands would cost their square).
    ranked = np.sort(turns)
    candidates = ranked[::max(1, len(ranked) // CLOCK_NORTH_CANDIDATES)]
    cost = np.abs(angles.wrap_signed_deg(turns[None, :] - candidates[:, None])).sum(axis=1)
    turn = float(candidates[int(np.argmin(cost))])

    found, unturned = _kept(measured, turn), _kept(measured, 0.0)
    if found >= CLOCK_NORTH_SHARE * len(measured) and found > unturned:
        return ClockNorth(turn, len(measured), found)
    return ClockNorth(None, len(measured), unturned)


def _clock_offsets_deg(pairs: Sequence[SunPair], turn: float) -> np.ndarray:
    """How far (deg) each measured Sun of the (measured, ephemeris) pairs is
    from the ephemeris's, turned by `turn`."""
    suns = angles.sun_in_world_from_angles(*np.array([sun for sun, _ in pairs]).T)
    zenith, azimuth = np.array([clock_sun for _, clock_sun in pairs]).T
    ephemeris = angles.sun_in_world_from_angles(zenith, azimuth + turn)
    return np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", suns, ephemeris), -1.0, 1.0)))


def _kept(pairs: Sequence[SunPair], turn: float) -> int:
    """How many of the pairs the ephemeris, turned by `turn`, keeps within
    CLOCK_SLACK_DEG."""
    return int(np.count_nonzero(_clock_offsets_deg(pairs, turn) <= CLOCK_SLACK_DEG))


# Whole hours the capture times may be off by, each way: a daylight-saving
# or a neighbouring zone's mistake. A clip of a few hours often fits an
# hour's shift as well as its true times (another north takes it up: 24 of
# the static 68 given their times kept every measured Sun at +-1 h), so a
# shift is tried only where the times given keep fewer than
# CLOCK_NORTH_SHARE of the measured Suns, and named where it keeps
# CLOCK_SHIFT_SHARE of them. A rough model's Suns fit an hour's shift a
# little better than their true times (rough9: 90% kept at -1 h, 86% at its
# times); a Sun the estimate got wrong can fit a shift of many hours
# (walls1: 96% kept at +7 h, 35% at its times).
CLOCK_SHIFT_MAX_HOURS = 2
CLOCK_SHIFT_SHARE = 0.75
# Measured Suns the shifts are tried on at most, spread over the clip (the
# ephemeris costs a native call a frame and a shift).
CLOCK_SHIFT_FRAMES = 48


def _clock_shift(native, raws: Sequence[RawSun], times, options: EstimateOptions) -> Optional[int]:
    """Where the ephemeris at the times given keeps fewer than
    CLOCK_NORTH_SHARE of the measured Suns (in a north of their own or the
    scene's), the whole-hour shift of the times under which it keeps at
    least CLOCK_SHIFT_SHARE of them, the most; None (no native core, no
    times or place, as in a unit test, fewer than CLOCK_NORTH_FRAMES
    measured Suns, or no shift does)."""
    if native is None or times is None or options.latitude_deg is None or \
            options.longitude_deg is None:
        return None
    lat, lon = float(options.latitude_deg), float(options.longitude_deg)
    picked = [(r.zenith_deg, r.azimuth_deg, t) for r, t in zip(raws, times)
              if r.zenith_deg is not None and r.azimuth_deg is not None
              and r.clock_sun is not None]
    if len(picked) < CLOCK_NORTH_FRAMES:
        return None
    picked = picked[::max(1, len(picked) // CLOCK_SHIFT_FRAMES)]

    def kept(hours: int) -> int:
        later = dt.timedelta(hours=hours)
        pairs = [((z, a), ephemeris_sun(native, t + later, lat, lon)) for z, a, t in picked]
        # Every measured Sun counts, whatever the clock's height: a shift
        # that lifts a dusk clip's Suns into the north's 10-80 deg must not
        # win by counting more of them.
        return _kept(pairs, _north_of(pairs).turn or 0.0)
    best, best_kept = None, kept(0)
    if best_kept >= CLOCK_NORTH_SHARE * len(picked):
        return None
    # The smallest shift first: of shifts that keep as many, it is kept.
    for hours in sorted(range(-CLOCK_SHIFT_MAX_HOURS, CLOCK_SHIFT_MAX_HOURS + 1), key=abs)[1:]:
        n = kept(hours)
        if n >= CLOCK_SHIFT_SHARE * len(picked) and n > best_kept:
            best, best_kept = hours, n
    return best


def _set_aside_off_the_clock(track: trackfile.Track, raws: List[RawSun],
                             north_turn: Optional[float]) -> Tuple[List[RawSun], int]:
    """The raw Suns with those the clock contradicts set aside
    (_off_the_clock), and how many; the track's initial Sun goes with its
    frame's."""
    kept = [_off_the_clock(r, north_turn) for r in raws]
    set_aside = {k.frame: k.reason for k, r in zip(kept, raws) if k is not r}
    if track.initial and track.initial.get("frame") in set_aside:
        # The initial Sun is that frame's measured Sun: set aside alike.
        track.initial["confidence"] = 0.0
        track.initial["message"] = f"set aside: {set_aside[track.initial['frame']]}"
    return kept, len(set_aside)


def _report_clock(track: trackfile.Track, raws: Sequence[RawSun], by_ephemeris: Sequence[bool],
                  clock_north: ClockNorth, few_measured: bool, contradicted: int) -> None:
    """The hints of the clock's rules: times that look whole hours off, the
    north the measured Suns agree on, or that most of them agree with the
    ephemeris in no north; and the daytime frames the ephemeris predicts."""
    north_turn = clock_north.turn
    shift = clock_north.times_off_hours
    if shift is not None:
        track.report("clock", trackfile.ProblemKind.HINT,
                     f"the measured Suns agree with the ephemeris better {abs(shift)} h "
                     f"{'after' if shift > 0 else 'before'} their capture times than at them: "
                     f"the times look {abs(shift)} h off (a time zone or daylight-saving "
                     f"mistake? times without a zone of their own are read in the panel's "
                     f"Time Zone or --utc-offset, else as UTC), so the ephemeris bounds no "
                     f"daytime frame and turns no north")
    elif clock_north.contradicted:
        track.report("clock", trackfile.ProblemKind.HINT,
                     f"{clock_north.measured - clock_north.kept} of {clock_north.measured} "
                     f"measured Suns are more than {CLOCK_SLACK_DEG:.0f} deg from the "
                     f"ephemeris's at their times and place, in any north: the model (its "
                     f"casters, the camera), the times (their zone) or the place is off")
    if north_turn is not None:
        track.report("clock", trackfile.ProblemKind.HINT,
                     f"the measured Suns agree with the ephemeris at their times and place in "
                     f"a north {north_turn:+.1f} deg from the scene's (north offset "
                     f"{track.north_offset_deg + north_turn:.1f} deg against "
                     f"{track.north_offset_deg:.1f}): the frames the ephemeris predicts take "
                     f"its Sun in that north. If the measured Suns are right, set the Sun "
                     f"Position add-on's North Offset to it: the track's azimuths are "
                     f"measured from the scene's north")
    daytime = [r.frame for r, e in zip(raws, by_ephemeris) if e and not r.clock_night]
    if daytime:
        # The note names the north the predictions are in: a turn the
        # measured Suns agree on is applied however small it is.
        north_said = (
            f"in the scene's north (north offset {track.north_offset_deg:.1f} deg: the Sun "
            f"Position add-on's North Offset; set it if north is elsewhere)"
            if north_turn is None else
            f"in the north the measured Suns agree on (north offset "
            f"{track.north_offset_deg + north_turn:.1f} deg, against the scene's "
            f"{track.north_offset_deg:.1f}; see the clock hint)")
        track.report("prediction", trackfile.ProblemKind.HINT,
                     ("the Sun was measured on too few frames for its path to bound the others: "
                      if few_measured else
                      "the model's shadows miss the footage's (see the model's hint), so the "
                      "path through its measured Suns does not bound the others: ")
                     + f"{len(daytime)} frame(s) ({trackfile.frame_ranges(daytime)}) take the "
                     f"ephemeris's Sun at their time and place"
                     + (f" ({contradicted} of them had a measured Sun more than "
                        f"{CLOCK_SLACK_DEG:.0f} deg from it)" if contradicted else "")
                     + f", {north_said}")


def _off_the_clock(r: RawSun, north_turn: Optional[float]) -> RawSun:
    """A measured Sun the clock contradicts, as a frame whose sunlight is
    unknown and has no Sun of its own (predicted: the track's raw angles
    and tracked shadow are null, the reason says how far off it was); else
    r."""
    if r.zenith_deg is None or r.azimuth_deg is None or r.clock_sun is None or \
            r.sunlight != Sunlight.YES:
        return r
    off = float(_clock_offsets_deg([((r.zenith_deg, r.azimuth_deg), r.clock_sun)],
                                   north_turn or 0.0)[0])
    if off <= CLOCK_SLACK_DEG:
        return r
    return replace(r, zenith_deg=None, azimuth_deg=None, tracked=None,
                   sunlight=Sunlight.UNKNOWN,
                   reason=f"its shadows put the Sun {off:.0f} deg from where the ephemeris "
                          f"does at its time and place")


def _predicted(r: RawSun) -> bool:
    """Whether a frame's Sun is to be predicted (from its segment's path, or
    the ephemeris): the method decided it has no direct sunlight, or cannot
    tell."""
    return r.sunlight is not None and r.sunlight != Sunlight.YES


def _columns(raws: Sequence[RawSun]
             ) -> Tuple[List[Optional[float]], List[Optional[float]], List[float]]:
    """(zeniths, geographic azimuths, confidences) of raw Suns."""
    return ([r.zenith_deg for r in raws], [r.azimuth_deg for r in raws],
            [r.confidence for r in raws])


def _world_azimuths(raws: Sequence[RawSun], north: float) -> List[Optional[float]]:
    return [None if r.azimuth_deg is None else
            float(angles.azimuth_world_from_geographic(r.azimuth_deg, north)) for r in raws]


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
