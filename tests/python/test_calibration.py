"""Confidence as a probability (issue 25 item 4): the fit that makes it one
(core.evaluation.isotonic_fit, run by bench/calibrate.py), the map the
estimate applies (estimate.calibration) and where it applies it."""
import datetime as dt
import importlib.util
import json
import os
import random
import sys

import pytest

from sunlapse.core import evaluation, trackfile
from sunlapse.estimate import calibration, finish
from sunlapse.estimate import options as estimate_options
from sunlapse.estimate.raw import RawSun


def drawn(n, chance, seed=3):
    """n frames (error deg, support) whose chance of being within 2 deg at
    support s is chance(s)."""
    rng = random.Random(seed)
    out = []
    for _ in range(n):
        s = rng.random()
        out.append((rng.uniform(0, 2) if rng.random() < chance(s) else rng.uniform(2.1, 20), s))
    return out


def test_the_fit_makes_an_overconfident_support_a_probability_on_new_frames():
    def chance(s):
        return s * s  # support 0.5 is right a quarter of the time
    fitted = evaluation.isotonic_fit(drawn(4000, chance), 2.0, min_block=40)
    fresh = drawn(4000, chance, seed=4)
    _, before = evaluation.reliability(fresh)
    _, after = evaluation.reliability([(e, calibration.probability(s, fitted)) for e, s in fresh])
    assert before > 0.15
    assert after < 0.03, after


def test_the_fit_is_monotone_and_each_knot_stands_for_enough_frames():
    frames = drawn(500, lambda s: 0.2 + 0.6 * s)
    knots = evaluation.isotonic_fit(frames, 2.0, min_block=50)
    assert len(knots) <= 500 // 50
    assert all(a[0] < b[0] and a[1] < b[1] for a, b in zip(knots, knots[1:]))
    assert all(0.0 <= p <= 1.0 for _, p in knots)
    # Without the block floor, noise alone sets more knots.
    assert len(evaluation.isotonic_fit(frames, 2.0, min_block=1)) > len(knots)
    assert evaluation.isotonic_fit([], 2.0) == []


def test_the_map_interpolates_holds_its_ends_and_keeps_zero():
    knots = ((0.6, 0.7), (0.9, 0.9))
    assert calibration.probability(0.75, knots) == pytest.approx(0.8)
    assert calibration.probability(0.55, knots) == pytest.approx(0.7)
    assert calibration.probability(0.95, knots) == pytest.approx(0.9)
    assert calibration.probability(0.0, knots) == 0.0


def test_frames_the_estimate_doubted_stay_below_one_half():
    knots = ((0.1, 0.9), (1.0, 0.95))
    below = calibration.DOUBTED_SUPPORT - 0.01
    assert calibration.probability(below, knots) == calibration.DOUBTED_MAX_PROBABILITY < 0.5
    assert calibration.probability(calibration.DOUBTED_SUPPORT, knots) > 0.9


def test_frames_of_one_confidence_are_pooled_not_split():
    # 10 frames at 0.9, 3 of them off: one knot at 0.7, not a 0 and a 1.
    frames = [(1.0, 0.9)] * 7 + [(9.0, 0.9)] * 3 + [(1.0, 0.2), (9.0, 0.2)]
    assert evaluation.isotonic_fit(frames, 2.0) == [(pytest.approx(0.2), 0.5),
                                                    (pytest.approx(0.9), pytest.approx(0.7))]


def test_the_shipped_map_is_a_monotone_probability():
    knots = calibration.SUPPORT_TO_PROBABILITY
    # One knot is a fit too: frames of every support within 2 deg alike.
    assert len(knots) >= 1, "fit it with bench/calibrate.py --write"
    assert all(0.0 <= p <= 1.0 for _, p in knots)
    assert all(a[0] < b[0] and a[1] <= b[1] for a, b in zip(knots, knots[1:]))
    values = [calibration.probability(k / 100) for k in range(101)]
    assert all(a <= b for a, b in zip(values, values[1:]))


def finished(method, calibrated, tracking="whole_clip", smoothing="two_pass"):
    raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=c)
            for f, c in zip(range(1, 6), (0.05, 0.3, 0.5, 0.7, 0.95))]
    track = trackfile.Track(method={"initial": method, "tracking": tracking,
                                    "smoothing": "two_pass"},
                            initial={"frame": 4, "zenith_deg": 44.0, "azimuth_deg": 184.0,
                                     "confidence": 0.7})
    opts = estimate_options.EstimateOptions(method=method, calibrated_confidence=calibrated,
                                            smoothing=smoothing)
    finish.finish(None, track, raws, opts, None, None, [[r.frame for r in raws]])
    return track, [r.confidence for r in raws]


