"""The Sun's circle about the pole, fitted so that a run of wrong Suns does
not bend it (bpy-free, numpy only). Used by the whole-clip path's prior
(estimate/whole_clip.py) and the off-circle confidence check (the same file).

A plain least-squares fit, even with Huber weights (core/suncircle.py), is
pulled several degrees by a third of a segment's Suns lying to one side of
the true path: the sky grid's evidence along a long thin shadow drifts
toward a lower Sun on low-Sun frames, and the shadow tracker, started
there, stays with it. This fit is trimmed: the Suns further from the
circle than INLIER_MEDIANS times the inliers' median distance (never less
than the caller's floor, the Suns' own precision) are left out and the
circle fitted again, until the inliers no longer change. When a fit of all
of them leaves some out, each half of the segment is tried as the start
too (the wrong Suns are usually one stretch: the low-Sun end), and the
start whose circle holds the most Suns within the tightest start's limit
wins; a circle holding fewer than half of them is no candidate. Starting
from the best half of a fit of all did worse: a bent fit's closest half
holds the wrong Suns that happen to lie along its bend.

It holds while the wrong Suns scatter (a zigzag along the ridge); a block
of Suns all shifted alike at one end of an untimed clip looks like another
circle (pole, declination and rate are free) and is not found.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Set

import numpy as np

from . import angles, suncircle

INLIER_MEDIANS = 2.0
ROUNDS = 8
# Iterations of each round's fit (core/suncircle.py's default is 60; the
# trimmed inliers come out the same with 20, at a third of the time; the
# final fit keeps the default). A closed-form fit (the plane through the
# Suns, the angle about its normal linear in time) was faster still but
# chose worse inliers on short arcs (suite scene 23: a 17 deg arc).
ROUND_ITERATIONS = 20
# At most this many Suns, spread over the segment, take part in the rounds
# (the circle has 5 parameters; a long clip's fit would cost seconds).
MAX_FIT_FRAMES = 300
MIN_FRAMES = 8
MIN_INLIER_SHARE = 0.5


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
    s_arr = np.asarray([suns_in_world[i] for i in use], dtype=float)
    s_arr /= np.linalg.norm(s_arr, axis=1, keepdims=True)
    position = {i: j for j, i in enumerate(use)}

    def trim(start):
        """Inliers trimmed from `start` until they no longer change, their
        median distance (None when a fit fails), every Sun's distance."""
        inliers: Set[int] = set(start)
        median: Optional[float] = None
        off: Dict[int, float] = {}
        for _ in range(ROUNDS):
            mask = np.zeros(len(use), dtype=bool)
            mask[[position[i] for i in inliers]] = True
            fit = suncircle.fit_circle(
                t_use, [za[i][0] if i in inliers else None for i in use],
                [za[i][1] if i in inliers else None for i in use],
                [w[i] for i in use], times_are_seconds=times_are_seconds,
                iterations=ROUND_ITERATIONS)
            if not fit.success:
                return inliers, None, off
            fitted = angles.sun_in_world_from_angles(np.asarray(fit.zenith_deg),
                                                     np.asarray(fit.azimuth_world_deg))
            dist = np.degrees(np.arccos(np.clip(np.sum(fitted * s_arr, axis=1), -1.0, 1.0)))
            off = {i: float(dist[j]) for j, i in enumerate(use)}
            median = float(np.median(dist[mask]))
            keep = {i for i in use if off[i] <= max(floor_deg, INLIER_MEDIANS * median)}
            if keep == inliers or len(keep) < MIN_FRAMES:
                break
            inliers = keep
        return inliers, median, off

    # Starts: all the Suns, then each half of the segment alone (the wrong
    # Suns are usually one stretch of it: the low-Sun end). The start whose
    # circle has the most Suns within one limit for all (the tightest
    # start's) wins: a circle bent toward the wrong Suns holds more of them
    # within its own, looser, limit. A circle that holds fewer than half
    # the Suns is one of many (a short arc's subsets each fit a circle of
    # their own): not a candidate.
    def holds_half(c):
        return c[1] is not None and len(c[0]) >= MIN_INLIER_SHARE * len(use)

    tried = [trim(use)]
    # (Skipping them when every Sun is within a few degrees of the first
    # start's circle saved 25 ms a run but kept the bent circles: they hold
    # the wrong Suns within a few degrees, which is how they fail.)
    if len(tried[0][0]) < len(use):
        half = len(use) // 2
        tried += [trim(start) for start in (use[:half], use[half:]) if len(start) >= MIN_FRAMES]
    tried = [c for c in tried if holds_half(c)]
    if not tried:
        out.message = "no circle holds half the Suns"
        return out
    limit = max(floor_deg, INLIER_MEDIANS * min(c[1] for c in tried))
    best = max(tried, key=lambda c: (sum(v <= limit for v in c[2].values()), -c[1]))
    inliers = best[0]
    # The circle at every given time, fitted once more on the inliers.
    fit = suncircle.fit_circle(
        [float(t) for t in times], [za[i][0] if i in inliers else None for i in range(n)],
        [za[i][1] if i in inliers else None for i in range(n)], w,
        times_are_seconds=times_are_seconds)
    if not fit.success:
        out.message = fit.message
        return out
    out.success = True
    out.sun_in_world = list(angles.sun_in_world_from_angles(
        np.asarray(fit.zenith_deg), np.asarray(fit.azimuth_world_deg)))
    out.off_deg = [None if suns_in_world[i] is None else
                   angles.angle_between_deg(out.sun_in_world[i], suns_in_world[i])
                   for i in range(n)]
    out.inliers = sorted(inliers)
    out.residual_deg = float(np.median([out.off_deg[i] for i in inliers]))
    return out
