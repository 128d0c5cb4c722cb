"""The whole-clip path's circle prior (addon/estimate/whole_clip.py): when
the first path zigzags off the Sun's circle on a third of the frames, the
prior is the Sun's circle; a path on its circle gets none; the confidence's
support never counts the prior. No Blender, no native module."""
import os
import sys
import types

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
if "sunlapse" not in sys.modules:
    _package = types.ModuleType("sunlapse")
    _package.__path__ = [os.path.join(ROOT, "addon")]
    sys.modules["sunlapse"] = _package
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
pytest.importorskip("_native")
from sunlapse.core import angles  # noqa: E402
from sunlapse.estimate import sun_circle, whole_clip  # noqa: E402
from test_trimmed_circle import clip  # noqa: E402

# The path's cells (sky.spacing_deg, the fit's inlier floor): a grid finer
# than the default 2.6 deg, as the Suns here scatter 0.3 deg, not a cell's.
SPACING_DEG = 1.5


def path_through(suns, measured=None):
    n = len(suns)
    return whole_clip._Path(jump_before=[False] * n, direction=list(range(n)),
                            measured=[True] * n if measured is None else measured,
                            path_margin=[30.0] * n)


@pytest.mark.parametrize("seed", [3, 102])
def test_a_zigzag_off_the_circle_gets_the_suns_circle_as_prior(seed):
    truth, suns = clip(seed=seed)
    prior = whole_clip._circle_prior(sun_circle.fit_trimmed, path_through(suns),
                                     [tuple(s) for s in suns], None, len(suns), SPACING_DEG)
    assert prior is not None
    for k, s in enumerate(truth):
        assert angles.angle_between_deg(prior[k], s) < 1.5, k


def test_a_path_on_its_circle_gets_no_prior_nor_does_a_short_one():
    _, suns = clip(stuck=())
    directions = [tuple(s) for s in suns]
    assert whole_clip._circle_prior(sun_circle.fit_trimmed, path_through(suns),
                                    directions, None, len(suns), SPACING_DEG) is None
    _, stuck = clip(seed=102)
    few = [k < sun_circle.min_frames() - 1 for k in range(len(stuck))]
    assert whole_clip._circle_prior(sun_circle.fit_trimmed, path_through(stuck, few),
                                    [tuple(s) for s in stuck], None, len(stuck),
                                    SPACING_DEG) is None


def test_support_after_the_prior_never_counts_the_prior():
    up = (0.0, 0.0, 1.0)
    near = tuple(angles.sun_in_world_from_angles(2.0, 0.0))   # within 1.5 cells
    far = tuple(angles.sun_in_world_from_angles(20.0, 0.0))
    directions = [up, near, far]
    first = whole_clip._Path(direction=[0, 0, 0, -1], path_margin=[5.0, 40.0, 40.0, 0.0])
    again = whole_clip._Path(direction=[1, 1, 2, -1], path_margin=[50.0, 20.0, 50.0, 3.0])
    support = whole_clip._evidence_support(first, again, directions, SPACING_DEG)
    cap = whole_clip.FOLLOWED_CONFIDENCE * whole_clip.FULL_CONFIDENCE_MARGIN
    assert support == [5.0, 20.0, cap, 3.0]
    assert np.isclose(cap, 6.0)
