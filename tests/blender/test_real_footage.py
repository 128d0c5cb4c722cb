"""The real March sundial clip end to end, as bench/real.py scores it: the
example .blend opens its clip from ../shared/real, the scripted run finds the
Sun, and the confident frames follow the ephemeris. Skipped when the footage
is not beside the work tree (a clone elsewhere)."""
import os
import sys

import bpy
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
FOOTAGE = os.path.join(os.path.dirname(ROOT), "shared", "real", "marseille-sundial")
BLEND = os.path.join(ROOT, "examples", "real", "marseille-2005-03-21.blend")

pytestmark = pytest.mark.skipif(not os.path.isdir(FOOTAGE),
                                reason=f"no real footage at {FOOTAGE}")


def test_example_blend_points_at_the_footage(empty_scene):
    bpy.ops.wm.open_mainfile(filepath=BLEND)
    clip = bpy.context.scene.active_clip
    assert clip is not None and clip.filepath.startswith("//")  # relative, not copied
    assert os.path.exists(bpy.path.abspath(clip.filepath))
    assert clip.size[0] == 320 and clip.size[1] == 240
    assert bpy.context.scene.sunlapse.ignore_top_rows == 16
    times = bpy.context.scene.sunlapse.times_file  # the frames' stamps, also relative
    assert times.startswith("//") and os.path.exists(bpy.path.abspath(times))


def test_march_clip_follows_the_ephemeris(tmp_path, native):
    sys.path.insert(0, os.path.join(ROOT, "bench"))
    import real
    from sunlapse.core import evaluation, trackfile
    out = str(tmp_path / "mar.sun.json")
    assert real.run_clip(BLEND, out, "default", out + ".log") == 0, \
        open(out + ".log").read()[-2000:]
    track = trackfile.read_track(out)
    truth = real.truth_track(os.path.join(FOOTAGE, "marseille-2005-03-21.times.csv"),
                             native.sun_position)
    raw = real.raw_view(track)
    # Every frame is measured but those without direct sunlight (issue 25):
    # frames 1 (18:08) and 2 (08:06), the Sun low, and 26-27 (14:16-14:17),
    # a cloud: no gnomon shadow on the dial. They say why, carry their
    # segment's path at confidence 0, within a few degrees of the ephemeris.
    unmeasured = [f for f in track.frames if f.raw_zenith_deg is None]
    assert {f.frame for f in unmeasured} <= {1, 2, 26, 27}, \
        [(f.frame, f.reason) for f in unmeasured]
    by_truth = {t.frame: t for t in truth.frames}
    for f in unmeasured:
        assert f.confidence == 0.0 and f.reason and f.predicted, f
        assert f.sunlight == trackfile.Sunlight.NO, f
        t = by_truth[f.frame]
        assert evaluation.angle_between_deg(
            evaluation.direction(f.zenith_deg, f.azimuth_deg),
            evaluation.direction(t.zenith_deg, t.azimuth_deg)) < 4.0, f
    r = evaluation.evaluate("march", raw, truth)
    assert r.frames_estimated >= 36
    # Every raw frame, confident or not. Measured 0.67 mean / 2.29 max
    # azimuth and 2.57 mean zenith (the dial's own +2-3.6 deg bias, see
    # docs/accuracy.md); bounds leave room, not the targets.
    assert r.azimuth.mean < 1.5 and r.azimuth.max < 3.0
    assert r.zenith.mean < 4.0
    # Frame 1 (18:08) is stored first but taken last: tracked in capture
    # order, the run does not start on it.
    assert track.extra["frame_times"]["out_of_order_frames"] == [2]
    assert track.initial["frame"] != 1


def test_march_clip_physical_smoothing_stays_near_the_target(tmp_path, native):
    sys.path.insert(0, os.path.join(ROOT, "bench"))
    import real
    from sunlapse.core import evaluation, trackfile
    out = str(tmp_path / "mar.phys.sun.json")
    assert real.run_clip(BLEND, out, "physical", out + ".log") == 0, \
        open(out + ".log").read()[-2000:]
    track = trackfile.read_track(out)
    assert track.method["smoothing"] == "physical"
    truth = real.truth_track(os.path.join(FOOTAGE, "marseille-2005-03-21.times.csv"),
                             native.sun_position)
    r = evaluation.evaluate("march", real.geographic(track), truth)
    # Measured 2.05-2.09 / 3.23-3.29 zenith, 1.22-1.25 / 2.23-2.28 azimuth
    # (mean / max) with the whole-clip estimator (1.95 zenith mean before
    # it): the target (mean 2) is missed by 0.05-0.09 deg on zenith, the dial
    # model's own +2-4 deg bias around noon (docs/accuracy.md); the bound holds the
    # result near it.
    assert r.frames_estimated == 40
    assert r.zenith.mean < 2.2 and r.azimuth.mean < 2.0
    assert r.zenith.max < 5.0 and r.azimuth.max < 5.0
