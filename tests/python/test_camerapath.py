"""A moving camera's solve checked for jumps (addon/core/camerapath.py)."""
import math

import numpy as np

from sunlapse.core import camerapath


def pan(deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def move(n, jitter=0.0, seed=0):
    """An eased 2 m slide and 30 deg pan over n frames, with a solve's
    jitter (m; a tenth of it in degrees... as rotation noise)."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 1, n)
    s = t * t * (3 - 2 * t)
    loc = np.stack([2.0 * s, 0.3 * s, np.full(n, 5.0)], axis=1) + rng.normal(0, jitter, (n, 3))
    rot = np.array([pan(30 * si + rng.normal(0, 10 * jitter)) for si in s])
    return list(range(1, n + 1)), loc, rot


def test_a_smooth_move_with_a_solves_jitter_has_no_jump():
    for n in (9, 10, 12, 40):
        assert camerapath.solve_jumps(*move(n, jitter=0.003)) == {}
    # A steady fast slide (a metre a frame) stays on its path at the ends.
    frames = list(range(10))
    loc = np.stack([np.arange(10.0), np.zeros(10), np.zeros(10)], axis=1)
    assert camerapath.solve_jumps(frames, loc, np.repeat(np.eye(3)[None], 10, axis=0)) == {}


def test_jumps_of_a_few_frames_are_found_and_only_they():
    frames, loc, rot = move(40, jitter=0.002)
    loc[10] += [0.2, 0.0, 0.0]            # one frame 20 cm off
    rot[25:28] = [pan(1.0) @ r for r in rot[25:28]]  # three frames a degree off
    found = camerapath.solve_jumps(frames, loc, rot)
    assert sorted(found) == [11, 26, 27, 28]
    assert "(0.2" in found[11] and " m " in found[11] and "deg" in found[26]


def test_a_fast_short_move_with_one_jump():
    """Ten frames of a 1.7 m eased slide (27 cm a frame at its fastest): a
    40 cm jump on one frame is found, nothing else."""
    frames, loc, rot = move(10, jitter=0.002)
    loc *= [0.85, 1, 1]
    loc[5] += [0.4, 0.0, 0.0]
    assert sorted(camerapath.solve_jumps(frames, loc, rot)) == [6]


def test_a_solve_that_breaks_once_loses_only_the_frames_at_the_break():
    frames, loc, rot = move(40, jitter=0.002)
    loc[20:] += [0.0, 0.3, 0.0]
    found = camerapath.solve_jumps(frames, loc, rot)
    assert found and all(17 <= f <= 24 for f in found), sorted(found)


def test_too_few_frames_are_not_judged():
    frames, loc, rot = move(8)
    loc[3] += 1.0
    assert camerapath.solve_jumps(frames, loc, rot) == {}


def test_rotation_vector_of_a_pan():
    assert np.allclose(camerapath.rotation_vector_deg(pan(12.0)), [0, 0, 12.0])
    assert np.allclose(camerapath.rotation_vector_deg(np.eye(3)), 0.0)