def test_the_whole_clip_track_reports_the_probability_and_says_so():
    track, support = finished("default", True)
    assert trackfile.ConfidenceKind.of(track) == trackfile.ConfidenceKind.PROBABILITY
    assert [f.confidence for f in track.frames] == \
        [pytest.approx(calibration.probability(s)) for s in support]
    assert [f.confidence for f in track.frames] != pytest.approx(support)
    assert track.initial["confidence"] == pytest.approx(calibration.probability(0.7))


@pytest.mark.parametrize("method,calibrated,tracking,smoothing", [
    ("default", False, "whole_clip", "two_pass"), ("thesis", True, "thesis", "two_pass"),
    ("default", True, "thesis", "two_pass"), ("default", True, "whole_clip", "online")])
def test_asked_for_or_not_fitted_the_support_is_reported_as_it_is(method, calibrated, tracking,
                                                                  smoothing):
    track, support = finished(method, calibrated, tracking, smoothing)
    assert trackfile.ConfidenceKind.of(track) == trackfile.ConfidenceKind.SUPPORT
    assert [f.confidence for f in track.frames] == pytest.approx(support)
    assert track.initial["confidence"] == 0.7


def test_a_track_says_what_its_confidence_is_and_old_files_are_support():
    track = trackfile.Track(method={"confidence": "probability within 2 deg"})
    back = trackfile.from_json(trackfile.to_json(track))
    assert trackfile.ConfidenceKind.of(back) == trackfile.ConfidenceKind.PROBABILITY
    for method in ({}, {"confidence": "something newer"}):
        assert trackfile.ConfidenceKind.of(trackfile.Track(method=method)) == \
            trackfile.ConfidenceKind.SUPPORT


def test_a_clip_whose_sun_was_seldom_measured_keeps_its_support_below_one_half():
    share = calibration.MEASURED_SHARE_MIN
    assert calibration.clip_doubted(share - 0.01) and not calibration.clip_doubted(share)
    knots = ((0.1, 0.9), (1.0, 0.95))
    assert calibration.probability(0.97, knots, doubted_clip=True) == \
        calibration.DOUBTED_MAX_PROBABILITY
    assert calibration.probability(0.3, knots, doubted_clip=True) == 0.3
    # In the run: 2 of the 5 frames that could show the Sun measured it.
    raws = [RawSun(1, 40.0, 180.0, confidence=0.97, sunlight=trackfile.Sunlight.YES),
            RawSun(2, 41.0, 181.0, confidence=0.3, sunlight=trackfile.Sunlight.YES)] + \
        [RawSun(f, confidence=0.0, sunlight=trackfile.Sunlight.UNKNOWN) for f in (3, 4, 5)] + \
        [RawSun(6, confidence=0.0, sunlight=trackfile.Sunlight.NO)]
    track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                    "smoothing": "two_pass"})
    finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                  [[r.frame for r in raws]])
    assert track.extra["sun_measured_share"] == pytest.approx(0.4)
    assert [f.confidence for f in track.frames[:2]] == [calibration.DOUBTED_MAX_PROBABILITY,
                                                        pytest.approx(0.3)]
    problem = track.problem("confidence")
    assert problem is not None and "2 of the 5 frames" in problem.message


def test_frames_looking_away_from_the_shadows_do_not_count_against_the_clip():
    """A moving camera's frames that do not see where the shadows fall could
    not show the Sun: 9 of 10 measured stays a clip the map applies to,
    however many frames looked away (issue 26)."""
    raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97, sunlight=trackfile.Sunlight.YES)
            for f in range(1, 10)] + [RawSun(10, sunlight=trackfile.Sunlight.UNKNOWN)]
    away = [RawSun(f, sunlight=trackfile.Sunlight.UNKNOWN, shadows_in_view=False)
            for f in range(11, 14)]

    def share(frames):
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"})
        finish.finish(None, track, frames, estimate_options.EstimateOptions(), None, None,
                      [[r.frame for r in frames]])
        return track.extra["sun_measured_share"], track.frames[0].confidence
    assert share(raws) == (pytest.approx(0.9), pytest.approx(calibration.probability(0.97)))
    assert share(raws + away) == share(raws)
    # Counted as frames that could show it, they would doubt the clip.
    counted = [RawSun(r.frame, sunlight=r.sunlight) for r in away]
    assert share(raws + counted)[1] == calibration.DOUBTED_MAX_PROBABILITY


