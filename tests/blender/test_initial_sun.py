"""Initial Sun on a tiny rendered preset: operator and scripted run, both methods."""
import json
import os

import bpy
import pytest

from sunlapse.core.angles import (angle_between_deg, azimuth_world_from_geographic,
                                  sun_in_world_from_geographic)
from test_addon import run_estimate


def truth_dir(truth, frame=1):
    f = truth.frames[frame - 1]
    return sun_in_world_from_geographic(f.zenith_deg, f.azimuth_deg, truth.north_offset_deg)


def test_operator_points_a_new_sun_lamp_at_the_sun(tiny_plaza):
    out, truth = tiny_plaza
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "scene.blend"))
    from conftest import sunlapse
    if not hasattr(bpy.types.Scene, "sunlapse"):
        sunlapse.register()
    scene = bpy.context.scene
    scene.frame_set(1)
    assert bpy.ops.clip.sunlapse_initial_sun() == {"FINISHED"}
    sun = scene.sunlapse.sun_lamp
    assert sun is not None and sun.data.type == "SUN"
    bpy.context.view_layer.update()
    toward = tuple(sun.matrix_world.col[2][:3])
    # A sanity bound at 128x96 pixels; accuracy targets live in the report.
    assert angle_between_deg(toward, truth_dir(truth)) < 5.0


@pytest.mark.parametrize("method", ["default", "thesis"])
def test_scripted_run_estimates_every_frame(tiny_plaza, tmp_path, method):
    out, truth = tiny_plaza
    track_path = str(tmp_path / f"{method}.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), track_path, "--method", method)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(track_path))
    # Ours finds the Sun over the whole clip at once (no initial estimate on
    # one frame); the thesis's baseline starts from frame 1.
    expected = "whole_clip" if method == "default" else method
    assert track["method"]["initial"] == expected and track["method"]["tracking"] == expected
    assert [f["frame"] for f in track["frames"]] == [1, 2, 3]
    # The tiny plaza is sunny on every frame: both methods find an initial
    # Sun and measure every frame (no frame without angles).
    init = track["initial"]
    assert init is not None and init["zenith_deg"] is not None, track.get("initial_tries")
    # A sanity bound for both: the thesis's baseline is coarse at 128x96
    # pixels (measured 21 deg off, ours 0.4), yet finds the Sun's side of the sky.
    assert angle_between_deg(
        sun_in_world_from_geographic(init["zenith_deg"], init["azimuth_deg"],
                                     track["north_offset_deg"]),
        truth_dir(truth)) < 30.0
    for f, t in zip(track["frames"], truth.frames):
        assert f["raw_zenith_deg"] is not None and f["raw_azimuth_deg"] is not None, f
        assert f.get("reason") is None and 0 <= f["zenith_deg"] <= 90, f
        if method == "default":
            # A sanity bound at 128x96 pixels; accuracy targets live in the report.
            est = sun_in_world_from_geographic(f["zenith_deg"], f["azimuth_deg"],
                                               track["north_offset_deg"])
            assert angle_between_deg(est, truth_dir(truth, t.frame)) < 5.0
            assert f["shadow"]["end_px"] and f["confidence"] > 0


def test_a_wrong_given_start_is_never_confidently_wrong(tiny_plaza, tmp_path):
    # --initial-sun measures the tracker alone from a given Sun. Started 40
    # deg off, it cannot follow the shadows: every frame it reports is
    # either right or doubtful, never a confident wrong Sun.
    out, truth = tiny_plaza
    f1 = truth.frames[0]
    wrong_azimuth = azimuth_world_from_geographic(f1.azimuth_deg + 40.0, truth.north_offset_deg)
    track_path = str(tmp_path / "wrong.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), track_path,
                        "--initial-sun", str(f1.zenith_deg), str(wrong_azimuth))
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(track_path))
    assert track["method"]["initial"] == "given"
    for f, t in list(zip(track["frames"], truth.frames))[1:]:
        if f["raw_zenith_deg"] is None:
            assert f["reason"] and f["confidence"] == 0.0, f
            continue
        est = sun_in_world_from_geographic(f["raw_zenith_deg"], f["raw_azimuth_deg"],
                                           track["north_offset_deg"])
        if angle_between_deg(est, truth_dir(truth, t.frame)) > 5.0:
            assert f["confidence"] < 0.8, f
