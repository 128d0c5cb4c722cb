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


def doubted_start(seed=3):
    """A morning of 32 frames whose first ten were doubted (confidence
    0.05-0.41) and drift from 6 deg too low a Sun back to the path (the
    sky's evidence along long low-Sun shadows, suite scene 27), the rest
    confident with 0.3 deg noise. (times s, truth, raw zenith, raw azimuth,
    confidence)"""
    hours = np.linspace(-5.0, -2.6, 32)
    truth = sun_path(hours, latitude=20.0)
    rng = np.random.default_rng(seed)
    raw_z = [z + rng.normal(0, 0.3) for z, _ in truth]
    raw_a = [a + rng.normal(0, 0.3) for _, a in truth]
    conf = [0.85] * 32
    for k in range(10):
        conf[k] = 0.05 + 0.04 * k
        raw_z[k] += 6.0 - 0.5 * k
    return list(hours * 3600.0), truth, raw_z, raw_a, conf


def test_a_doubted_run_follows_the_prior_path_offset_by_the_confident_frames():
    t, truth, raw_z, raw_a, conf = doubted_start()
    # The prior (the segment's Sun circle) is itself 1 deg too low: the fit
    # takes its shape, not its place.
    prior_z = [z + 1.0 for z, _ in truth]
    prior_a = [a for _, a in truth]
    zs, azs = smoothing.two_pass_local_directions(t, raw_z, raw_a, conf,
                                                  prior_zenith=prior_z, prior_azimuth=prior_a)
    errors = [angle(zs[k], azs[k], *truth[k]) for k in range(len(t))]
    assert max(errors) < 0.5, max(errors)
    # Without a prior the window stays put and follows the doubted run.
    zn, an = smoothing.two_pass_local_directions(t, raw_z, raw_a, conf)
    assert max(angle(zn[k], an[k], *truth[k]) for k in range(len(t))) > 3.0
    # A prior with a gap is no prior.
    gap_z = list(prior_z)
    gap_z[5] = None
    assert smoothing.two_pass_local_directions(t, raw_z, raw_a, conf, prior_zenith=gap_z,
                                               prior_azimuth=prior_a) == (zn, an)


def test_without_a_prior_the_window_does_not_widen_at_a_doubted_end():
    """An equinox afternoon to sunset whose last frames are right but
    doubted (Marseille March): a window widened toward the confident frames
    is one-sided there and fits a line through the path's curve (6 deg off
    here, 11 on the clip); without a prior the window keeps its width."""
    hours = np.linspace(-1.0, 5.5, 32)
    truth = sun_path(hours, latitude=43.0, declination=0.0)
    rng = np.random.default_rng(1)
    raw_z = [z + rng.normal(0, 0.2) for z, _ in truth]
    raw_a = [a + rng.normal(0, 0.2) for _, a in truth]
    conf = [0.9] * 28 + [0.1] * 4
    t = list(hours * 3600.0)
    zs, azs = smoothing.two_pass_local_directions(t, raw_z, raw_a, conf)
    assert max(angle(zs[k], azs[k], *truth[k]) for k in range(len(t))) < 0.4
    wide = smoothing.two_pass_local_directions(t, raw_z, raw_a, conf, half_window=t[-1] - t[0])
    assert max(angle(wide[0][k], wide[1][k], *truth[k]) for k in range(len(t))) > 3.0


def test_the_local_fits_at_once_are_each_frames_least_squares():
    """_local_fits solves every frame's weighted local polynomial from its
    moments at once: the same values as a least-squares fit per frame, with
    the degree rule (a line at the ends, a constant on two frames, no more
    terms than distinct times) and repeated times."""
    rng = np.random.default_rng(4)
    t = np.sort(np.concatenate([rng.uniform(0.0, 40.0, 60), [7.0, 7.0, 7.0]]))
    values = np.stack([np.sin(t / 7.0), np.cos(t / 5.0), t / 40.0], axis=1) + \
        rng.normal(0.0, 0.01, (len(t), 3))
    weights = rng.uniform(0.0, 1.0, len(t)) * (rng.random(len(t)) < 0.9)
    order = np.argsort(t, kind="stable")
    windows = np.full(len(t), 4.0)
    lo = np.searchsorted(t, t - windows, side="right")
    hi = np.searchsorted(t, t + windows, side="left")
    got = smoothing._local_fits(t, order, lo, hi, windows, weights, values)
    for i in range(len(t)):
        near = order[lo[i]:hi[i]]
        d = (t[near] - t[i]) / windows[i]
        kern = smoothing._tricube(d) * weights[near]
        sel = kern > 0
        if not sel.any():
            assert np.isnan(got[i]).all()
            continue
        sides = min(int(np.sum(sel & (d < 0))), int(np.sum(sel & (d > 0))))
        m = int(sel.sum())
        degree = min(2 if (m >= 6 and sides >= 3) else (1 if m >= 3 else 0),
                     len(np.unique(d[sel])) - 1)
        x = np.vander(d[sel], degree + 1, increasing=True) * np.sqrt(kern[sel])[:, None]
        want = np.linalg.lstsq(x, values[near][sel] * np.sqrt(kern[sel])[:, None],
                               rcond=None)[0][0]
        assert np.allclose(got[i], want, atol=1e-10), i


def unpinned_morning(seed=5):
    """A morning of 32 frames (urban15's shape): most frames' shadows point
    the Sun's way but do not pin its height, and came back with the Sun 4-10
    deg too low; frames 3, 8, 9 and 11 pin it (0.2 deg noise). (times s,
    truth, raw zenith, raw azimuth, each frame's height spread)"""
    hours = np.linspace(-3.0, -1.0, 32)
    truth = sun_path(hours, latitude=60.0, declination=-12.0)
    rng = np.random.default_rng(seed)
    pinned = {3, 8, 9, 11}
    raw_z = [z + (rng.normal(0, 0.2) if k in pinned else rng.uniform(4.0, 10.0))
             for k, (z, _) in enumerate(truth)]
    raw_a = [a + rng.normal(0, 0.2) for _, a in truth]
    spread = [0.5 if k in pinned else 90.0 for k in range(32)]
    return list(hours * 3600.0), truth, raw_z, raw_a, spread


def test_heights_the_shadows_do_not_pin_follow_the_frames_that_pin_them():
    t, truth, raw_z, raw_a, spread = unpinned_morning()
    zs, azs = smoothing.two_pass_local_directions(t, raw_z, raw_a, [1.0] * len(t),
                                                  height_spread_deg=spread)
    z0, a0 = smoothing.two_pass_local_directions(t, raw_z, raw_a, [1.0] * len(t))
    near = range(1, 12)  # the frames around the pinned ones (3, 8, 9, 11)
    corrected = [abs(zs[k] - truth[k][0]) for k in near]
    alike = [abs(z0[k] - truth[k][0]) for k in near]
    assert np.mean(alike) > 4.0, alike  # the unpinned frames pull every height down
    # Toward the pinned frames, shrunk by their own scatter (2 deg).
    assert np.mean(corrected) < 2.0 and max(corrected) < 3.0, corrected
    # Far from them the unpinned frames' own fit stands, and the azimuths
    # are the direction's fit either way.
    assert abs(zs[31] - z0[31]) < 0.5
    assert max(abs(azs[k] - a0[k]) for k in range(len(t))) < 1e-9
    # Every frame pinned alike, or none: nothing to correct toward.
    for alike in ([0.5] * len(t), [90.0] * len(t), [None] * len(t)):
        assert smoothing.two_pass_local_directions(t, raw_z, raw_a, [1.0] * len(t),
                                                   height_spread_deg=alike) == (z0, a0)