def test_a_segment_of_few_sunlit_frames_is_short_however_many_dark_ones_it_has():
    """walls9 (a fresh suite member): 7 dark frames and 2 sunlit ones split
    off the rest by a jump of the path; the 2 were 59 deg off at 0.93. Dark
    frames show nothing of the Sun's path, so only sunlit frames count."""
    segments = [list(range(1, 10)), list(range(10, 33))]
    sunlit = set(range(8, 33))
    assert calibration.short_segment_frames(segments) == set()
    assert calibration.short_segment_frames(segments, sunlit) == set(range(1, 10))
    raws = [RawSun(f, sunlight=trackfile.Sunlight.NO) for f in range(1, 8)] + \
        [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97, sunlight=trackfile.Sunlight.YES)
         for f in range(8, 33)]
    track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                    "smoothing": "two_pass"})
    finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None, segments)
    by_frame = {f.frame: f for f in track.frames}
    assert [by_frame[f].confidence for f in (8, 9)] == [calibration.DOUBTED_MAX_PROBABILITY] * 2
    assert all(by_frame[f].confidence > 0.9 for f in range(10, 33))


def test_a_short_segment_split_off_the_clip_stays_below_one_half():
    assert calibration.short_segment_frames([[1, 2, 3], [4, 5, 6, 7, 8]]) == {1, 2, 3}
    assert calibration.short_segment_frames([[1, 2, 3]]) == set()  # the whole clip
    raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97, sunlight=trackfile.Sunlight.YES)
            for f in range(1, 9)]
    track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                    "smoothing": "two_pass"})
    finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                  [[1, 2, 3], [4, 5, 6, 7, 8]])
    assert [f.confidence for f in track.frames[:3]] == [calibration.DOUBTED_MAX_PROBABILITY] * 3
    assert all(f.confidence > 0.9 for f in track.frames[3:])


def test_frames_no_circle_of_the_suns_path_checked_stay_below_one_half():
    """A clip of a few frames, or a stretch of one, has too few Suns for the
    circle of the Sun's path (TrimmedCircleOptions.min_frames), or too few whose
    shadows pin the Sun's height: nothing checks their Suns, and on the
    suite's scenes cut to 1-12 frames some were 5-148 deg off at 0.98."""
    assert calibration.unchecked_frames([(1, False), (2, True), (3, None)]) == {1}

    def finished(checked):
        raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97,
                       sunlight=trackfile.Sunlight.YES, circle_checked=c)
                for f, c in enumerate(checked, start=1)]
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"})
        finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                      [[r.frame for r in raws]])
        return [f.confidence for f in track.frames], track.problem("confidence")
    # Three frames no circle checked: all held, and the run says why.
    held, why = finished([False] * 3)
    assert held == [calibration.DOUBTED_MAX_PROBABILITY] * 3
    assert why is not None and "could not be checked" in why.message
    # Twelve frames, the first four unchecked: those held.
    mixed, _ = finished([False] * 4 + [True] * 8)
    assert mixed[:4] == [calibration.DOUBTED_MAX_PROBABILITY] * 4
    assert all(c > 0.9 for c in mixed[4:])
    # Every frame checked, or a method without the check: none held, nothing said.
    for flags in ([True] * 12, [None] * 12):
        free, why = finished(flags)
        assert all(c > 0.9 for c in free) and why is None


class _Tracked:
    """What finish.py reads of a native TrackedFrame."""

    def __init__(self, misfit):
        self.misfit = misfit
        self.contrast = 2.0
        self.elevation_pinned_deg = float("inf")
        self.shadow_start_px = self.shadow_end_px = (float("nan"), float("nan"))


def _finished_with_misfits(misfits, method="default"):
    raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97, sunlight=trackfile.Sunlight.YES,
                   tracked=_Tracked(m)) for f, m in enumerate(misfits, start=1)]
    track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                    "smoothing": "two_pass"})
    finish.finish(None, track, raws, estimate_options.EstimateOptions(method=method), None,
                  None, [[r.frame for r in raws]])
    return track


