"""Degenerate numerical inputs end as a result or a clear error, never as a
LAPACK abort (issue 15). The LAPACK error handler ends the whole process in
Blender, so the riskiest cases run in a child process and the test asserts it
exited normally."""
import datetime as dt
import math
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from core import clock, smoothing, sunpath
from test_sunpath import low_precision_sun

ADDON = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))),
                     "addon")


def in_child(code, timeout=60):
    """Runs Python `code` in a child process beside the add-on's modules: an
    abort or a crash there fails the test instead of ending pytest."""
    return subprocess.run([sys.executable, "-c", code], cwd=ADDON, capture_output=True,
                          text=True, timeout=timeout)


def test_two_pass_with_every_frame_at_one_time_gives_a_constant_not_an_abort():
    # A times file with a date-only column: every frame at the same second.
    code = (
        "from core import smoothing\n"
        "z, a = smoothing.smooth_angles([1, 2, 3, 4, 5], [40, 41, 42, 43, 44],\n"
        "    [100, 101, 102, 103, 104], [1] * 5, 'two_pass', degree=3,\n"
        "    times_s=[0.0] * 5, space='directions')\n"
        "print(z[0] is not None and all(v == v for v in z + a))\n"
        "z = smoothing.two_pass([7] * 5, [40, 41, 42, 43, 44], degree=3)\n"
        "print(max(z) - min(z) < 1e-9 and abs(z[0] - 42) < 1e-9)\n"
        "z, a = smoothing.two_pass_directions([7] * 5, [40] * 5, [10, 11, 12, 13, 14], degree=3)\n"
        "print(all(v == v for v in z + a))\n")
    proc = in_child(code)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["True", "True", "True"], proc.stdout + proc.stderr


def test_equal_times_fall_back_to_frame_order():
    # With no time spread the frame numbers still order the frames: a ramp
    # over frames comes back as that ramp, not as its mean.
    frames = list(range(1, 11))
    zen = [30.0 + f for f in frames]
    z, _ = smoothing.smooth_angles(frames, zen, [90.0] * 10, [1.0] * 10, "two_pass", degree=1,
                                   times_s=[5.0] * 10)
    assert np.allclose(z, zen, atol=1e-6)


def test_nan_times_and_weights_carry_no_weight():
    frames = [1.0, 2.0, float("nan"), 4.0, 5.0]
    z = smoothing.two_pass(frames, [1.0, 2.0, 99.0, 4.0, 5.0],
                           weights=[1, 1, 1, float("inf"), 1], degree=1)
    assert np.allclose([z[0], z[1], z[4]], [1.0, 2.0, 5.0], atol=1e-6)


def angle_lists(n):
    value = st.one_of(st.none(), st.floats(allow_nan=True, allow_infinity=True),
                      st.floats(-720, 720))
    return st.lists(value, min_size=n, max_size=n)


@st.composite
def smoothing_inputs(draw):
    n = draw(st.integers(0, 12))
    frames = draw(st.lists(st.one_of(st.integers(-5, 5), st.floats(-1e7, 1e7), st.just(math.nan)),
                           min_size=n, max_size=n))
    weights = draw(st.lists(st.floats(allow_nan=True, allow_infinity=True),
                            min_size=n, max_size=n))
    return frames, draw(angle_lists(n)), draw(angle_lists(n)), weights


@settings(max_examples=int(os.environ.get("SUNLAPSE_FUZZ_EXAMPLES", 60)), deadline=None,
          derandomize=True, database=None, suppress_health_check=list(HealthCheck))
@given(smoothing_inputs(), st.sampled_from(["online", "two_pass"]),
       st.sampled_from(["angles", "directions"]), st.integers(0, 4))
def test_smoothing_never_raises_on_any_numbers(inputs, mode, space, degree):
    frames, zen, azi, weights = inputs
    z, a = smoothing.smooth_angles(frames, zen, azi, weights, mode, degree=degree, space=space)
    for v in list(z) + list(a):
        assert v is None or math.isfinite(v)


def test_physical_fit_refuses_degenerate_inputs_with_a_reason():
    t0 = dt.datetime(2025, 6, 21, 9, tzinfo=dt.timezone.utc)
    same = [t0] * 5
    z, a = [40.0] * 5, [120.0] * 5
    fit = sunpath.fit_sun_path(same, z, a, [1.0] * 5, low_precision_sun, 43.3, 5.4)
    assert not fit.success and "same time" in fit.message
    times = [t0 + dt.timedelta(minutes=10 * k) for k in range(5)]
    for lat, lon, word in ((200.0, 5.4, "latitude"), (float("nan"), 5.4, "latitude"),
                           (43.3, float("inf"), "longitude")):
        fit = sunpath.fit_sun_path(times, z, a, [1.0] * 5, low_precision_sun, lat, lon)
        assert not fit.success and word in fit.message
    fit = sunpath.fit_sun_path(times, z, a, [float("nan")] * 5, low_precision_sun, 43.3, 5.4)
    assert not fit.success and "fewer than 3" in fit.message


@pytest.mark.parametrize("seconds", [0.0, -5.0, float("nan"), float("inf")])
def test_zero_or_negative_seconds_per_frame_is_refused(seconds):
    with pytest.raises(ValueError, match="positive"):
        clock.frame_times(dt.datetime(2025, 6, 21, tzinfo=dt.timezone.utc), seconds, [1, 2])


def test_the_sun_circle_fits_never_crash_and_never_succeed_with_nan_on_any_numbers():
    """Times, Suns and weights drawn with NaN, infinities, zeros, huge values
    and all-equal times: the native fits (C++ since issue 28) return a result
    (any status) and a successful one has a finite Sun at every finite time.
    In a child process: a crash there must fail the test, not end pytest."""
    code = (
        "import numpy as np, _native as nat\n"
        "rng = np.random.default_rng(5)\n"
        "odd = [np.nan, np.inf, -np.inf, 0.0, 1e300, -1e300, 1e-300]\n"
        "bad = 0\n"
        "for it in range(1500):\n"
        "    n = int(rng.integers(0, 40))\n"
        "    t, s, w = rng.normal(0, 1e4, n), rng.normal(0, 1, (n, 3)), rng.uniform(-0.5, 2, n)\n"
        "    for _ in range(int(rng.integers(0, 4))):\n"
        "        if n:\n"
        "            t[rng.integers(0, n)] = odd[rng.integers(0, 7)]\n"
        "            w[rng.integers(0, n)] = odd[rng.integers(0, 7)]\n"
        "            s[rng.integers(0, n), rng.integers(0, 3)] = odd[rng.integers(0, 7)]\n"
        "    if n and rng.random() < 0.2:\n"
        "        t[:] = t[0]\n"
        "    for r in (nat.fit_sun_circle(list(t), s, list(w), times_are_seconds=bool(it % 2)),\n"
        "              nat.fit_trimmed_sun_circle(list(t), s, 1.0, list(w))):\n"
        "        if r.status == nat.SunCircleStatus.SUCCESS:\n"
        "            bad += not np.isfinite(r.sun_in_world[np.isfinite(t)]).all()\n"
        "print(bad)\n")
    proc = in_child(code, timeout=120)
    if "No module named '_native'" in proc.stderr:
        pytest.skip("the native module is not built")
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split() == ["0"], proc.stdout + proc.stderr
