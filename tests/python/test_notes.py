"""The clip background and frame spreading (addon/estimate/notes.py) used by the
unmodelled-shadow note."""
import numpy as np

from sunlapse.estimate import notes


def test_spread_takes_the_ends_and_never_more_than_asked():
    frames = list(range(10, 110))
    picks = notes.spread(frames, 5)
    assert picks[0] == 10 and picks[-1] == 109 and len(picks) == 5
    assert notes.spread([3, 4], 24) == [3, 4]


def test_clip_background_is_the_median_so_a_moving_shadow_vanishes():
    base = np.full((8, 12, 3), 200, np.uint8)
    frames = []
    for k in range(5):
        f = base.copy()
        f[:, 2 * k:2 * k + 2] = 40  # a shadow that moves along the rows
        frames.append(f)
    back = notes.clip_background(frames, rows_per_chunk=3)
    assert np.array_equal(back, base)
    assert notes.clip_background(frames[:2]) is None
    assert notes.clip_background([frames[0], None, frames[1]]) is None