def test_a_clip_whose_model_does_not_fit_its_footage_stays_below_one_half_and_says_why():
    """Issue 25 (rough models): a hand-made model's misplaced casters bias
    every frame alike, and only the shadows' misfit shows it. The clip's
    median decides, so a few badly fitted frames do not."""
    limit = calibration.MODEL_MISFIT_MAX
    assert calibration.model_misfit([None, 0.1, 0.3, 0.2]) == pytest.approx(0.2)
    assert calibration.model_misfit([None]) is None
    assert not calibration.model_doubted(None)
    assert calibration.model_doubted(limit) and not calibration.model_doubted(limit - 0.001)
    assert calibration.clip_doubted(1.0, limit) and not calibration.clip_doubted(1.0, 0.0)

    fitting = _finished_with_misfits([0.01] * 7 + [0.5] * 3)
    assert fitting.extra["model_misfit"] == pytest.approx(0.01)
    assert fitting.problem("model") is None
    assert all(f.confidence > 0.9 for f in fitting.frames)

    rough = _finished_with_misfits([0.01] * 3 + [limit + 0.05] * 7)
    assert rough.extra["model_misfit"] == pytest.approx(limit + 0.05)
    cap = calibration.MODEL_DOUBTED_PROBABILITY
    assert 0 < cap < 0.5
    assert [f.confidence for f in rough.frames] == [pytest.approx(cap)] * 10
    knots = ((0.1, 0.9), (1.0, 0.95))
    assert calibration.probability(0.97, knots, model_doubted_clip=True) == pytest.approx(cap)
    assert calibration.probability(0.1, knots, model_doubted_clip=True) == pytest.approx(
        min(0.1, cap))
    assert calibration.probability(0.0, knots, model_doubted_clip=True) == 0.0
    hint = rough.problem("model")
    assert hint is not None and hint.kind == trackfile.ProblemKind.HINT
    assert "caster" in hint.message and f"{limit + 0.05:.0%}" in hint.message
    assert rough.problem("confidence") is not None
    back = trackfile.from_json(trackfile.to_json(rough))
    assert back.frames[5].shadow_misfit == pytest.approx(limit + 0.05)
    # A height its shadows do not pin (inf) is written as any height.
    assert back.frames[5].sun_height_pinned_deg == 90.0


def test_a_clip_whose_model_the_clip_refined_stays_below_one_half_and_says_why():
    """A model the clip had to refine was made by hand; what the refinement
    cannot see of it still biases every frame (held-out rough10: refined,
    misfit 0.054, 25 frames more than 5 deg off at 0.9 and more)."""
    limit = calibration.REFINED_MISFIT_MAX
    assert 0 < limit < calibration.MODEL_MISFIT_MAX
    assert calibration.model_doubted(None, refined=True)
    assert calibration.model_doubted(limit, refined=True)
    assert not calibration.model_doubted(limit - 0.001, refined=True)
    assert not calibration.model_doubted(limit)
    assert calibration.clip_doubted(1.0, limit, refined=True)

    def finished(used, misfit=limit + 0.01):
        raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97,
                       sunlight=trackfile.Sunlight.YES, tracked=_Tracked(misfit))
                for f in range(1, 11)]
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"})
        track.extra["model_refinement"] = {"used": used, "message": "m"}
        finish.finish(None, track, raws, estimate_options.EstimateOptions(refine_model=True),
                      None, None, [[r.frame for r in raws]])
        return track
    kept = finished(False)
    assert kept.problem("model") is None and kept.problem("confidence") is None
    assert all(f.confidence > 0.9 for f in kept.frames)
    refined = finished(True)
    cap = calibration.MODEL_DOUBTED_PROBABILITY
    assert [f.confidence for f in refined.frames] == [pytest.approx(cap)] * 10
    hint = refined.problem("model")
    assert hint is not None and "refined" in hint.message and "caster" in hint.message
    assert f"{limit + 0.01:.0%}" in hint.message
    assert "refined by the clip" in refined.problem("confidence").message
    # Refined, and its shadows then fit the footage closely: the map's.
    fits = finished(True, misfit=0.5 * limit)
    assert fits.problem("model") is None and fits.problem("confidence") is None
    assert all(f.confidence > 0.9 for f in fits.frames)


def test_shadows_the_model_does_not_cast_stay_named_when_the_model_misfits():
    """A tree's shadow over the ground (not in the model) makes the model's
    shadows miss the footage's as a misplaced caster does: the hint about
    those shadows, reported first, is kept in the misfit's, as a cause."""
    limit = calibration.MODEL_MISFIT_MAX
    raws = [RawSun(f, 40.0 + f, 180.0 + f, confidence=0.97, sunlight=trackfile.Sunlight.YES,
                   tracked=_Tracked(limit + 0.1)) for f in range(1, 8)]
    track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                    "smoothing": "two_pass"})
    seen = "1 hard ground shadow(s) on frame 4 are not cast by the model"
    track.report("model", trackfile.ProblemKind.HINT, seen)
    finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                  [[r.frame for r in raws]])
    hint = track.problem("model")
    assert hint is not None and hint.message.startswith("the model's shadows miss")
    assert f"or shadows it does not cast, bias every frame's Sun ({seen})" in hint.message
    alone = _finished_with_misfits([limit + 0.1] * 7).problem("model")
    assert alone is not None and alone.message.startswith("the model's shadows miss")
    assert "does not cast" not in alone.message
    assert "a caster or the camera is off in the model, which biases every frame's Sun. " \
        "Check" in alone.message


