"""The rendered ground truth: tiny presets rendered by examples/generate_scene.py."""
import copy
import json
import math
import os
import subprocess

import bpy
import numpy as np
import pytest

import random_scene  # examples/, on sys.path through conftest
from conftest import generate_preset
from sunlapse.core import evaluation, trackfile

PRESETS = ["plaza", "southern_winter"]  # north offset 0 and 35 deg, both hemispheres


@pytest.fixture(scope="module", params=PRESETS)
def generated(request, tmp_path_factory):
    return generate_preset(request.param, tmp_path_factory)


def truth_direction(truth, f):
    return np.array(evaluation.direction(f.zenith_deg, f.azimuth_deg + truth.north_offset_deg))


def angle_deg(u, v):
    u, v = np.asarray(u) / np.linalg.norm(u), np.asarray(v) / np.linalg.norm(v)
    return math.degrees(math.acos(min(1.0, max(-1.0, float(u @ v)))))


def test_truth_agrees_with_the_keyframed_lamp(generated):
    out, truth = generated
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "render.blend"))
    scene = bpy.context.scene
    lamp = bpy.data.objects["Sun"]
    assert lamp.data.type == "SUN"
    assert math.degrees(lamp.data.angle) == pytest.approx(0.545, abs=1e-3)
    assert len(truth.frames) == scene.frame_end - scene.frame_start + 1 == 3
    for f in truth.frames:
        scene.frame_set(f.frame)
        toward_sun = np.array(lamp.matrix_world.col[2][:3])  # local +Z
        assert angle_deg(toward_sun, truth_direction(truth, f)) < 0.01, f.frame


def test_sky_sun_follows_the_lamp(generated):
    out, truth = generated
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "render.blend"))
    scene = bpy.context.scene
    sky = scene.world.node_tree.nodes["Sky Texture"]
    for f in truth.frames:
        scene.frame_set(f.frame)
        # Cycles 3.x: sun at geographical_to_direction(elev, rotation + 90 deg).
        e, lon = sky.sun_elevation, sky.sun_rotation + math.pi / 2
        sky_dir = (math.cos(e) * math.cos(lon), math.cos(e) * math.sin(lon), math.sin(e))
        assert angle_deg(sky_dir, truth_direction(truth, f)) < 0.01


def test_user_blend_holds_only_what_a_user_has(generated):
    out, truth = generated
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "scene.blend"))
    scene = bpy.context.scene
    assert scene.camera is not None
    assert not [o for o in bpy.data.objects if o.type == "LIGHT"]
    model = bpy.data.collections["Model"]
    assert "Ground" in model.all_objects
    names = {o.name for o in bpy.data.objects}
    assert not names & set(truth.extra["footage_only_objects"])
    clip = scene.active_clip
    assert clip is not None and clip.filepath.startswith("//")
    assert os.path.exists(bpy.path.abspath(clip.filepath))
    assert tuple(clip.size) == (128, 96) and clip.frame_duration == 3


def test_shadow_masks_mark_some_ground(generated):
    out, truth = generated
    masks = truth.extra["shadow_masks"]
    assert len(masks) >= 2
    for rel in masks.values():
        img = bpy.data.images.load(os.path.join(out, rel))
        px = np.array(img.pixels[:]).reshape(img.size[1], img.size[0], -1)[..., 0]
        frac = float((px > 0.5).mean())
        assert 0.002 < frac < 0.4, (rel, frac)
        bpy.data.images.remove(img)


def test_evaluation_round_trip(generated):
    out, truth = generated
    perfect = copy.deepcopy(truth)
    perfect.format = trackfile.FORMAT_TRACK
    r = evaluation.evaluate("t", perfect, truth)
    assert r.frames_estimated == 3 and r.zenith.max < 1e-9 and r.azimuth.max < 1e-9
    shifted = copy.deepcopy(perfect)
    for f in shifted.frames:
        f.zenith_deg += 2.0
    r = evaluation.evaluate("t", shifted, truth)
    assert r.zenith.mean == pytest.approx(2.0) and r.azimuth.mean == pytest.approx(0, abs=1e-9)
    for f in shifted.frames:
        f.zenith_deg -= 2.0
        f.azimuth_deg += 2.0
    r = evaluation.evaluate("t", shifted, truth)
    assert r.azimuth.mean == pytest.approx(2.0) and r.zenith.mean == pytest.approx(0, abs=1e-9)


