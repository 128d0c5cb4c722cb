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


def test_measure_is_not_darkened_by_heavy_grain():
    """A dusk frame's grain (each pixel's level 60% off its neighbours',
    skewed as a dim sensor's is) must not bias the ratio: the lit side's
    dark pixels are not taken for shadow, nor the shadow's bright ones for
    lit ground."""
    rng = np.random.default_rng(7)
    h, w = 90, 160
    lit = np.array([0.30, 0.32, 0.35])
    ratio = np.array([0.25, 0.27, 0.30])
    grain = rng.gamma(shape=1 / 0.6 ** 2, scale=0.6 ** 2, size=(h, w, 1))  # mean 1, sd 0.6
    img = np.tile(lit, (h, w, 1)) * grain
    shadow = np.zeros((h, w), bool)
    shadow[30:60, 40:100] = True
    img[shadow] *= ratio
    # The medians of the grain on each side, as a noise-free measure sees them.
    expected = ratio * np.median(grain[shadow]) / np.median(grain[~shadow])
    b = arlight.measure_shadow_balance(img, np.ones((h, w), bool), shadow)
    assert b is not None
    assert np.allclose(b.shadow_ratio, expected, rtol=0.08), (b.shadow_ratio, expected)


def test_box_mean_averages_each_square_with_the_border_repeated():
    img = np.arange(12, dtype=float).reshape(3, 4)
    out = arlight.box_mean(img, 1)
    assert out.shape == img.shape
    assert out[1, 1] == pytest.approx(img[0:3, 0:3].mean())
    corner = np.pad(img, 1, mode="edge")[0:3, 0:3].mean()
    assert out[0, 0] == pytest.approx(corner)
    assert np.array_equal(arlight.box_mean(img, 0), img)


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


def _sample(frame, ratio, lit=(0.2, 0.2, 0.2), zenith=50.0, sunlight=arlight.Sunlight.YES):
    bal = arlight.ShadowBalance(tuple(ratio), tuple(lit), 100, 100)
    return arlight.LightSample(frame, zenith, sunlight, balance=bal)


def test_light_follows_each_frames_shadows_to_the_clips_ends():
    """Dusk: the shadows fade frame by frame to the last one; every frame's
    light gives its own ratio back (the running median keeps a ramp)."""
    ratios = np.linspace(0.3, 0.8, 9)
    lights = arlight.light_per_frame([_sample(f, (r,) * 3) for f, r in enumerate(ratios, 1)],
                                     1.0, 1.0)
    assert [x.frame for x in lights] == list(range(1, 10))
    for light, r in zip(lights, ratios):
        assert light.target_ratio == pytest.approx((r,) * 3, abs=1e-6)
        sky = math.pi * np.array(light.sky_rgb)
        back = sky / (np.array(light.sun_rgb) * math.cos(math.radians(50.0)) + sky)
        assert back == pytest.approx([r] * 3, abs=1e-6)


def test_a_frame_measured_wrong_takes_its_neighbours_light_and_a_step_stays():
    ratios = [0.3] * 3 + [0.9] + [0.3] * 4 + [0.6] * 5   # an outlier, then a cloud
    lights = arlight.light_per_frame([_sample(f, (r,) * 3) for f, r in enumerate(ratios, 1)],
                                     1.0, 1.0)
    got = [x.target_ratio[0] for x in lights]
    assert got[3] == pytest.approx(0.3, abs=1e-6)
    assert got[:8] == pytest.approx([0.3] * 8, abs=1e-6)
    assert got[8:] == pytest.approx([0.6] * 5, abs=1e-6)


def test_the_frames_thinning_into_a_cloud_keep_their_own_light():
    """Full Sun, one frame each side of the cloud with the Sun half through
    (its shadows fainter), the cloud without sunlight: the median does not
    reach across the cloud, so the thinning frames are not given the full
    Sun's balance of the frames beyond it."""
    ratios = {f: 0.3 for f in list(range(1, 6)) + list(range(11, 16))}
    ratios[5] = ratios[11] = 0.7
    samples = [_sample(f, (r,) * 3) for f, r in ratios.items()]
    samples += [arlight.LightSample(f, 50.0, arlight.Sunlight.NO, ground_linear=(0.1,) * 3)
                for f in range(6, 11)]
    got = {x.frame: x.target_ratio for x in arlight.light_per_frame(samples, 1.0, 1.0)}
    assert got[5] == pytest.approx((0.7,) * 3, abs=1e-6)
    assert got[11] == pytest.approx((0.7,) * 3, abs=1e-6)
    assert all(got[f] is None for f in range(6, 11))
    assert got[3] == pytest.approx((0.3,) * 3, abs=1e-6)
    assert got[13] == pytest.approx((0.3,) * 3, abs=1e-6)