def test_the_thesis_method_measures_no_model_misfit():
    track = _finished_with_misfits([0.5] * 5, method="thesis")
    assert "model_misfit" not in track.extra and track.problem("model") is None
    assert all(f.shadow_misfit is None and f.sun_height_pinned_deg is None
               for f in track.frames)


def _bench_calibrate():
    """bench/calibrate.py loaded by path; the paths and modules it adds for
    itself are taken back, so that bench/'s modules shadow nothing here."""
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
        os.path.abspath(__file__)))), "bench", "calibrate.py")
    saved_path, saved_modules = list(sys.path), set(sys.modules)
    try:
        spec = importlib.util.spec_from_file_location("bench_calibrate", path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path[:] = saved_path
        for name in set(sys.modules) - saved_modules:
            del sys.modules[name]
    return module


def test_calibrate_caps_model_doubted_clips_at_their_share_within_2_deg(tmp_path):
    """bench/calibrate.py: the clips the model rule holds get, at most, the
    share of their frames that was within 2 deg, and never 0.5."""
    calibrate = _bench_calibrate()
    rows = [{"scene": "fits", "measured_share": 1.0, "model_misfit": 0.01,
             "per_frame": [{"error_deg": 0.5, "confidence": 0.9}] * 4},
            {"scene": "rough", "measured_share": 1.0,
             "model_misfit": calibration.MODEL_MISFIT_MAX,
             "per_frame": [{"error_deg": 1.0, "confidence": 0.9}] +
             [{"error_deg": 4.0, "confidence": 0.9}] * 3}]
    path = tmp_path / "suite.json"
    path.write_text(json.dumps({"smoothings": {"two_pass": {"scenes": rows}}}))
    scenes, doubted, model = calibrate.scenes_from([str(path)])
    assert model == {"two_pass:fits": False, "two_pass:rough": True}
    assert doubted["two_pass:rough"] and not doubted["two_pass:fits"]
    assert calibrate.model_cap(scenes["two_pass:rough"]) == pytest.approx(0.25)
    assert calibrate.model_cap([(0.1, 0.9)] * 3) == calibration.DOUBTED_MAX_PROBABILITY
    assert calibrate.mapped(scenes["two_pass:rough"], ((0.1, 0.9),), True, True, 0.25) == \
        [(1.0, 0.25)] + [(4.0, 0.25)] * 3


def test_a_seldom_measured_clip_with_a_clock_predicts_its_frames_by_the_ephemeris():
    """With capture times and a place, a clip whose Sun was seldom measured
    (the AMOS webcams: 1 of 43) predicts its frames without a measured Sun
    where the ephemeris puts the Sun, not on a path through too few Suns,
    and says so; a clip measured on most frames keeps its path (issue 25)."""
    Sunlight = trackfile.Sunlight
    unknown, night = (5, 6), 40

    def run(measured, clock_of_measured):
        raws = [RawSun(f, 40.0 + 0.1 * f, 180.0 + f, confidence=0.9, sunlight=Sunlight.YES,
                       clock_sun=clock_of_measured(f))
                for f in range(1, measured + 3) if f not in unknown]
        raws += [RawSun(f, confidence=0.0, sunlight=Sunlight.UNKNOWN,
                        clock_sun=(60.0 + f, 150.0 + f)) for f in unknown]
        raws += [RawSun(night, confidence=0.0, sunlight=Sunlight.NO, clock_sun=(95.0, 250.0),
                        clock_night=True)]
        raws.sort(key=lambda r: r.frame)
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"}, north_offset_deg=-28.0,
                                initial={"frame": 4, "zenith_deg": 40.4, "azimuth_deg": 184.0,
                                         "confidence": 0.9, "message": "the best-supported"})
        finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                      [[r.frame for r in raws]])
        return track, {f.frame: f for f in track.frames}

    # 5 of 7 frames that could show the Sun measured it, nowhere near the
    # ephemeris (a model the footage does not fit): the scene's north holds.
    track, by_frame = run(5, lambda f: (20.0 + 9.0 * f, 300.0 - 37.0 * f))
    for f in unknown:
        est = by_frame[f]
        assert est.predicted and est.confidence == 0.0
        assert (est.zenith_deg, est.azimuth_deg) == (60.0 + f, 150.0 + f)
        assert "ephemeris" in est.reason
    assert (by_frame[night].zenith_deg, by_frame[night].azimuth_deg) == (95.0, 250.0)
    # Frame 3's measured Sun (40.3 deg from the zenith, azimuth 183) is 8
    # deg from the ephemeris's (47, 189): kept. Frame 4's is 18 deg from it:
    # predicted, as are 1, 2 and 7.
    assert not by_frame[3].predicted and abs(by_frame[3].zenith_deg - 40.3) < 1.0
    assert by_frame[4].predicted and by_frame[4].sunlight == trackfile.Sunlight.UNKNOWN
    assert (by_frame[4].zenith_deg, by_frame[4].azimuth_deg) == (56.0, 152.0)
    assert by_frame[4].raw_zenith_deg is None and by_frame[4].confidence == 0.0
    assert "deg from where the ephemeris" in by_frame[4].reason
    # Frame 4's Sun was the run's initial Sun: set aside with it.
    assert track.initial["confidence"] == 0.0 and "set aside" in track.initial["message"]
    hint = track.problem("prediction")
    assert hint is not None and hint.kind == trackfile.ProblemKind.HINT
    assert "6 frame(s) (1-2, 4-7)" in hint.message and "4 of them" in hint.message
    assert "-28.0" in hint.message

    # The measured Suns are the ephemeris's turned by 30 deg: a north offset
    # left 30 deg off. The predicted Suns are turned with them, and the
    # hint names the north they agree on.
    track, by_frame = run(5, lambda f: (40.0 + 0.1 * f, 150.0 + f))
    for f in unknown:
        assert by_frame[f].predicted and by_frame[f].zenith_deg == 60.0 + f
        assert by_frame[f].azimuth_deg == pytest.approx(180.0 + f)
    assert "2.0 deg" in track.problem("prediction").message   # -28 + 30

    # 30 of 32 measured: the path predicts the day's frames.
    track, by_frame = run(30, lambda f: (45.0, 200.0))
    assert track.problem("prediction") is None
    for f in unknown:
        est = by_frame[f]
        assert est.predicted and est.zenith_deg is not None
        assert abs(est.zenith_deg - 40.0 - 0.1 * f) < 1.0 and "path" in est.reason
    assert (by_frame[night].zenith_deg, by_frame[night].azimuth_deg) == (95.0, 250.0)


