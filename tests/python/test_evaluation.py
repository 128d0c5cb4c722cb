import copy

import pytest

from core import evaluation as ev
from core import trackfile as tf


def truth(north=30.0):
    return tf.Track(format=tf.FORMAT_TRUTH, north_offset_deg=north, frames=[
        tf.FrameEstimate(frame=i + 1, zenith_deg=40.0 + i, azimuth_deg=350.0 + 2 * i)
        for i in range(10)])


def as_track(t, dz=0.0, da=0.0, north=None):
    out = copy.deepcopy(t)
    out.format = tf.FORMAT_TRACK
    if north is not None:  # same Sun, expressed with another north offset
        for f in out.frames:
            f.azimuth_deg = (f.azimuth_deg + t.north_offset_deg - north) % 360
        out.north_offset_deg = north
    for f in out.frames:
        f.zenith_deg += dz
        f.azimuth_deg = (f.azimuth_deg + da) % 360
    first = out.frames[0]
    out.initial = {"zenith_deg": first.zenith_deg, "azimuth_deg": first.azimuth_deg}
    return out


def test_perfect_track_scores_zero():
    r = ev.evaluate("s", as_track(truth()), truth())
    assert r.frames_estimated == 10
    assert r.zenith.max == pytest.approx(0, abs=1e-9)
    assert r.azimuth.max == pytest.approx(0, abs=1e-9)
    assert r.direction.max == pytest.approx(0, abs=1e-5)
    assert r.initial_error_deg == pytest.approx(0, abs=1e-5)


def test_offsets_of_two_degrees_score_two():
    r = ev.evaluate("s", as_track(truth(), dz=2.0), truth())
    assert r.zenith.min == pytest.approx(2) and r.zenith.mean == pytest.approx(2)
    assert r.azimuth.max == pytest.approx(0, abs=1e-9)
    assert r.direction.mean == pytest.approx(2, abs=1e-6)
    r = ev.evaluate("s", as_track(truth(), da=-2.0), truth())  # across 0/360
    assert r.azimuth.mean == pytest.approx(2) and r.zenith.mean == pytest.approx(0)


def test_unknown_north_track_is_compared_in_world_frame():
    r = ev.evaluate("s", as_track(truth(north=30.0), north=0.0), truth(north=30.0))
    assert r.azimuth.max == pytest.approx(0, abs=1e-9)


def test_missing_frames_and_missing_track_are_reported_not_scored():
    t = as_track(truth())
    t.frames[3].zenith_deg = None
    del t.frames[5]
    r = ev.evaluate("s", t, truth())
    assert r.frames_estimated == 8 and r.frames_total == 10
    r = ev.evaluate("s", None, truth(), message="no track was produced")
    assert r.zenith is None and "no track" in r.message
    table = ev.format_table([r])
    assert "no track was produced" in table and "Zenith Mean Error" in table


def test_empty_track_reports_its_message():
    t = tf.Track(frames=[], extra={"message": "no estimator exists yet"})
    r = ev.evaluate("s", t, truth())
    assert r.frames_estimated == 0 and r.message == "no estimator exists yet"
    assert "-" in ev.format_table([r])


def test_plot_is_written(tmp_path):
    r = ev.evaluate("s", as_track(truth(), dz=1.0), truth())
    out = ev.plot(r, str(tmp_path / "s.png"))
    assert out and (tmp_path / "s.png").stat().st_size > 1000


def test_initial_sun_is_scored_on_its_own_frame():
    t = truth()
    tr = as_track(t)
    f4 = tr.frames[3]
    tr.initial = {"frame": 4, "zenith_deg": f4.zenith_deg, "azimuth_deg": f4.azimuth_deg}
    assert ev.evaluate("s", tr, t).initial_error_deg == pytest.approx(0, abs=1e-5)
    tr.initial.pop("frame")  # without a frame: frame 1's Sun, 3 deg of zenith away
    assert ev.evaluate("s", tr, t).initial_error_deg > 2.5


def test_angle_between_is_exact_for_tiny_angles_and_any_length():
    # float32 round-off leaves a lamp's axis ~1e-8 off unit length: acos of
    # the dot read 0.014 deg between such a vector and itself.
    d = (0.837967038154602, -0.025124138221144676, 0.5451421737670898)
    assert ev.angle_between_deg(d, d) < 1e-9
    u = ev.direction(40.0, 10.0)
    v = ev.direction(40.001, 10.0)
    assert ev.angle_between_deg(u, v) == pytest.approx(0.001, rel=1e-6)
    assert ev.angle_between_deg([2 * x for x in u], v) == pytest.approx(0.001, rel=1e-6)
    assert ev.angle_between_deg((1, 0, 0), (-1, 0, 0)) == pytest.approx(180.0)
    assert ev.angle_between_deg((1, 0, 0), (0, 3, 0)) == pytest.approx(90.0)


def test_reliability_bins_confidence_against_the_share_within():
    frames = [(0.5, 0.95)] * 9 + [(6.0, 0.95)] + [(0.5, 0.15)] * 2 + [(3.0, 0.15)] * 8 \
        + [(0.1, 1.0)]
    rows, ece = ev.reliability(frames, within_deg=2.0)
    assert [(r.lo, r.frames) for r in rows] == [(0.1, 10), (0.9, 11)]
    low, high = rows
    assert low.share_within == pytest.approx(0.2) and low.mean_confidence == pytest.approx(0.15)
    assert high.share_within == pytest.approx(10 / 11)
    gap = 10 * 0.05 + 11 * abs(10 / 11 - (0.95 * 10 + 1.0) / 11)
    assert ece == pytest.approx(gap / 21)
    assert ev.reliability([]) == ([], None)
