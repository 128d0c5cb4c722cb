"""addon/core/angles.py: the Sun's angles <-> its direction in the world
frame (+X east, +Y north, +Z up), world <-> geographic azimuth."""
import math

import numpy as np
import pytest

from core.angles import (angle_between_deg, angles_from_sun_in_world, cross,
                         azimuth_geographic_from_world, azimuth_world_from_geographic,
                         sun_in_world_from_angles, sun_in_world_from_geographic,
                         wrap_azimuth_deg, wrap_signed_deg)


@pytest.mark.parametrize("zenith, azimuth, expected", [
    (0, 123, (0, 0, 1)),     # overhead, whatever the azimuth
    (90, 0, (0, 1, 0)),      # north on the horizon: +Y
    (90, 90, (1, 0, 0)),     # east: +X
    (90, 180, (0, -1, 0)),   # south
    (90, 270, (-1, 0, 0)),   # west
])
def test_sun_in_world_points_along_the_world_axes(zenith, azimuth, expected):
    assert np.allclose(sun_in_world_from_angles(zenith, azimuth), expected, atol=1e-12)


def test_sun_in_world_toward_the_north_east_is_a_unit_vector():
    d = sun_in_world_from_angles(60, 45)
    assert d.shape == (3,)
    assert math.isclose(np.linalg.norm(d), 1.0)
    assert math.isclose(d[2], 0.5)
    assert d[0] > 0 and math.isclose(d[0], d[1])


def test_angles_invert_the_vector_at_any_length_for_scalars_and_arrays():
    zen, azi = np.meshgrid(np.arange(0.5, 180, 7.3), np.arange(0, 360, 11.1))
    v = 3.7 * sun_in_world_from_angles(zen, azi)
    assert v.shape == zen.shape + (3,)
    z, a = angles_from_sun_in_world(v)
    assert np.allclose(z, zen, atol=1e-9) and np.allclose(a, azi, atol=1e-9)
    z1, a1 = angles_from_sun_in_world(list(v[3, 4]))
    assert isinstance(z1, float) and isinstance(a1, float)
    assert math.isclose(z1, zen[3, 4]) and math.isclose(a1, azi[3, 4])


def test_one_vector_reads_as_the_same_vector_in_an_array():
    # One vector takes a plain-float path; it must agree with the arrays'.
    rng = np.random.default_rng(3)
    vectors = list(rng.normal(size=(500, 3)) * rng.uniform(1e-3, 1e3, size=(500, 1)))
    vectors += [np.array(v, dtype=float) for v in
                ([0, 0, 1], [0, 0, -1], [-1e-17, 1, 0], [0, 1e-300, 0], [1, 0, 0])]
    for v in vectors:
        z1, a1 = angles_from_sun_in_world(v)
        z, a = angles_from_sun_in_world(v[None, :])
        assert abs(z1 - z[0]) < 1e-12
        assert abs(float(wrap_signed_deg(a1 - a[0]))) < 1e-12
        assert 0.0 <= a1 < 360.0
    assert angles_from_sun_in_world([0.0, 0.0, 0.0]) == (90.0, 0.0)


def test_azimuth_stays_in_zero_to_360():
    _, a = angles_from_sun_in_world([-1e-9, 1.0, 0.0])  # just west of north
    assert 0.0 <= a < 360.0 and math.isclose(a, 360.0, abs_tol=1e-6)
    _, a = angles_from_sun_in_world([-1.0, 1e-9, 0.0])  # just north of west
    assert math.isclose(a, 270.0, abs_tol=1e-6)
    assert angles_from_sun_in_world([0, 0, 2]) == (0.0, 0.0)
    assert wrap_azimuth_deg(360.0) == 0.0 and wrap_azimuth_deg(-1e-15) == 0.0
    assert math.isclose(wrap_azimuth_deg(-90.0), 270.0)
    assert np.allclose(wrap_azimuth_deg(np.array([725.0, -90.0])), [5.0, 270.0])


def test_world_azimuth_turns_by_the_north_offset():
    # A scene turned 90 deg: true north lies along world +X.
    assert math.isclose(azimuth_world_from_geographic(0.0, 90.0), 90.0)
    assert math.isclose(azimuth_world_from_geographic(300.0, 90.0), 30.0)
    assert math.isclose(azimuth_world_from_geographic(10.0, -30.0), 340.0)
    assert math.isclose(azimuth_geographic_from_world(30.0, 90.0), 300.0)
    geo = np.arange(0, 360, 13.7)
    for offset in np.arange(-400, 400, 37.1):
        world = azimuth_world_from_geographic(geo, offset)
        assert np.all((world >= 0) & (world < 360))
        assert np.allclose(azimuth_geographic_from_world(world, offset), geo, atol=1e-9)
    # The vector of a geographic Sun in a turned scene: north offset 90 puts
    # a Sun due north (geographic 0) along +X.
    assert np.allclose(sun_in_world_from_angles(90, azimuth_world_from_geographic(0, 90)),
                       (1, 0, 0), atol=1e-12)
    assert np.allclose(sun_in_world_from_geographic(90, 0, 90), (1, 0, 0), atol=1e-12)
    assert np.allclose(sun_in_world_from_geographic(30, 200, -20),
                       sun_in_world_from_angles(30, 180), atol=1e-12)


def test_angle_between_is_exact_for_tiny_and_large_angles():
    a = sun_in_world_from_angles(40, 100)
    assert math.isclose(angle_between_deg(a, sun_in_world_from_angles(40.001, 100)),
                        0.001, rel_tol=1e-6)
    assert math.isclose(angle_between_deg(2 * a, -a), 180.0)
    assert math.isclose(angle_between_deg((0, 1, 0), (1, 0, 0)), 90.0)
    f32 = a.astype(np.float32)
    assert angle_between_deg(f32, f32) < 1e-6


def test_cross_is_numpys_to_the_bit():
    # The Sun circle's fits keep their results only if the fast cross gives
    # exactly numpy's values (each product rounded, then the difference).
    rng = np.random.default_rng(7)
    for u, v in zip(rng.normal(size=(500, 3)) * 10.0 ** rng.integers(-8, 8, (500, 1)),
                    rng.normal(size=(500, 3))):
        assert np.array_equal(cross(u, v), np.cross(u, v))
    assert np.array_equal(cross([1, 0, 0], (0, 1, 0)), [0.0, 0.0, 1.0])