def test_suns_the_clock_sets_aside_do_not_steer_the_smoothing_of_the_others():
    """A seldom-measured clip's measured Suns the clock contradicts are set
    aside before the smoothing: the Suns kept are smoothed among
    themselves, not pulled toward the ones set aside."""
    Sunlight = trackfile.Sunlight
    off = {1, 2, 4}
    raws = [RawSun(f, *((70.0, 260.0) if f in off else (40.0, 180.0)), confidence=0.9,
                   sunlight=Sunlight.YES, clock_sun=(40.0, 180.0)) for f in range(1, 8)]
    raws += [RawSun(f, confidence=0.0, sunlight=Sunlight.UNKNOWN, clock_sun=(40.0, 180.0))
             for f in (8, 9, 10)]
    track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                    "smoothing": "two_pass"})
    finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                  [[r.frame for r in raws]])
    by_frame = {f.frame: f for f in track.frames}
    assert track.extra["sun_measured_share"] == pytest.approx(0.7)
    for f in (3, 5, 6, 7):
        assert not by_frame[f].predicted
        assert by_frame[f].zenith_deg == pytest.approx(40.0, abs=0.01)
    for f in off:
        assert by_frame[f].predicted and by_frame[f].zenith_deg == 40.0


def test_the_measured_suns_north_is_their_circular_median_on_a_long_clip_too():
    """The turn the measured Suns agree on, from thousands of them (a long
    clip's candidates are spread over their order): near their circular
    median, across the wrap at 180 deg; none where they disagree."""
    rng = random.Random(5)
    Sunlight = trackfile.Sunlight

    def suns(turn_of):
        return [RawSun(f, 45.0, (200.0 + turn_of(f)) % 360.0, confidence=0.9,
                       sunlight=Sunlight.YES, clock_sun=(45.0, 200.0)) for f in range(5000)]
    turn = finish._clock_north(suns(lambda f: 178.0 + rng.uniform(-3.0, 3.0))).turn
    assert turn is not None and abs(((turn - 178.0) + 180.0) % 360.0 - 180.0) < 0.5
    assert finish._clock_north(suns(lambda f: rng.uniform(-180.0, 180.0))).turn is None