# ---------------------------------------------------------------------------
# Random scenes of the suite (examples/random_scene.py, generate_scene --random)

TINY_RANDOM = {"outdoor": "3", "room": "4"}  # seed 4 is a room (every fifth seed)
TINY_FRAMES, TINY_RESOLUTION = 3, (128, 72)


def test_random_specs_are_deterministic_and_keep_their_shadows_in_view(native):
    keys = sorted(random_scene.FIXED) + [str(s) for s in range(1, 11)]
    for key in keys:
        a = random_scene.draw(key, native.sun_position)
        b = random_scene.draw(key, native.sun_position)
        assert json.dumps(a, sort_keys=True) == json.dumps(b, sort_keys=True), key
        if a["kind"] == "room":
            assert all(random_scene.sunlit_floor_in_view(a, native.sun_position)), key
            assert a["ground"]["name"] != "Ground"  # found by the add-on, not by name
        else:
            assert 2 <= len(a["casters"]) <= 5
            assert all(random_scene.casters_in_view(a, native.sun_position)), key
    one, two = (random_scene.draw(k, native.sun_position) for k in ("1", "2"))
    assert one != two
    with pytest.raises(ValueError, match="integer seed"):
        random_scene.draw("plaza", native.sun_position)


def test_shadow_check_rejects_a_caster_out_of_view(native):
    spec = random_scene.draw("1", native.sun_position)
    spec["casters"][0]["location"] = [500.0, 500.0, 0.0]
    assert random_scene.casters_in_view(spec, native.sun_position)[0] is False


def generate_tiny(key, out, mask_frames):
    """(key, folder, truth) of the random scene `key` rendered tiny into
    `out` by examples/generate_scene.py, in a Blender of its own."""
    cmd = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", os.path.join(os.path.dirname(random_scene.__file__), "generate_scene.py"),
           "--", "--random", key, "--out", out, "--tiny", "--mask-frames", str(mask_frames)]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return key, out, trackfile.read_track(os.path.join(out, "truth.sun.json"))


@pytest.fixture(scope="module", params=sorted(TINY_RANDOM))
def random_generated(request, tmp_path_factory):
    key = TINY_RANDOM[request.param]
    return generate_tiny(key, str(tmp_path_factory.mktemp(f"random{key}")), mask_frames=2)


def test_random_scene_renders_its_spec(random_generated, native):
    key, out, truth = random_generated
    spec = random_scene.draw(key, native.sun_position, frames=TINY_FRAMES,
                             resolution=TINY_RESOLUTION)
    spec["render"]["samples"] = 4  # --tiny
    with open(os.path.join(out, "spec.json")) as fh:
        assert json.load(fh) == json.loads(json.dumps(spec))
    suns = random_scene.suns_of(spec, native.sun_position)
    assert [(f.zenith_deg, f.azimuth_deg) for f in truth.frames] == pytest.approx(
        [tuple(s) for s in suns])


def test_random_user_blend_has_the_rest_camera_and_no_clutter(random_generated):
    key, out, truth = random_generated
    spec = truth.extra["random_scene"]
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "scene.blend"))
    scene = bpy.context.scene
    assert not [o for o in bpy.data.objects if o.type == "LIGHT"]
    names = {o.name for o in bpy.data.objects}
    assert truth.extra["footage_only_objects"] and not names & set(
        truth.extra["footage_only_objects"])
    assert spec["ground"]["name"] in bpy.data.collections["Model"].all_objects
    cam = scene.camera
    assert cam.animation_data is None
    look = np.array(cam.matrix_world.col[2][:3]) * -1.0  # cameras look along local -Z
    want = np.array(spec["camera"]["target"]) - np.array(spec["camera"]["location"])
    assert angle_deg(look, want) < 0.01
    assert tuple(scene.active_clip.size) == TINY_RESOLUTION


