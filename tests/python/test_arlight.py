import math

import numpy as np
import pytest

from core import arlight


def test_sun_and_sky_reproduce_the_ratio_and_the_lit_brightness():
    ratio, lit, z = (0.30, 0.35, 0.45), (0.20, 0.22, 0.25), 40.0
    sun, sky = arlight.sun_and_sky(ratio, lit, z, ground_albedo=0.4)
    cos_z = math.cos(math.radians(z))
    for c in range(3):
        shadow = math.pi * sky[c]
        lit_irr = sun[c] * cos_z + math.pi * sky[c]
        assert shadow / lit_irr == pytest.approx(ratio[c])
        assert lit_irr * 0.4 / math.pi == pytest.approx(lit[c])


def test_casters_sky_occlusion_is_taken_out():
    ratio = (0.3, 0.3, 0.3)
    k_open = arlight.sun_to_sky(ratio, 30.0)
    k_walled = arlight.sun_to_sky(ratio, 30.0, sky_seen_in_shadow=0.8, sky_seen_lit=0.95)
    # Part of the darkness came from the hidden sky: the Sun is relatively weaker.
    assert all(w < o for w, o in zip(k_walled, k_open))
    back = arlight.ratio_for(k_walled, 30.0, 0.8, 0.95)
    assert back == pytest.approx(ratio)
    # The balance is the same at another Sun height, the ratio is not.
    assert arlight.ratio_for(k_open, 60.0)[0] > ratio[0]


def test_measure_finds_the_shadow_ratio_despite_a_misplaced_edge():
    rng = np.random.default_rng(1)
    h, w = 60, 80
    lit = np.array([0.4, 0.42, 0.45])
    ratio = np.array([0.3, 0.34, 0.42])
    img = np.tile(lit, (h, w, 1)) * rng.uniform(0.9, 1.1, (h, w, 1))
    shadow = np.zeros((h, w), bool)
    shadow[20:40, 20:50] = True
    img[shadow] *= ratio
    ground = np.ones((h, w), bool)
    predicted = np.roll(shadow, 2, axis=1)   # a Sun a little off
    b = arlight.measure_shadow_balance(img, ground, predicted)
    assert b is not None
    assert np.allclose(b.shadow_ratio, ratio, atol=0.02), b.shadow_ratio
    assert arlight.measure_shadow_balance(img, ground, np.zeros((h, w), bool)) is None


def test_sky_seen_counts_blocked_directions():
    dirs = arlight.cosine_directions(256)
    assert np.allclose(np.linalg.norm(dirs, axis=1), 1.0, atol=1e-6) and (dirs[:, 2] > 0).all()
    # A wall blocking every direction toward +x hides half of a uniform sky.
    seen = arlight.sky_seen(np.zeros((3, 3), np.float32), lambda o, d: d[:, 0] > 0, n=256)
    assert seen == pytest.approx(0.5, abs=0.02)
    # Cosine weighting: a cone within 30 deg of the zenith holds sin^2(30) = 1/4 of it.
    seen = arlight.sky_seen(np.zeros((1, 3), np.float32),
                            lambda o, d: d[:, 2] > math.cos(math.radians(30)), n=1024)
    assert seen == pytest.approx(0.75, abs=0.02)