def test_a_clip_whose_model_misses_the_footage_takes_the_ephemeris_where_the_clock_says_so():
    """With capture times and a place, a clip measured on every frame whose
    model's shadows miss the footage's (Marseille's sundial) sets aside the
    measured Suns far from the ephemeris and predicts them by it where the
    clock agrees with most of them in the scene's own north; the same clip
    with a model that fits keeps its measured Suns, and so does one whose
    Suns the clock meets only through a north turn (it may be taking up
    times an hour off) or in no north at all."""
    Sunlight = trackfile.Sunlight
    clock = {f: (50.0 - f, 100.0 + 3.0 * f) for f in range(1, 11)}
    far = {3, 8}

    def run(misfit, far=far, north_off=0.0):
        # The measured Suns are the ephemeris's, two of them 25 deg off.
        raws = [RawSun(f, clock[f][0] + (25.0 if f in far else 0.5),
                       clock[f][1] + north_off, confidence=0.9, sunlight=Sunlight.YES,
                       tracked=_Tracked(misfit), clock_sun=clock[f]) for f in clock]
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"})
        finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                      [[r.frame for r in raws]])
        return track, {f.frame: f for f in track.frames}

    doubted = calibration.MODEL_MISFIT_MAX + 0.05
    track, by_frame = run(doubted)
    for f in far:
        est = by_frame[f]
        assert est.predicted and est.confidence == 0.0 and est.raw_zenith_deg is None
        assert (est.zenith_deg, est.azimuth_deg) == clock[f]
    for f in set(clock) - far:
        assert not by_frame[f].predicted and by_frame[f].raw_zenith_deg is not None
    hint = track.problem("prediction")
    assert hint is not None and hint.message.startswith("the model's shadows miss the footage's")
    assert "2 frame(s) (3, 8)" in hint.message and "north offset 0.0 deg" in hint.message

    track, by_frame = run(0.01)
    assert track.problem("prediction") is None
    assert not any(by_frame[f].predicted for f in clock)

    # The scene's north 90 deg off: a turn finds it, and the footage stands.
    track, by_frame = run(doubted, north_off=90.0)
    assert track.problem("prediction") is None and "+90.0 deg" in track.problem("clock").message
    assert not any(by_frame[f].predicted for f in clock)

    # Every measured Sun 25 deg from the ephemeris, in any north: the clock
    # is as likely wrong as the model, and the footage stands; the clock
    # hint says they disagree.
    track, by_frame = run(doubted, far=set(clock))
    assert track.problem("prediction") is None
    assert not any(by_frame[f].predicted for f in clock)
    assert track.problem("clock").message.startswith("10 of 10 measured Suns are more than")


def test_the_north_the_measured_suns_agree_on_needs_half_of_them_and_more_than_the_scenes():
    """The measured Suns' turn is north when it keeps at least half of them
    within the slack, and more of them than the scene's north does: a
    rough model's Suns (rough10: 71% kept) turn it; Suns that agree on
    nothing (the AMOS webcams) or that the scene's north keeps as well do
    not."""
    rng = random.Random(3)
    Sunlight = trackfile.Sunlight

    def suns(measured):
        return [RawSun(f, z, a % 360.0, confidence=0.9, sunlight=Sunlight.YES,
                       clock_sun=(45.0, 200.0)) for f, (z, a) in enumerate(measured)]
    # 7 of 10 within 3 deg of the ephemeris turned by 85 deg, 3 far off.
    rough = [(45.0 + rng.uniform(-3, 3), 285.0 + rng.uniform(-3, 3)) for _ in range(7)]
    rough += [(45.0 + 20.0, 285.0 + 40.0 * k) for k in (1, 2, 3)]
    turn = finish._clock_north(suns(rough)).turn
    assert turn is not None and abs(turn - 85.0) < 3.5
    # 4 of 10 agree: no north.
    few = rough[:4] + [(45.0 + 20.0, 285.0 + 25.0 * k) for k in range(1, 7)]
    assert finish._clock_north(suns(few)).turn is None
    scattered = [(rng.uniform(5, 85), rng.uniform(0, 360)) for _ in range(12)]
    scattered_north = finish._clock_north(suns(scattered))
    assert scattered_north.turn is None and scattered_north.contradicted
    # Suns on the ephemeris, one 8 deg away in azimuth: the median turn
    # (0 here) keeps no more than the scene's north does.
    on_it = finish._clock_north(suns([(45.0, 200.0)] * 4 + [(45.0, 208.0)]))
    assert on_it.turn is None and not on_it.contradicted and on_it.kept == 5


