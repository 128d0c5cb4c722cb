"""The native option structs bound as classes (defaults from C++) and the
keyword arguments of the functions that take them forwarded into the struct,
so both spellings reach the same options."""
import math

import numpy as np
import pytest

native = pytest.importorskip("_native")

NOON = (2005, 3, 21, 11, 0, 0.0, 43.3, 5.4)


def test_options_classes_carry_the_cpp_defaults_and_keyword_fields():
    o = native.InitialSunOptions()
    assert o.method == "default" and o.max_pixels == 12000 and o.per_object_albedo is True
    o = native.InitialSunOptions(method="thesis", max_pixels=5000)
    assert (o.method, o.max_pixels, o.num_candidates) == ("thesis", 5000, 300)
    o.loss_scale = 0.5
    assert "loss_scale=0.5" in repr(o) and "method='thesis'" in repr(o)
    t = native.ShadowTrackerOptions(ground_object_ids=[3, 4])
    assert t.ground_object_ids == [3, 4] and t.band_radius_px == 4


def test_bad_fields_are_named_errors():
    with pytest.raises(TypeError, match="'bogus'; valid: method, max_pixels"):
        native.InitialSunOptions(bogus=1)
    with pytest.raises(TypeError, match="max_pixels: expected int"):
        native.InitialSunOptions(max_pixels="many")
    with pytest.raises(ValueError, match="method: expected 'thesis' or 'default'"):
        native.InitialSunOptions(method="best")
    with pytest.raises(ValueError, match="max_pixels"):
        native.InitialSunOptions(max_pixels=-1).check()
    with pytest.raises(TypeError, match="'bogus'"):
        native.sun_position(*NOON, bogus=1)


def test_keywords_and_the_options_struct_reach_the_same_options():
    refracted = native.sun_position(*NOON)
    no_refraction = native.sun_position(*NOON, pressure_hpa=0.0)
    # Refraction lifts the Sun: turning it off must move the zenith.
    assert no_refraction[0] > refracted[0] + 1e-3
    via_struct = native.sun_position(*NOON, options=native.SunPositionOptions(pressure_hpa=0.0))
    assert via_struct == no_refraction
    # Keywords apply on top of a given struct.
    both = native.sun_position(*NOON, options=native.SunPositionOptions(pressure_hpa=0.0),
                               pressure_hpa=1013.25)
    assert both == refracted


def test_camera_from_params_or_keywords_is_the_same_camera():
    kw = dict(lens_mm=35.0, sensor_width_mm=36.0, sensor_height_mm=24.0, width=64, height=48,
              shift_x=0.1, matrix_world=np.eye(4))
    a = native.Camera.from_blender(**kw)
    b = native.Camera.from_blender(params=native.BlenderCameraParams(**kw))
    assert np.allclose(a.K, b.K)
    assert not math.isclose(a.K[0, 2], 31.5)  # shift_x reached the camera
    assert native.BlenderCameraParams(sensor_fit="VERTICAL").sensor_fit == "VERTICAL"
    kw.pop("height")
    with pytest.raises(TypeError, match="missing required argument 'height'"):
        native.Camera.from_blender(**kw)
    with pytest.raises(ValueError, match="sensor_fit"):
        native.BlenderCameraParams(sensor_fit="DIAGONAL")


def flat_ground_under_a_camera():
    """A 10 m square of ground and a 64x48 camera 10 m above it, looking down."""
    v = np.array([[-5, -5, 0], [5, -5, 0], [5, 5, 0], [-5, 5, 0]], dtype=np.float32)
    scene = native.Scene(v, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.int32),
                         np.zeros(2, dtype=np.int32))
    m = np.eye(4)
    m[2, 3] = 10.0
    cam = native.Camera.from_blender(lens_mm=35, sensor_width_mm=36, sensor_height_mm=24,
                                     width=64, height=48, matrix_world=m)
    return scene, cam


def test_trackers_take_the_ground_ids_positionally_or_in_the_options():
    scene, cam = flat_ground_under_a_camera()
    native.ShadowTracker(scene, cam, [0], ignore_top_rows=2)
    native.ShadowTracker(scene, cam, options=native.ShadowTrackerOptions(ground_object_ids=[0]))
    native.ThesisTracker(scene, cam, [0], ignore_top_rows=2)
    with pytest.raises(ValueError, match="ground_object_ids"):
        native.ShadowTracker(scene, cam)
    with pytest.raises(ValueError, match="band_radius_px"):
        native.ShadowTracker(scene, cam, [0], band_radius_px=0)


def test_stage_results_are_classes_with_a_status_enum_not_dicts():
    """Callers decide by a result's status, never by its message's text."""
    few = native.solve_camera(np.zeros((3, 3)), np.zeros((3, 2)), 320, 240)
    assert not isinstance(few, dict)
    assert few.status == native.CameraSolveStatus.TOO_FEW_POINTS
    assert "at least 6" in few.message
    scene, cam = flat_ground_under_a_camera()
    gray = np.full((48, 64), 0.5, dtype=np.float32)
    stopped = native.estimate_initial_sun(scene, cam, gray, progress=lambda f: False)
    assert stopped.status == native.InitialSunStatus.CANCELLED
    assert native.estimate_initial_sun(scene, cam, gray).status != \
        native.InitialSunStatus.CANCELLED
    assert {"SUCCESS", "NO_EVIDENCE"} <= set(native.SunPathStatus.__members__)


def test_the_sky_stages_options_are_options_classes_too():
    # Every field of SkyEvidenceOptions (sky_evidence.h) is bound,
    # min_significance included, and both take keywords and name bad ones.
    sky = native.SkyEvidenceOptions(min_significance=2.5, num_directions=1200)
    assert (sky.min_significance, sky.num_directions, sky.band_steps) == (2.5, 1200, 2)
    assert "min_significance=2.5" in repr(sky)
    path = native.SunPathOptions(jump_cost=-1.0)
    assert path.jump_cost == -1.0 and path.max_step_deg == 12.0
    with pytest.raises(TypeError, match="'bogus'; valid: evidence_weight, step_weight"):
        native.SunPathOptions(bogus=1)
    with pytest.raises(TypeError, match="num_directions: expected int"):
        native.SkyEvidenceOptions(num_directions="many")
    with pytest.raises(ValueError, match="min_significance"):
        native.SkyEvidenceOptions(min_significance=-1.0).check()