def test_without_sunlight_the_lamp_is_off_and_the_sky_lights_the_ground_as_the_footage():
    dark = arlight.LightSample(5, 95.0, arlight.Sunlight.NO, ground_linear=(0.02, 0.03, 0.05))
    lights = arlight.light_per_frame([_sample(1, (0.3,) * 3), dark], 1.0, 0.9)
    off = lights[-1]
    assert off.frame == 5 and off.sun_rgb == (0.0, 0.0, 0.0) and off.target_ratio is None
    # A horizontal point seeing 90% of the sky gets pi W 0.9; albedo x that / pi = the plate.
    lit = np.array(off.sky_rgb) * 0.9 * arlight.GROUND_ALBEDO
    assert lit == pytest.approx([0.02, 0.03, 0.05])
    # A frame without sunlight that still shows no ground is left to interpolation.
    none = arlight.LightSample(6, 96.0, arlight.Sunlight.NO)
    assert [x.frame for x in arlight.light_per_frame([dark, none], 1.0, 1.0)] == [5]


def test_a_renderer_brighter_under_the_sun_than_lambert_is_corrected_by_its_check():
    """A renderer whose ground answers the Sun 1.4x Lambert's (a grazing
    Sun on a rough diffuse ground): its shadow comes out darker than the
    footage's; the check render's response makes the next light give the
    footage's ratio, and it is interpolated in the Sun's zenith."""
    def rendered(light, zenith, response):
        sky = math.pi * np.array(light.sky_rgb)
        sun = np.array(light.sun_rgb) * math.cos(math.radians(zenith)) * response
        return tuple(sky / (sun + sky))
    sample = _sample(1, (0.4, 0.45, 0.5), zenith=80.0)
    first = arlight.light_per_frame([sample], 1.0, 1.0)[0]
    got = rendered(first, 80.0, 1.4)
    assert got[0] < 0.4 - 0.05       # too dark without the correction
    response = arlight.sun_response(got, first.target_ratio, 80.0)
    assert response == pytest.approx((1.4, 1.4, 1.4), rel=1e-6)
    fixed = arlight.light_per_frame([sample], 1.0, 1.0, [(80.0, response)])[0]
    assert rendered(fixed, 80.0, 1.4) == pytest.approx((0.4, 0.45, 0.5), abs=1e-6)
    corrections = [(80.0, (2.0, 2.0, 1.0)), (40.0, (1.0, 1.0, 1.0))]
    assert arlight.response_at(corrections, 60.0) == pytest.approx((2 ** 0.5, 2 ** 0.5, 1.0))
    assert arlight.response_at(corrections, 85.0) == pytest.approx((2.0, 2.0, 1.0))
    assert arlight.response_at(None, 20.0) == (1.0, 1.0, 1.0)


def _grainy_still(rng, stride, lit_code, shadow_code, grain_codes):
    """A dim still at full size: sRGB codes with the sensor's grain added in
    code values (uniform, as ffmpeg's noise filter adds it), a shadow in the
    middle; and where the masks look, one full-size pixel per reduced one."""
    h, w = 45 * stride, 80 * stride
    shadow = np.zeros((h, w), bool)
    shadow[15 * stride:30 * stride, 20 * stride:60 * stride] = True
    codes = np.where(shadow, shadow_code, lit_code)[..., None] + \
        rng.uniform(-grain_codes, grain_codes, size=(h, w, 3))
    bgr = np.clip(np.rint(codes), 0, 255).astype(np.uint8)
    return bgr, shadow, shadow[::stride, ::stride]


def test_a_large_stills_ratio_is_the_one_a_smaller_frame_shows():
    """Reduced by block means (native linear_block_means), a 20-45 MP still's
    shadow ratio is the one its pixels average to, as a frame of the
    reduced size shows it. Point samples kept each pixel's grain: here their
    medians gave 0.48-0.57 by channel for 0.53."""
    native = pytest.importorskip("_native")
    stride = 8
    bgr, shadow_full, shadow = _grainy_still(np.random.default_rng(11), stride, 42, 28, 20)
    linear_full = arlight.SRGB_TO_LINEAR_TABLE[bgr[..., ::-1]].astype(np.float64)
    expected = linear_full[shadow_full].mean(axis=0) / linear_full[~shadow_full].mean(axis=0)
    ground = np.ones(shadow.shape, bool)
    rgb = native.linear_block_means(bgr, stride, arlight.SRGB_TO_LINEAR_TABLE)[..., ::-1]
    assert rgb.shape == bgr[::stride, ::stride].shape and rgb.dtype == np.float32
    b = arlight.measure_shadow_balance(rgb, ground, shadow)
    assert b is not None
    assert np.allclose(b.shadow_ratio, expected, rtol=0.03), (b.shadow_ratio, expected)


def test_linear_block_means_names_what_it_was_given():
    native = pytest.importorskip("_native")
    with pytest.raises(ValueError, match="image"):
        native.linear_block_means(np.zeros((4, 4, 3), np.float32), 2, arlight.SRGB_TO_LINEAR_TABLE)
    with pytest.raises(ValueError, match="table"):
        native.linear_block_means(np.zeros((4, 4, 3), np.uint8), 2, np.zeros(10, np.float32))
    with pytest.raises(ValueError, match="stride"):
        native.linear_block_means(np.zeros((4, 4, 3), np.uint8), 0, arlight.SRGB_TO_LINEAR_TABLE)