def test_night_frames_take_the_ephemeris_in_the_north_the_measured_suns_agree_on():
    """A clip the estimate explains, given its times and a place, whose
    scene keeps its north offset at 0 while north is 40 deg away: its
    measured Suns are kept as they are, its frames the clock puts at night
    take the ephemeris's Sun turned to the measured Suns' north (the lamp
    does not swing round at dusk), and a hint names that north; with the
    scene's north right there is no such hint."""
    Sunlight = trackfile.Sunlight
    clock = {f: (40.0 + 4.0 * f, 200.0 + 5.0 * f) for f in range(1, 9)}

    def run(north_off, higher=0.0):
        raws = [RawSun(f, clock[f][0] + 0.2 - higher, clock[f][1] + north_off, confidence=0.9,
                       sunlight=Sunlight.YES, tracked=_Tracked(0.01), clock_sun=clock[f])
                for f in clock]
        raws.append(RawSun(9, confidence=0.0, sunlight=Sunlight.NO, clock_sun=(93.0, 250.0),
                           clock_night=True))
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"})
        finish.finish(None, track, raws, estimate_options.EstimateOptions(), None, None,
                      [[r.frame for r in raws]])
        return track, {f.frame: f for f in track.frames}

    track, by_frame = run(40.0)
    assert all(not by_frame[f].predicted for f in clock)
    assert by_frame[9].predicted and by_frame[9].zenith_deg == 93.0
    assert by_frame[9].azimuth_deg == pytest.approx(290.0)
    hint = track.problem("clock")
    assert hint is not None and hint.kind == trackfile.ProblemKind.HINT
    assert "+40.0 deg" in hint.message and "North Offset" in hint.message
    assert track.problem("prediction") is None

    track, by_frame = run(0.0)
    assert track.problem("clock") is None and by_frame[9].azimuth_deg == 250.0

    # Measured Suns 25 deg higher than the ephemeris's: no north, a hint.
    track, by_frame = run(0.0, higher=25.0)
    hint = track.problem("clock")
    assert hint is not None and hint.message.startswith("8 of 8 measured Suns are more than")
    assert by_frame[9].azimuth_deg == 250.0


def test_a_clock_an_hour_off_is_named():
    """Measured Suns that agree with the ephemeris an hour after their
    capture times (a daylight-saving mistake): the clock hint says the times
    look 1 h off; Suns that agree with it at no time get the general hint."""
    native = pytest.importorskip("_native")
    Sunlight = trackfile.Sunlight
    lat, lon = 45.0, 5.0
    # A whole June day, 05:00-18:30 UTC: no north turn takes up an hour's
    # shift over it (the Sun's azimuth moves fastest at noon).
    times = [dt.datetime(2025, 6, 21, 5, tzinfo=dt.timezone.utc) + dt.timedelta(minutes=30 * k)
             for k in range(28)]

    def run(measured_at, misfit=0.01):
        raws = [RawSun(k + 1, *measured_at(k, t), confidence=0.9, sunlight=Sunlight.YES,
                       tracked=_Tracked(misfit),
                       clock_sun=finish.ephemeris_sun(native, t, lat, lon))
                for k, t in enumerate(times)]
        track = trackfile.Track(method={"initial": "default", "tracking": "whole_clip",
                                        "smoothing": "two_pass"})
        options = estimate_options.EstimateOptions(latitude_deg=lat, longitude_deg=lon)
        finish.finish(native, track, raws, options, times, None, [[r.frame for r in raws]])
        return track

    def an_hour_late(k, t):
        return finish.ephemeris_sun(native, t + dt.timedelta(hours=1), lat, lon)
    hint = run(an_hour_late).problem("clock")
    assert hint is not None and "1 h after their capture times" in hint.message
    assert "1 h off" in hint.message
    # Such a clock sets no measured Sun aside, even where the model is doubted.
    track = run(an_hour_late, misfit=calibration.MODEL_MISFIT_MAX + 0.1)
    assert "1 h off" in track.problem("clock").message and track.problem("prediction") is None
    assert not any(f.predicted for f in track.frames)
    hint = run(lambda k, t: (20.0 + 3.0 * k, (170.0 + 97.0 * k) % 360.0)).problem("clock")
    assert hint is not None and "h off" not in hint.message and "the place is off" in hint.message
