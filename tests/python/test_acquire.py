"""The shadow search (addon/acquire.py) on frames drawn from a pole on a
textured ground: it finds the Sun that made the shadow, ignores a smooth
glare, and says so when there is no shadow."""
import math

import numpy as np
import pytest

native = pytest.importorskip("_native")
import acquire  # noqa: E402

W, H = 320, 240


def look_at(eye, target):
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross([0.0, 0.0, 1.0], back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, up, back, eye
    return m


def box(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    f = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
         (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return v, f


def sun(zenith, azimuth):
    z, a = math.radians(zenith), math.radians(azimuth)
    return np.array([math.sin(z) * math.sin(a), math.sin(z) * math.cos(a), math.cos(z)])


@pytest.fixture(scope="module")
def world():
    ground = [(-15, -15, 0), (15, -15, 0), (15, 15, 0), (-15, 15, 0)]
    pole_v, pole_f = box((-0.05, -0.05, 0.0), (0.05, 0.05, 1.5))
    verts = np.array(ground + pole_v, dtype=np.float32)
    tris = np.array([(0, 1, 2), (0, 2, 3)] + [tuple(i + 4 for i in t) for t in pole_f],
                    dtype=np.int32)
    ids = np.array([0, 0] + [1] * 12, dtype=np.int32)
    scene = native.Scene(verts, tris, ids)
    camera = native.Camera.from_blender(lens_mm=35, sensor_width_mm=36, sensor_height_mm=24,
                                        width=W, height=H, matrix_world=look_at((1, -7, 5),
                                                                                (0, 1.5, 0)))
    ys, xs = np.mgrid[0:H, 0:W]
    pixels = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)
    hits = scene.intersect_pixels(camera, pixels)
    rng = np.random.default_rng(3)
    texture = (0.5 + 0.4 * rng.random((H, W))).astype(np.float32)  # engraved-like speckle
    return scene, camera, hits, texture


def draw(world, d, glare=False):
    scene, camera, hits, texture = world
    on_ground = hits["object_id"] == 0
    pts = np.nan_to_num(hits["point"]).astype(np.float32)
    origins = (pts + np.array([0, 0, 1e-3], np.float32))
    shadow = scene.occluded(origins, np.repeat(d[None].astype(np.float32), len(pts), axis=0))
    light = np.where(on_ground & shadow, 0.3, 1.0).reshape(H, W)
    img = texture * light
    img[~on_ground.reshape(H, W)] = 0.1  # the pole and the sky
    if glare:
        xs = np.arange(W)[None, :]
        img = img * (1.0 + 0.8 * np.exp(-((xs - 250) / 60.0) ** 2))
    return img.astype(np.float32)


def test_finds_the_sun_from_a_thin_shadow(world):
    truth = sun(55, 140)
    back = acquire.background([draw(world, sun(z, a)) for z, a in
                               ((40, 100), (50, 180), (60, 220), (45, 260), (65, 120))])
    search = acquire.ShadowSearch(world[0], world[1], [0])
    r = search.search(draw(world, truth, glare=True), back)
    assert r["message"] == ""
    err = math.degrees(math.acos(min(1.0, float(np.dot(r["sun_in_world"], truth)))))
    assert err < 1.5, r
    assert r["precision"] > 0.8


def test_says_when_there_is_no_shadow(world):
    back = acquire.background([draw(world, sun(z, 180)) for z in (30, 40, 50, 60)])
    lit = world[3] * 1.0
    search = acquire.ShadowSearch(world[0], world[1], [0])
    r = search.search(lit.astype(np.float32), back)
    assert r["sun_in_world"] is None or r["message"]


def test_background_needs_three_frames(world):
    assert acquire.background([world[3], None, world[3]]) is None
