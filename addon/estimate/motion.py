"""How far the Sun can move between two frames of a run: the bound the sky's
path is solved under (native SunPathOptions), used again by the check and by
smoothing past a segment's span."""

from __future__ import annotations

from typing import List, Optional, Sequence, Tuple

from . import native_loader


def sun_motion_bound_deg(k: int, j: int, times_s: Optional[Sequence[float]],
                         path_options=None) -> float:
    """How far the Sun can move between frames k and j (positions in the
    run's frames; deg): from their capture times in seconds when known, else
    a generous step per frame. path_options: the native SunPathOptions the
    path was solved with (its defaults when None)."""
    o = path_options if path_options is not None else native_loader.require().SunPathOptions()
    if times_s is not None:
        return abs(times_s[k] - times_s[j]) / 3600.0 * o.max_speed_deg_per_hour
    return abs(k - j) * o.max_step_deg


def segment_bounds(starts: Sequence) -> List[int]:
    """A run's segment bounds: 0, each position whose flag in `starts` is
    set (a segment start, or a jump of the path's), and the run's length."""
    n = len(starts)
    return [0] + [k for k in range(1, n) if starts[k]] + [n]


def segment_ranges(starts: Sequence) -> List[Tuple[int, int]]:
    """The run's segments as [lo, hi) position ranges (segment_bounds)."""
    bounds = segment_bounds(starts)
    return list(zip(bounds[:-1], bounds[1:]))
