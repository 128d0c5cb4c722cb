"""The Sun's small circle (estimate/sun_circle.py over the native fit,
sky/sun_circle.h) recovers latitude, declination and north from a day of
Suns seen in a scene turned from north, with no place or date given. The
fit's own steps (its Jacobian, stopping once settled) are tested with it
(native/src/sky/sun_circle_test.cc)."""
import math

import numpy as np
import pytest

pytest.importorskip("_native")
from sunlapse.estimate import sun_circle  # noqa: E402


def day(latitude, declination, north_offset, hours):
    lat, dec = math.radians(latitude), math.radians(declination)
    zen, az = [], []
    for h in hours:
        ha = math.radians(15.0 * h)
        e = -math.cos(dec) * math.sin(ha)
        n = math.sin(dec) * math.cos(lat) - math.cos(dec) * math.cos(ha) * math.sin(lat)
        u = math.sin(dec) * math.sin(lat) + math.cos(dec) * math.cos(ha) * math.cos(lat)
        zen.append(math.degrees(math.acos(u)))
        az.append((math.degrees(math.atan2(e, n)) + north_offset) % 360.0)
    return zen, az


@pytest.mark.parametrize("latitude,declination,north", [(43.3, -2.0, 0.0), (-33.9, 23.0, 35.0),
                                                        (59.9, -8.0, 120.0), (-1.3, 0.5, 300.0)])
def test_recovers_place_date_and_north_from_a_day(latitude, declination, north):
    hours = np.linspace(-3.5, 2.5, 40)
    zen, az = day(latitude, declination, north, hours)
    rng = np.random.default_rng(4)
    zen = [z + rng.normal(0, 0.2) for z in zen]
    az = [a + rng.normal(0, 0.2) for a in az]
    fit = sun_circle.fit_circle(list(hours * 3600.0 + 40000.0), zen, az)
    assert fit.success, fit.message
    assert abs(fit.latitude_deg - latitude) < 1.5
    assert abs(fit.declination_deg - declination) < 1.0
    assert abs((fit.north_offset_deg - north + 180) % 360 - 180) < 2.0
    assert abs(fit.hour_angle_deg[0] - 15.0 * hours[0]) < 2.0
    true_z, true_a = day(latitude, declination, north, hours)
    worst = max(abs(a - b) for a, b in zip(fit.zenith_deg, true_z))
    assert worst < 0.3


def test_without_times_the_rate_is_fitted():
    hours = np.linspace(-2, 3, 30)
    zen, az = day(48.0, 15.0, 10.0, hours)
    fit = sun_circle.fit_circle(list(range(1, 31)), zen, az, times_are_seconds=False)
    assert fit.success
    assert abs(fit.latitude_deg - 48.0) < 1.0
    assert abs(fit.rate_deg - 15.0 * 5 / 29) < 0.2  # deg per frame


def test_too_few_or_simultaneous_frames_are_refused():
    assert not sun_circle.fit_circle([1, 2, 3], [30, 31, 32], [100, 101, 102]).success
    fit = sun_circle.fit_circle([5.0] * 6, [30] * 6, [100] * 6)
    assert not fit.success and "same time" in fit.message


def test_the_rounds_and_the_limit_come_from_cpp():
    # What the estimate's messages quote (finish.py) is the fit's own default.
    import _native
    assert sun_circle.min_frames() == _native.TrimmedCircleOptions().min_frames == 8


def test_bad_arguments_name_themselves():
    import _native
    with pytest.raises(ValueError, match="suns_in_world: expected an \\(N, 3\\) array"):
        _native.fit_sun_circle([1.0, 2.0], np.zeros((2, 2)))
    with pytest.raises(ValueError, match="weights: expected none or one per time"):
        _native.fit_sun_circle([1.0, 2.0], np.ones((2, 3)), [1.0])
    with pytest.raises(ValueError, match="floor_deg must be >= 0"):
        _native.fit_trimmed_sun_circle([1.0, 2.0], np.ones((2, 3)), -1.0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'iteration'"):
        _native.fit_sun_circle([1.0, 2.0], np.ones((2, 3)), iteration=3)
