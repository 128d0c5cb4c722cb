import datetime as dt
import math

import numpy as np
import pytest

from core import clock, sunpath


def low_precision_sun(t, lat, lon):
    """The Astronomical Almanac's low-precision Sun (about 0.01 deg), an
    ephemeris independent of the project's."""
    n = (t - dt.datetime(2000, 1, 1, 12, tzinfo=dt.timezone.utc)).total_seconds() / 86400.0
    L = 280.460 + 0.9856474 * n
    g = math.radians(357.528 + 0.9856003 * n)
    lam = math.radians(L + 1.915 * math.sin(g) + 0.020 * math.sin(2 * g))
    eps = math.radians(23.439 - 4e-7 * n)
    ra = math.atan2(math.cos(eps) * math.sin(lam), math.cos(lam))
    dec = math.asin(math.sin(eps) * math.sin(lam))
    H = math.radians(280.46061837 + 360.98564736629 * n + lon) - ra
    phi = math.radians(lat)
    cz = math.sin(phi) * math.sin(dec) + math.cos(phi) * math.cos(dec) * math.cos(H)
    az = math.atan2(-math.sin(H) * math.cos(dec),
                    math.cos(phi) * math.sin(dec) - math.sin(phi) * math.cos(dec) * math.cos(H))
    return math.degrees(math.acos(cz)), math.degrees(az) % 360.0


def clip(lat=43.3, lon=5.4, north=35.0, true_offset_s=240.0, n=90, noise=0.3, seed=0):
    start = dt.datetime(2025, 6, 21, 9, 0, tzinfo=dt.timezone(dt.timedelta(hours=2)))
    frames = list(range(1, n + 1))
    times = clock.frame_times(start, 120.0, frames)
    rng = np.random.default_rng(seed)
    true = [low_precision_sun(t + dt.timedelta(seconds=true_offset_s), lat, lon) for t in times]
    z = [a + rng.normal(0, noise) for a, _ in true]
    a = [(b + north + rng.normal(0, noise)) % 360 for _, b in true]
    return times, z, a, true


def test_fit_recovers_time_offset_and_north_and_smooths_the_noise():
    times, z, a, true = clip()
    fit = sunpath.fit_sun_path(times, z, a, [1.0] * len(z), low_precision_sun, 43.3, 5.4)
    assert fit.success, fit.message
    assert fit.north_offset_deg == pytest.approx(35.0, abs=0.2)
    assert fit.time_offset_s == pytest.approx(240.0, abs=60)
    err_z = np.abs(np.array(fit.zenith_deg) - [t[0] for t in true])
    err_a = np.abs(((np.array(fit.azimuth_deg) - [t[1] for t in true]) + 180) % 360 - 180)
    assert err_z.max() < 0.15 and err_a.max() < 0.2   # from 0.3 deg noise per frame


def test_fit_finds_a_wrong_latitude_and_ignores_outliers():
    times, z, a, true = clip(lat=-33.9, lon=151.2, north=300.0, true_offset_s=0)
    z[10], a[40] = 5.0, 100.0     # gross tracking failures
    fit = sunpath.fit_sun_path(times, z, a, [1.0] * len(z), low_precision_sun, -30.0, 151.2,
                               latitude_sigma_deg=10.0)
    assert fit.latitude_deg == pytest.approx(-33.9, abs=0.7)
    assert fit.north_offset_deg == pytest.approx(300.0, abs=0.5)
    assert np.max(np.abs(np.array(fit.zenith_deg) - [t[0] for t in true])) < 0.3


def test_too_few_frames_is_a_message_not_a_crash():
    times, z, a, _ = clip(n=5)
    fit = sunpath.fit_sun_path(times, [z[0], None, None, None, None], a, [1, 0, 0, 0, 0],
                               low_precision_sun, 43.3, 5.4)
    assert not fit.success and "fewer than 3" in fit.message


def test_wrong_date_is_flagged():
    times, z, a, _ = clip()
    shifted = [t + dt.timedelta(days=150) for t in times]   # the user typed the wrong month
    fit = sunpath.fit_sun_path(shifted, z, a, [1.0] * len(z), low_precision_sun, 43.3, 5.4,
                               fit_latitude=False)
    assert "do not follow a Sun path" in fit.message