def test_random_scene_shadows_are_in_view(random_generated, native):
    """On the truth masks (255 = ground in the Sun's cast shadow), every
    caster's shadow is in view outdoors (a shadow pixel near where the shadow's
    middle projects), and in a room the sunlit patch through the window is on
    the floor in view (no shadow where its centre projects, shadow around)."""
    key, out, truth = random_generated
    spec = truth.extra["random_scene"]
    cam = random_scene.camera_of(spec)
    for frame, rel in truth.extra["shadow_masks"].items():
        img = bpy.data.images.load(os.path.join(out, rel))
        w, h = img.size
        # Blender's pixels run bottom-up; flip to OpenCV rows.
        mask = np.array(img.pixels[:]).reshape(h, w, -1)[::-1, :, 0] > 0.5
        bpy.data.images.remove(img)
        z, a = truth.frame(int(frame)).zenith_deg, truth.frame(int(frame)).azimuth_deg
        sun = random_scene.sun_in_world(z, a + truth.north_offset_deg)

        def near(point, radius=2):
            x, y = (int(round(v)) for v in cam.project(point))
            return mask[max(0, y - radius):y + radius + 1, max(0, x - radius):x + radius + 1]
        if spec["kind"] == "room":
            patch = random_scene.window_patch_center(spec, sun)
            assert not near(patch, 0).any(), (frame, "no sunlit patch where the window projects")
            assert mask.mean() > 0.05
        else:
            for item in spec["casters"]:
                mid = random_scene.shadow_points(item, sun)[1]
                assert near(mid).any(), (frame, item["name"])


# ---------------------------------------------------------------------------
# The kinds real footage brings (issue 25 item 7): a rough model beside the
# true one, and the footage-only trees and the overcast sky kept out of the
# user's scene.

@pytest.fixture(scope="module")
def rough_generated(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("rough1"))
    cmd = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python", os.path.join(os.path.dirname(random_scene.__file__), "generate_scene.py"),
           "--", "--random", "rough1", "--out", out, "--tiny", "--mask-frames", "1"]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return out, trackfile.read_track(os.path.join(out, "truth.sun.json"))


def _model_and_camera(path):
    bpy.ops.wm.open_mainfile(filepath=path)
    cam = bpy.context.scene.camera
    model = {o.name: (np.array(o.matrix_world.translation), np.array(o.dimensions),
                      math.degrees(o.rotation_euler.z))
             for o in bpy.data.collections["Model"].objects}
    return model, cam.matrix_world.to_quaternion(), cam.data.lens


def test_rough_member_carries_the_hand_made_model_beside_the_true_one(rough_generated):
    out, truth = rough_generated
    spec = truth.extra["random_scene"]
    true_model, true_cam, true_lens = _model_and_camera(os.path.join(out, "scene_true.blend"))
    rough_model, rough_cam, rough_lens = _model_and_camera(os.path.join(out, "scene.blend"))
    assert set(true_model) == set(rough_model)
    for item in spec["casters"]:
        want = random_scene.rough_item(item, spec["rough_model"])
        loc, dims, turn = rough_model[item["name"]]
        assert loc[:2] == pytest.approx(want["location"][:2], abs=1e-3)
        assert loc[:2] != pytest.approx(true_model[item["name"]][0][:2], abs=0.04)
        assert dims[2] == pytest.approx(want["size"][2], rel=1e-3)
    assert math.degrees(true_cam.rotation_difference(rough_cam).angle) == pytest.approx(
        random_scene.ROUGH_CAMERA_DEG, abs=0.01)
    assert rough_lens / true_lens == pytest.approx(spec["rough_model"]["camera"]["lens_factor"])


@pytest.fixture(scope="module", params=["trees1", "overcast1"])
def kind_generated(request, tmp_path_factory):
    return generate_tiny(request.param, str(tmp_path_factory.mktemp(request.param)),
                         mask_frames=1)


def test_trees_and_overcast_sky_stay_out_of_the_users_scene(kind_generated):
    key, out, truth = kind_generated
    spec = truth.extra["random_scene"]
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "render.blend"))
    if spec.get("trees"):
        crowns = [o.name for o in bpy.data.collections["FootageOnly"].objects
                  if "_crown" in o.name]
        assert len(crowns) == 2 * len(spec["trees"])
        assert set(crowns) <= set(truth.extra["footage_only_objects"])
    if spec.get("overcast"):
        nodes = bpy.context.scene.world.node_tree.nodes
        assert "Overcast" in nodes and nodes["Overcast"].inputs["Strength"].default_value > 0
        curves = bpy.context.scene.world.node_tree.animation_data.action.fcurves
        assert any("Fac" in fc.data_path or "inputs[0]" in fc.data_path for fc in curves)
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "scene.blend"))
    names = {o.name for o in bpy.data.objects}
    assert not names & set(truth.extra["footage_only_objects"])
    assert bpy.context.scene.world is None
