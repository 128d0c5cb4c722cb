"""The trimmed fit of the Sun's circle (estimate/sun_circle.py over
sky/sun_circle.h): a third of the Suns stuck to one side of the path must not
bend the circle, which then says how far each of them is off. No Blender."""
import math
import os
import sys
import types

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The add-on's package without its bpy registration (addon/__init__.py): its
# bpy-free modules import each other relatively.
if "sunlapse" not in sys.modules:
    _package = types.ModuleType("sunlapse")
    _package.__path__ = [os.path.join(ROOT, "addon")]
    sys.modules["sunlapse"] = _package
pytest.importorskip("_native")
from sunlapse.core import angles  # noqa: E402
from sunlapse.estimate import sun_circle as circle  # noqa: E402


def sun_at(hour_angle_deg, latitude_deg=40.0, declination_deg=15.0):
    """Toward the Sun (x east, y north, z up) at an hour angle (deg, negative
    in the morning)."""
    h, d, p = (math.radians(v) for v in (hour_angle_deg, declination_deg, latitude_deg))
    return np.array([-math.cos(d) * math.sin(h),
                     math.sin(d) * math.cos(p) - math.cos(d) * math.cos(h) * math.sin(p),
                     math.sin(d) * math.sin(p) + math.cos(d) * math.cos(h) * math.cos(p)])


def clip(n=40, stuck=range(0, 13), seed=3):
    """Suns 2 deg of hour angle apart, with a little noise; the `stuck` ones
    3-14 deg lower than the Sun, scattered (a low-Sun run zigzagging along a
    shadow's ridge, as the sky grid's cells do on suite scene 16)."""
    rng = np.random.default_rng(seed)
    truth = [sun_at(-70.0 + 2.0 * k) for k in range(n)]
    measured = []
    for k, s in enumerate(truth):
        z, a = angles.angles_from_sun_in_world(s)
        z += rng.normal(0.0, 0.3) + (rng.uniform(3.0, 14.0) if k in stuck else 0.0)
        measured.append(angles.sun_in_world_from_angles(z, a + rng.normal(0.0, 0.3)))
    return truth, measured


def test_a_third_of_the_suns_to_one_side_bends_a_plain_fit():
    # The case the trimmed fit exists for: the plain (Huber) fit is pulled
    # well over a degree off the Sun by the stuck third.
    truth, measured = clip()
    zen, azi = zip(*(angles.angles_from_sun_in_world(s) for s in measured))
    fit = circle.fit_circle(list(range(len(truth))), list(zen), list(azi),
                            times_are_seconds=False)
    assert fit.success
    worst = max(angles.angle_between_deg(angles.sun_in_world_from_angles(z, a), s)
                for z, a, s in zip(fit.zenith_deg, fit.azimuth_world_deg, truth))
    assert worst > 1.5


@pytest.mark.parametrize("seed", [3, 102, 110])
def test_the_trimmed_fit_stays_on_the_sun_and_says_which_are_off(seed):
    # Seeds 102 and 110 bend a fit of all the Suns toward the stuck ones
    # even after trimming: only the start from the clean half finds it.
    truth, measured = clip(seed=seed)
    fit = circle.fit_trimmed(list(range(len(truth))), measured, 1.5,
                             times_are_seconds=False)
    assert fit.success, fit.message
    for k, s in enumerate(truth):
        # The stuck third is extrapolated from the others: 1.5 deg there.
        assert angles.angle_between_deg(fit.sun_in_world[k], s) < 1.5, k
    stuck = set(range(0, 13))
    assert stuck.isdisjoint(fit.inliers)
    assert set(fit.inliers) == set(range(len(truth))) - stuck
    assert all(fit.off_deg[k] > 2.0 for k in stuck)
    assert all(fit.off_deg[k] < 1.5 for k in range(13, len(truth)))


def test_clean_suns_all_take_part_and_missing_ones_are_predicted():
    truth, measured = clip(stuck=())
    measured[5] = measured[20] = None
    fit = circle.fit_trimmed(list(range(len(truth))), measured, 1.5,
                             times_are_seconds=False)
    assert fit.success, fit.message
    assert len(fit.inliers) == len(truth) - 2
    assert fit.off_deg[5] is None and fit.off_deg[20] is None
    assert angles.angle_between_deg(fit.sun_in_world[5], truth[5]) < 0.5
    assert angles.angle_between_deg(fit.sun_in_world[20], truth[20]) < 0.5


def test_too_few_suns_is_a_result_not_an_error():
    truth, measured = clip(n=6, stuck=())
    fit = circle.fit_trimmed(list(range(6)), measured, 1.5, times_are_seconds=False)
    assert not fit.success
    assert "at least" in fit.message
