import numpy as np
import pytest

from core import evaluation, smoothing


def noisy_path(n=120, seed=0, drop=()):
    rng = np.random.default_rng(seed)
    frames = list(range(1, n + 1))
    t = np.linspace(0, 1, n)
    zen = 60 - 20 * t + 4 * t * t              # the Sun climbing, slowly bending
    azi = (350 + 40 * t) % 360                  # crosses north
    zn = list(zen + rng.normal(0, 0.6, n))
    an = list((azi + rng.normal(0, 0.6, n)) % 360)
    for k in drop:
        zn[k] = an[k] = None
    return frames, zen, azi, zn, an


def az_err(a, b):
    return np.abs((np.asarray(a) - np.asarray(b) + 180) % 360 - 180)


def test_two_pass_recovers_a_known_path_from_noisy_samples():
    frames, zen, azi, zn, an = noisy_path(drop=(10, 11, 50))
    z, a = smoothing.smooth_angles(frames, zn, an, [1.0] * len(frames), "two_pass", degree=3)
    # Noise 0.6 deg on 120 samples: a cubic's error is ~0.1 deg on average and
    # ~0.22 deg (1 sigma) at the clip's ends.
    assert np.mean(np.abs(np.array(z) - zen)) < 0.2 and np.mean(az_err(a, azi)) < 0.2
    assert np.max(np.abs(np.array(z) - zen)) < 0.7 and np.max(az_err(a, azi)) < 0.7
    assert all(v is not None for v in z)          # dropped frames are filled


def test_linear_two_pass_is_the_thesis_line():
    frames = list(range(10))
    z = smoothing.two_pass(frames, [2.0 * f + 1 for f in frames], degree=1)
    assert np.allclose(z, [2.0 * f + 1 for f in frames])


def test_two_pass_ignores_outliers_and_zero_confidence():
    frames, zen, azi, zn, an = noisy_path(seed=1)
    zn[30], zn[31] = 10.0, 85.0                   # gross tracking failures
    w = [1.0] * len(frames)
    w[60] = 0.0
    zn[60] = 0.0
    z = smoothing.two_pass(frames, zn, w, degree=3)
    assert np.max(np.abs(np.array(z) - zen)) < 0.5


def test_online_is_causal_and_follows_the_path():
    frames, zen, azi, zn, an = noisy_path(seed=2)
    z = smoothing.online(frames, zn)
    # Causal: changing a later sample does not change earlier outputs.
    zn2 = list(zn)
    zn2[100] = 0.0
    assert smoothing.online(frames, zn2)[:100] == z[:100]
    err = np.abs(np.array(z[20:]) - zen[20:])
    assert err.mean() < 0.5 and err.max() < 1.5


def test_nothing_estimated_gives_none():
    assert smoothing.two_pass([1, 2, 3], [None, None, None]) == [None] * 3
    assert smoothing.online([1, 2, 3], [None, None, None]) == [None] * 3


def test_unknown_mode_is_an_error():
    with pytest.raises(ValueError, match="smoothing mode"):
        smoothing.smooth_angles([1], [1.0], [1.0], [1.0], "spline")


def irregular_path(seed=3):
    """A Sun path sampled at irregular capture times (repeats, gaps, and the
    evening's last capture stored first), like the real sundial clips."""
    rng = np.random.default_rng(seed)
    steps = rng.choice([900.0, 1200.0, 1800.0, 2400.0], size=39)
    t = np.concatenate([[0.0], np.cumsum(steps)])
    t = np.repeat(t, 3)                         # each capture held 3 frames
    t = np.concatenate([[t[-1] + 600.0], t])    # out of order: the last first
    x = t / t.max()
    zen = 75 - 40 * x + 30 * x * x
    azi = 120 + 120 * x
    zn = list(zen + rng.normal(0, 0.4, len(t)))
    an = list(azi + rng.normal(0, 0.4, len(t)))
    return list(range(1, len(t) + 1)), list(t), zen, azi, zn, an


def test_two_pass_over_capture_times_follows_irregular_steps():
    frames, t, zen, azi, zn, an = irregular_path()
    w = [1.0] * len(frames)
    z, a = smoothing.smooth_angles(frames, zn, an, w, "two_pass", degree=3, times_s=t)
    assert np.mean(np.abs(np.array(z) - zen)) < 0.2 and np.max(np.abs(np.array(z) - zen)) < 0.6
    assert np.max(az_err(a, azi)) < 0.6
    # Over frame numbers the same samples fit worse: the first frame (taken
    # last) and the irregular steps bend the curve.
    z_f, _ = smoothing.smooth_angles(frames, zn, an, w, "two_pass", degree=3)
    assert np.max(np.abs(np.array(z_f) - zen)) > 2 * np.max(np.abs(np.array(z) - zen))


