"""bench/real.py's scoring of the real clips against the ephemeris."""
import importlib.util
import os

# Loaded by path: putting bench/ on sys.path would let its modules shadow others.
_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "bench", "real.py")
_spec = importlib.util.spec_from_file_location("real_bench", _PATH)
real = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(real)


def fake_sun(year, month, day, hour, minute, second, lat, lon):
    """(zenith, geographic azimuth) growing with the hour."""
    return 30.0 + hour, (100.0 + 10.0 * hour) % 360.0


def test_a_run_that_gives_the_ephemeris_in_the_scenes_north_scores_no_error(tmp_path):
    """A track whose geographic azimuths are the ephemeris's, written with
    the scene's given north (-28 deg at Mulhouse), is scored 0 deg off: the
    truth the runs are scored against stays geographic even though the one
    written beside them carries the scene's north (it was 28 deg off once)."""
    spec = real.CLIP_SPECS["amos-mulhouse"]
    times = tmp_path / "clip.times.csv"
    times.write_text("frame,utc_time\n1,2014-04-01 08:00:00\n2,2014-04-01 10:00:00\n"
                     "3,2014-04-01 12:00:00\n")
    truth, scored, kept = real.clip_truth(str(times), fake_sun, spec)
    assert kept.north_offset_deg == -28.0 and len(scored.frames) == 3
    track = real.trackfile.Track(north_offset_deg=spec["north_offset_deg"])
    track.frames = [real.trackfile.FrameEstimate(
        frame=f.frame, zenith_deg=f.zenith_deg, azimuth_deg=f.azimuth_deg,
        raw_zenith_deg=f.zenith_deg, raw_azimuth_deg=f.azimuth_deg, confidence=0.9)
        for f in truth.frames]
    views = real.scored_views("mulhouse/default", track, spec, scored)
    assert [label for label, _ in views] == ["mulhouse/default raw", "mulhouse/default smoothed",
                                             "mulhouse/default raw, confident"]
    for label, view in views:
        report = real.evaluation.evaluate(label, view, scored)
        assert report.frames_estimated == 3
        assert report.azimuth.mean < 1e-9 and report.direction.mean < 1e-6
    # A north the run got wrong by 10 deg costs 10 deg of azimuth.
    track.north_offset_deg += 10.0
    view = dict(real.scored_views("m", track, spec, scored))["m smoothed"]
    assert abs(real.evaluation.evaluate("m", view, scored).azimuth.mean - 10.0) < 1e-9
