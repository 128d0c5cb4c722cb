"""The rendered ground truth: tiny presets rendered by examples/generate_scene.py."""
import copy
import math
import os

import bpy
import numpy as np
import pytest

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
