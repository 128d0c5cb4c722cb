"""Native projection against bpy_extras.object_utils.world_to_camera_view."""
import numpy as np
import pytest
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

import scenes
from sunlapse.blender import gather

CASES = [
    # fit, sensor w/h, shift, resolution, percentage, pixel aspect
    ("AUTO", 36.0, 24.0, (0.0, 0.0), (1920, 1080), 100, (1, 1)),
    ("AUTO", 36.0, 24.0, (0.12, -0.07), (720, 1280), 50, (1, 1)),
    ("HORIZONTAL", 23.5, 15.6, (-0.05, 0.1), (640, 480), 100, (1, 1)),
    ("VERTICAL", 36.0, 20.25, (0.03, 0.2), (1000, 700), 100, (1, 1)),
    ("AUTO", 24.0, 24.0, (0.0, 0.15), (853, 480), 100, (1.0, 1.25)),
    ("VERTICAL", 10.0, 7.5, (0.2, 0.0), (400, 600), 100, (2.0, 1.0)),
]


@pytest.mark.parametrize("fit,sw,sh,shift,res,pct,aspect", CASES)
def test_native_projection_equals_world_to_camera_view(
        empty_scene, native, fit, sw, sh, shift, res, pct, aspect):
    scene = empty_scene
    scene.render.resolution_x, scene.render.resolution_y = res
    scene.render.resolution_percentage = pct
    scene.render.pixel_aspect_x, scene.render.pixel_aspect_y = aspect
    cam_obj = scenes.add_camera(scene, (6.0, -9.0, 4.5), (0.5, 0.3, 0.2), lens=28.0,
                                sensor_fit=fit, sensor_width=sw, sensor_height=sh,
                                shift=shift)
    info = gather.gather_camera(__import__("bpy").context)
    cam = gather.build_camera(info)
    w, h = info.params["width"], info.params["height"]

    rng = np.random.default_rng(42)
    # Random points in view: random pixels pushed to random depths.
    pixels = np.column_stack([rng.uniform(0, w - 1, 300), rng.uniform(0, h - 1, 300)])
    rays = cam.pixel_rays(pixels)
    points = cam.center_in_world + rays * rng.uniform(2, 40, (300, 1))
    native_px, in_front = cam.project(np.ascontiguousarray(points))
    assert in_front.all()
    assert np.abs(native_px - pixels).max() < 1e-6

    blender_px = []
    for p in points:
        ndc = world_to_camera_view(scene, cam_obj, Vector(p))
        blender_px.append((ndc.x * w - 0.5, (1.0 - ndc.y) * h - 0.5))
    err = np.abs(native_px - np.array(blender_px)).max()
    assert err < 0.01, f"max pixel difference {err}"
