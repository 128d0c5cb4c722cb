import json
import math

import pytest

from core import trackfile as tf


def sample_track():
    return tf.Track(
        clip="footage.mp4", frame_start=5, north_offset_deg=12.5,
        method={"initial": "default", "smoothing": "two_pass", "options": {}},
        initial={"zenith_deg": 40.0, "azimuth_deg": 170.0, "residual": 0.01},
        frames=[
            tf.FrameEstimate(frame=5, zenith_deg=40.0, azimuth_deg=170.0,
                             raw_zenith_deg=40.2, raw_azimuth_deg=169.0, confidence=0.9,
                             shadow_start_px=[10, 20], shadow_end_px=[30, 40],
                             time_utc="2005-03-21T07:06:00+00:00"),
            tf.FrameEstimate(frame=6, reason="frame is black"),
        ],
        extra={"future_key": {"a": 1}})


def test_round_trip_keeps_everything(tmp_path):
    path = tmp_path / "t.sun.json"
    tf.write_track(str(path), sample_track())
    back = tf.read_track(str(path))
    assert back.frame_start == 5 and back.north_offset_deg == 12.5
    assert back.frames[0].raw_azimuth_deg == 169.0
    assert back.frames[0].shadow_end_px == [30, 40]
    assert back.frames[0].time_utc == "2005-03-21T07:06:00+00:00"
    assert back.frames[1].time_utc is None
    assert back.frames[1].zenith_deg is None and back.frames[1].reason == "frame is black"
    assert back.extra == {"future_key": {"a": 1}}
    assert back.initial["azimuth_deg"] == 170.0


def test_written_json_has_the_design_shape(tmp_path):
    path = tmp_path / "t.sun.json"
    tf.write_track(str(path), sample_track())
    d = json.loads(path.read_text())
    assert d["format"] == "sunlapse.track" and d["version"] == 1
    f0, f1 = d["frames"]
    assert set(f0) >= {"frame", "zenith_deg", "azimuth_deg", "raw_zenith_deg",
                       "raw_azimuth_deg", "confidence", "shadow"}
    assert "reason" not in f0
    assert f1["zenith_deg"] is None and f1["reason"] == "frame is black"


def test_non_finite_angles_become_null(tmp_path):
    t = sample_track()
    t.frames[0].zenith_deg = math.nan
    path = tmp_path / "t.json"
    tf.write_track(str(path), t)
    d = json.loads(path.read_text())
    assert d["frames"][0]["zenith_deg"] is None and "reason" in d["frames"][0]


def test_non_finite_numbers_anywhere_become_null(tmp_path):
    t = sample_track()
    t.initial["spread_deg"] = math.nan
    t.extra["nested"] = {"values": [1.0, math.inf]}
    path = tmp_path / "t.json"
    tf.write_track(str(path), t)
    d = json.loads(path.read_text())
    assert d["initial"]["spread_deg"] is None
    assert d["nested"]["values"] == [1.0, None]


def test_truth_files_are_read_by_the_same_reader(tmp_path):
    t = sample_track()
    t.format = tf.FORMAT_TRUTH
    path = tmp_path / "truth.json"
    tf.write_track(str(path), t)
    assert tf.read_track(str(path)).format == tf.FORMAT_TRUTH


@pytest.mark.parametrize("content,message", [
    ("{", "not valid JSON"),
    ('{"format": "other", "version": 1}', "format"),
    ('{"format": "sunlapse.track", "version": 99}', "version"),
    ('{"format": "sunlapse.track", "version": 1, "frames": [{"zenith_deg": 1}]}', "frame entry 0"),
])
def test_bad_files_give_reasons(tmp_path, content, message):
    path = tmp_path / "bad.json"
    path.write_text(content)
    with pytest.raises(tf.TrackFileError, match=message):
        tf.read_track(str(path))


def test_missing_file(tmp_path):
    with pytest.raises(tf.TrackFileError, match="no such file"):
        tf.read_track(str(tmp_path / "nope.json"))


def test_failed_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "t.json"
    tf.write_track(str(path), sample_track())
    before = path.read_text()
    bad = sample_track()
    bad.extra = {"x": object()}  # not serialisable: the write fails
    with pytest.raises(TypeError):
        tf.write_track(str(path), bad)
    assert path.read_text() == before
    assert [p.name for p in tmp_path.iterdir()] == ["t.json"]


