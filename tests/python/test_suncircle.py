"""The Sun's small circle (core.suncircle) recovers latitude, declination
and north from a day of Suns seen in a scene turned from north, with no
place or date given."""
import math

import numpy as np
import pytest

from core import suncircle


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
    fit = suncircle.fit_circle(list(hours * 3600.0 + 40000.0), zen, az)
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
    fit = suncircle.fit_circle(list(range(1, 31)), zen, az, times_are_seconds=False)
    assert fit.success
    assert abs(fit.latitude_deg - 48.0) < 1.0
    assert abs(fit.rate_deg - 15.0 * 5 / 29) < 0.2  # deg per frame


def test_too_few_or_simultaneous_frames_are_refused():
    assert not suncircle.fit_circle([1, 2, 3], [30, 31, 32], [100, 101, 102]).success
    fit = suncircle.fit_circle([5.0] * 6, [30] * 6, [100] * 6)
    assert not fit.success and "same time" in fit.message


@pytest.mark.parametrize("rate", [None, -math.radians(15.0)])
def test_the_analytic_jacobian_is_the_models_derivative(rate):
    """The fit's Jacobian (analytic, in place of five evaluations of the
    model an iteration) against central differences of the model, poles on
    both sides of the zenith (the basis flips with the sign of sin(pz))
    and at the zenith, where the fit falls back to differences."""
    rng = np.random.default_rng(3)
    t = rng.uniform(-5.0, 5.0, 25)
    root_w = np.sqrt(rng.uniform(0.1, 1.0, 25))
    for pz in (0.3, 1.2, -0.4, -2.0, 2.9):
        params = np.array([pz, rng.uniform(-4, 4), rng.uniform(-0.4, 0.4), rng.uniform(-2, 2)]
                          + ([rng.uniform(-0.3, 0.3)] if rate is None else []))
        jac = suncircle._jacobian(params, t, rate, root_w)

        def model(q):
            return (suncircle._model(q, t, rate) * root_w[:, None]).ravel()
        numeric = np.stack([(model(params + 1e-7 * e) - model(params - 1e-7 * e)) / 2e-7
                            for e in np.eye(len(params))], axis=1)
        assert np.abs(jac - numeric).max() < 1e-6, pz
    assert suncircle._jacobian(np.array([0.0, 1.0, 0.2, 0.1]), t, -0.26, root_w) is None


@pytest.mark.parametrize("seconds", [True, False])
def test_a_settled_fit_ends_early_where_every_iteration_would_end(seconds, monkeypatch):
    # Outliers make the robust weights matter; the fit that skips its
    # settled steps must give the Suns that running all 60 gives.
    hours = np.linspace(-3.0, 2.0, 60)
    zen, az = day(37.0, 12.0, 40.0, hours)
    rng = np.random.default_rng(7)
    zen = [z + rng.normal(0, 0.1) + (6.0 if i % 9 == 0 else 0.0) for i, z in enumerate(zen)]
    az = [a + rng.normal(0, 0.1) for a in az]
    times = list(hours * 3600.0) if seconds else list(range(60))
    steps = []
    solve = suncircle._damped_step

    def counted(*args):
        steps.append(1)
        return solve(*args)

    monkeypatch.setattr(suncircle, "_damped_step", counted)
    early = suncircle.fit_circle(times, zen, az, times_are_seconds=seconds)
    early_steps = len(steps)
    monkeypatch.setattr(suncircle, "SETTLED_STEP_RAD", 0.0)
    steps.clear()
    every = suncircle.fit_circle(times, zen, az, times_are_seconds=seconds)
    assert early.success and every.success
    assert len(steps) == 60 and early_steps < 60
    sun = np.array(suncircle._unit(np.array(early.zenith_deg), np.array(early.azimuth_world_deg)))
    ref = np.array(suncircle._unit(np.array(every.zenith_deg), np.array(every.azimuth_world_deg)))
    off = np.degrees(np.arccos(np.clip(np.sum(sun * ref, axis=1), -1.0, 1.0)))
    assert off.max() < 1e-5
