"""The Sun's circle about the pole, fitted so that a run of wrong Suns does
not bend it (bpy-free, numpy only).

A plain least-squares fit, even with Huber weights (core/suncircle.py), is
pulled several degrees by a third of a segment's Suns lying to one side of
the true path: the sky grid's evidence along a long thin shadow drifts
toward a lower Sun on every low-Sun frame (estimate/whole_clip.py), and the
shadow tracker, started there, stays with it. This fit is trimmed: the
Suns further from the circle than INLIER_MEDIANS times the inliers' median
distance (never less than the caller's floor, the Suns' own precision) are
left out and the circle fitted again, until the inliers no longer change.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional, Sequence

import numpy as np

from ..core import angles, suncircle

INLIER_MEDIANS = 2.0
ROUNDS = 8
# At most this many Suns, spread over the segment, take part in the rounds
# (the circle has 5 parameters; a long clip's fit would cost seconds).
MAX_FIT_FRAMES = 300
MIN_FRAMES = 8


@dataclass
class TrimmedFit:
    success: bool = False
    message: str = ""
    # Per given time: the circle's Sun (world frame), and how far the given
    # Sun is from it (deg; None where no Sun was given).
    sun_in_world: List[np.ndarray] = field(default_factory=list)
    off_deg: List[Optional[float]] = field(default_factory=list)
    inliers: List[int] = field(default_factory=list)   # indices into the inputs
    residual_deg: Optional[float] = None    # median distance of the inliers


def _spread(items: Sequence[int], k: int) -> List[int]:
    n = len(items)
    if n <= k:
        return list(items)
    return [items[i] for i in sorted({round(j * (n - 1) / (k - 1)) for j in range(k)})]


def fit_trimmed(times: Sequence[float], suns_in_world: Sequence[Optional[Sequence[float]]],
                floor_deg: float, weights: Optional[Sequence[float]] = None,
                times_are_seconds: bool = True) -> TrimmedFit:
    """The circle through the given Suns (unit vectors, world frame; None:
    no Sun at that time), the far ones left out as the module says.
    `floor_deg`: the inlier limit never falls below this (deg)."""
    out = TrimmedFit()
    n = len(times)
    given = [i for i in range(n) if suns_in_world[i] is not None]
    if len(given) < MIN_FRAMES:
        out.message = f"needs at least {MIN_FRAMES} Suns (has {len(given)})"
        return out
    za = {i: angles.angles_from_sun_in_world(suns_in_world[i]) for i in given}
    w = [1.0] * n if weights is None else list(weights)
    use = _spread(given, MAX_FIT_FRAMES)
    t_use = [float(times[i]) for i in use]
    inliers = set(use)
    for _ in range(ROUNDS):
        fit = suncircle.fit_circle(
            t_use, [za[i][0] if i in inliers else None for i in use],
            [za[i][1] if i in inliers else None for i in use],
            [w[i] for i in use], times_are_seconds=times_are_seconds)
        if not fit.success:
            out.message = fit.message
            return out
        off = {i: angles.angle_between_deg(
            angles.sun_in_world_from_angles(fit.zenith_deg[j], fit.azimuth_world_deg[j]),
            suns_in_world[i]) for j, i in enumerate(use)}
        limit = max(floor_deg, INLIER_MEDIANS * float(np.median([off[i] for i in inliers])))
        keep = {i for i in use if off[i] <= limit}
        if keep == inliers or len(keep) < MIN_FRAMES:
            break
        inliers = keep
    # The circle at every given time, fitted once more on the inliers.
    fit = suncircle.fit_circle(
        [float(t) for t in times], [za[i][0] if i in inliers else None for i in range(n)],
        [za[i][1] if i in inliers else None for i in range(n)], w,
        times_are_seconds=times_are_seconds)
    if not fit.success:
        out.message = fit.message
        return out
    out.success = True
    out.sun_in_world = [angles.sun_in_world_from_angles(z, a)
                        for z, a in zip(fit.zenith_deg, fit.azimuth_world_deg)]
    out.off_deg = [None if suns_in_world[i] is None else
                   angles.angle_between_deg(out.sun_in_world[i], suns_in_world[i])
                   for i in range(n)]
    out.inliers = sorted(inliers)
    out.residual_deg = float(np.median([out.off_deg[i] for i in inliers]))
    return out