def test_north_comes_from_where_the_track_says():
    """North fitted from the Sun's circle is not north given by the scene
    (the panel said "given" for it: only the ephemeris fit counted)."""
    circle = tf.Track(north_offset_deg=0.1, extra={"sun_circle_fit": {"north_offset_deg": 0.1}})
    assert circle.north_source() == tf.NorthSource.SUN_CIRCLE and circle.north_known()
    ephemeris = tf.Track(north_offset_deg=12.0, extra={"sun_path_fit": {"latitude_deg": 43.3}})
    assert ephemeris.north_source() == tf.NorthSource.EPHEMERIS
    assert tf.Track(north_offset_deg=35.0).north_source() == tf.NorthSource.GIVEN
    unknown = tf.Track()
    assert unknown.north_source() == tf.NorthSource.UNKNOWN and not unknown.north_known()


def test_problems_round_trip_and_old_files_read_their_stage_keys(tmp_path):
    t = tf.Track(frames=[tf.FrameEstimate(frame=1)])
    t.report("smoothing", tf.ProblemKind.FELL_BACK, "physical fit failed; used two_pass")
    t.report("model", tf.ProblemKind.HINT, "model the bin")
    path = str(tmp_path / "p.sun.json")
    tf.write_track(path, t)
    d = json.load(open(path))
    assert d["smoothing_message"] == "physical fit failed; used two_pass"  # older readers
    back = tf.read_track(path)
    assert back.problems == t.problems
    assert [p.is_warning for p in back.problems] == [True, False]
    del d["problems"]  # a file written before "problems"
    old = tf.from_json(d)
    assert old.problem("smoothing").kind == tf.ProblemKind.FELL_BACK
    assert old.problem("model").kind == tf.ProblemKind.HINT


def test_sunlight_and_predicted_round_trip_and_are_keyed(tmp_path):
    frames = [tf.FrameEstimate(frame=f, zenith_deg=40.0 + f, azimuth_deg=170.0,
                               raw_zenith_deg=40.0 + f, raw_azimuth_deg=170.0, confidence=0.9,
                               sunlight=tf.Sunlight.YES) for f in (1, 2, 3)]
    frames += [tf.FrameEstimate(frame=4, zenith_deg=91.0, azimuth_deg=250.0, confidence=0.0,
                                sunlight=tf.Sunlight.NO, predicted=True,
                                reason="the Sun is below the horizon here"),
               tf.FrameEstimate(frame=5, zenith_deg=93.0, azimuth_deg=252.0, confidence=0.0),
               tf.FrameEstimate(frame=6, sunlight=tf.Sunlight.UNKNOWN, reason="frame is black")]
    path = tmp_path / "t.sun.json"
    tf.write_track(str(path), tf.Track(frames=frames))
    written = json.loads(path.read_text())["frames"]
    assert written[3]["sunlight"] == "no" and written[3]["predicted"] is True
    assert "sunlight" not in written[4] and "predicted" not in written[4]
    back = tf.read_track(str(path))
    assert [f.sunlight for f in back.frames] == [tf.Sunlight.YES] * 3 + [
        tf.Sunlight.NO, None, tf.Sunlight.UNKNOWN]
    assert [f.predicted for f in back.frames] == [False, False, False, True, False, False]
    # Predicted frames are keyed (lamp off there); a frame that only
    # extrapolates past the measured ones is not.
    assert [f.frame for f in back.keyable()] == [1, 2, 3, 4]
    assert back.extrapolated() == [5]
    assert back.without_sunlight() == [4]


@pytest.mark.parametrize("entry, message", [
    ({"frame": 1, "sunlight": "maybe"}, "sunlight is 'maybe'"),
    ({"frame": 1, "predicted": "yes"}, "predicted is 'yes'")])
def test_bad_sunlight_fields_are_named(tmp_path, entry, message):
    path = tmp_path / "t.sun.json"
    path.write_text(json.dumps({"format": tf.FORMAT_TRACK, "version": 1, "frames": [entry]}))
    with pytest.raises(tf.TrackFileError, match=message):
        tf.read_track(str(path))


def test_frame_ranges_read_as_runs():
    assert tf.frame_ranges([57, 1, 2, 3, 9, 58, 5, 4]) == "1-5, 9, 57-58"
    assert tf.frame_ranges([7]) == "7"
    assert tf.frame_ranges([]) == ""