def test_online_over_capture_times_is_causal_in_time():
    frames, t, zen, azi, zn, an = irregular_path(seed=4)
    w = [1.0] * len(frames)
    z, _ = smoothing.smooth_angles(frames, zn, an, w, "online", times_s=t)
    # The out-of-order first frame is smoothed where it belongs (at the end
    # of the day), not as the first sample.
    assert abs(z[0] - zen[0]) < 1.5
    # Changing the last capture changes nothing before it in time.
    zn2 = list(zn)
    zn2[0] = 5.0
    z2, _ = smoothing.smooth_angles(frames, zn2, an, w, "online", times_s=t)
    assert z2[1:] == z[1:]
    # Repeated captures (equal times) are fine: no degenerate regression.
    assert all(v is not None and np.isfinite(v) for v in z)
    assert np.mean(np.abs(np.array(z[10:]) - zen[10:])) < 1.0


def test_times_must_match_frames():
    with pytest.raises(ValueError, match="times"):
        smoothing.smooth_angles([1, 2], [1.0, 2.0], [1.0, 2.0], None, "two_pass", times_s=[0.0])


def near_zenith_path(n=120, seed=5, lat=15.0, dec=20.0, noise=0.3):
    """A morning at the tropics: the Sun turns uniformly about the celestial
    pole and climbs to 6 deg from the zenith, where its azimuth swings fast.
    Raw Suns carry 0.3 deg of direction noise."""
    phi, d = np.radians(lat), np.radians(dec)
    pole = np.array([0, np.cos(phi), np.sin(phi)])
    meridian = np.array([0, -np.sin(phi), np.cos(phi)])
    west = np.array([-1.0, 0, 0])
    h = np.radians(np.linspace(-60, -4, n))
    v = np.sin(d) * pole + np.cos(d) * (np.cos(h)[:, None] * meridian + np.sin(h)[:, None] * west)
    rng = np.random.default_rng(seed)
    noisy = v + np.radians(noise) * rng.normal(size=v.shape)
    noisy /= np.linalg.norm(noisy, axis=1, keepdims=True)

    def angles(u):
        return (np.degrees(np.arccos(u[:, 2])), np.degrees(np.arctan2(u[:, 0], u[:, 1])) % 360)
    zen, azi = angles(v)
    zn, an = angles(noisy)
    return list(range(1, n + 1)), zen, azi, list(zn), list(an)


def direction_errors(z, a, zen, azi):
    return np.array([evaluation.angle_between_deg(evaluation.direction(z1, a1),
                                                  evaluation.direction(z2, a2))
                     for z1, a1, z2, a2 in zip(z, a, zen, azi)])


def test_two_pass_in_directions_follows_the_sun_near_the_zenith():
    frames, zen, azi, zn, an = near_zenith_path()
    assert zen.min() < 7
    w = [1.0] * len(frames)
    z, a = smoothing.smooth_angles(frames, zn, an, w, "two_pass", degree=3, space="directions")
    d = direction_errors(z, a, zen, azi)
    assert d.mean() < 0.1 and d.max() < 0.3
    assert np.max(az_err(a, azi)) < 1.0
    # A cubic per angle cannot follow the azimuth's swing by the zenith.
    z_a, a_a = smoothing.smooth_angles(frames, zn, an, w, "two_pass", degree=3)
    assert np.max(az_err(a_a, azi)) > 3 * np.max(az_err(a, azi))


def test_two_pass_in_directions_ignores_outliers_and_fills_gaps():
    frames, zen, azi, zn, an = near_zenith_path(seed=6)
    zn[40], an[40] = 70.0, 200.0                  # a gross tracking failure
    zn[70] = an[70] = None                        # a frame without estimate
    z, a = smoothing.two_pass_directions(frames, zn, an, [1.0] * len(frames))
    assert all(v is not None for v in z + a)
    assert direction_errors(z, a, zen, azi).max() < 0.3


def test_unknown_space_is_an_error():
    with pytest.raises(ValueError, match="smoothing space"):
        smoothing.smooth_angles([1], [1.0], [1.0], [1.0], "two_pass", space="sphere")


def test_online_in_directions_follows_the_sun_near_the_zenith_causally():
    frames, zen, azi, zn, an = near_zenith_path(seed=7)
    w = [1.0] * len(frames)
    zn[5] = an[5] = None                          # a frame without estimate
    z, a = smoothing.smooth_angles(frames, zn, an, w, "online", space="directions")
    assert all(v is not None for v in z + a)
    d = direction_errors(z[20:], a[20:], zen[20:], azi[20:])
    assert d.mean() < 0.3 and d.max() < 0.6
    # Per angle, the azimuth lags through its swing by the zenith.
    _, a_a = smoothing.smooth_angles(frames, zn, an, w, "online")
    assert np.max(az_err(a_a[20:], azi[20:])) > 2 * np.max(az_err(a[20:], azi[20:]))
    # Causal: a later sample changes nothing before it.
    zn2 = list(zn)
    zn2[100] = 40.0
    z2, a2 = smoothing.smooth_angles(frames, zn2, an, w, "online", space="directions")
    assert z2[:100] == z[:100] and a2[:100] == a[:100]
