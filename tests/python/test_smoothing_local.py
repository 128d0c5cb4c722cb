"""Two-pass smoothing of the default method (core.smoothing.
two_pass_local_directions) on a whole day of the Sun: it stays within the
measurements' noise where they are good, rejects outliers, and does better
than one cubic over the day."""
import math

import numpy as np

from core import smoothing


def sun_path(hours, latitude=40.0, declination=20.0):
    """(zenith, azimuth) of the Sun at these hours from solar noon."""
    lat, dec = math.radians(latitude), math.radians(declination)
    out = []
    for h in hours:
        ha = math.radians(15.0 * h)
        # East, north, up components of the direction toward the Sun.
        e = -math.cos(dec) * math.sin(ha)
        nn = math.sin(dec) * math.cos(lat) - math.cos(dec) * math.cos(ha) * math.sin(lat)
        u = math.sin(dec) * math.sin(lat) + math.cos(dec) * math.cos(ha) * math.cos(lat)
        out.append((math.degrees(math.acos(u)), math.degrees(math.atan2(e, nn)) % 360.0))
    return out


def angle(z1, a1, z2, a2):
    v = [np.array([math.sin(math.radians(z)) * math.sin(math.radians(a)),
                   math.sin(math.radians(z)) * math.cos(math.radians(a)),
                   math.cos(math.radians(z))]) for z, a in ((z1, a1), (z2, a2))]
    return math.degrees(math.atan2(np.linalg.norm(np.cross(v[0], v[1])), float(v[0] @ v[1])))


def test_a_whole_day_stays_within_the_noise_and_outliers_are_dropped():
    hours = np.linspace(-4.5, 4.5, 109)  # every 5 minutes, 9 hours
    truth = sun_path(hours)
    rng = np.random.default_rng(1)
    raw_z = [z + rng.normal(0, 0.1) for z, _ in truth]
    raw_a = [a + rng.normal(0, 0.1) for _, a in truth]
    for k in (10, 50, 51, 90):  # wrong frames
        raw_z[k] += 8.0
    raw_a[30] = None
    raw_z[30] = None
    t = list(hours * 3600.0)
    zs, azs = smoothing.two_pass_local_directions(t, raw_z, raw_a, [1.0] * len(t))
    errors = [angle(zs[k], azs[k], *truth[k]) for k in range(len(t))]
    assert max(errors) < 0.15, max(errors)
    assert np.mean(errors) < 0.06
    # One cubic over the day cannot follow it as closely.
    zc, ac = smoothing.two_pass_directions(t, raw_z, raw_a, [1.0] * len(t), degree=3)
    cubic = [angle(zc[k], ac[k], *truth[k]) for k in range(len(t))]
    assert max(cubic) > 2 * max(errors)


def test_degenerate_inputs_give_values_not_errors():
    # All at one time, a single frame, and no measurement at all.
    zs, azs = smoothing.two_pass_local_directions([5.0] * 4, [30, 31, 30, 31],
                                                  [100, 100, 101, 101], None)
    assert all(abs(z - 30.5) < 1 for z in zs)
    assert abs(smoothing.two_pass_local_directions([1], [20.0], [10.0], None)[0][0] - 20.0) < 1e-9
    assert smoothing.two_pass_local_directions([1, 2], [None, None], [None, None], None) == \
        ([None, None], [None, None])
