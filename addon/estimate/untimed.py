"""The clip's structure when its frames carry no times (bpy-free): where
it goes back along the Sun's path (a loop, a cut to earlier footage),
where it turns back over it (played backward from there), and the clock
a segment's Sun circle is fitted on when its pace changes. All from the
Suns measured per frame, in the clip's order; estimate/whole_clip.py
decides what is done with them (segments start at loops and turns; a
segment's circle follows the pace where the frame numbers leave its Suns
far off it).
"""

from __future__ import annotations

import math
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

from . import motion
from ..core import angles

# Without capture times a loop whose Sun goes back less than the path's
# largest step (12 deg a frame) was one segment, smoothed across the loop
# (4.7 deg off on test_whole_clip's four loops): the clip going back along
# the Sun's path starts a segment (going_back). Groups of at least
# LOOP_GROUP frames (at most LOOP_GROUP_MAX) spanning LOOP_MOTION_DEG of the
# path on either side; going back more than LOOP_BACK_DEG and
# LOOP_SCATTER_TIMES their scatter (refined Suns scatter by tenths of a
# degree; a low Sun's by up to 10 along its shadows).
LOOP_GROUP = 4
LOOP_GROUP_MAX = 12
LOOP_MOTION_DEG = 1.0
LOOP_BACK_DEG = 2.0
LOOP_SCATTER_TIMES = 3.0
# A clip played backward from some frame (a boomerang edit) turns the Sun
# back over the path it came along, which the Sun never does; the segment's
# circle, clocked by frame numbers, cannot turn (the speed benchmark's
# ping-pong clip: 4-14 deg off around each turn). Four groups of frames
# around the turn, each spanning REVERSAL_MOTION_DEG of the path (at least
# LOOP_GROUP frames, at most REVERSAL_GROUP_MAX).
REVERSAL_MOTION_DEG = 3.0
REVERSAL_GROUP_MAX = 30
# Without times a segment's circle is clocked by frame numbers, which holds
# while the frames are evenly spaced in time. A time-lapse whose interval
# changes (a day-to-night ramp, a speed-ramped edit) moves the Sun further
# a frame in one part: the circle, fitted to the rest, took the frames of
# that part for shadows that are not the Sun's and dropped their Suns (12
# of 40 frames of test_whole_clip's interval change, the rest 0.1-0.4 deg
# off). Where the thirds of a segment move at paces more than
# PACE_CHANGE_RATIO apart, its clock follows the Sun's own pace: the Sun
# crosses the sky at a constant angular speed, so the way it has come is
# the time (pace_clock). Paces measured over groups of frames spanning
# PACE_MOTION_DEG of the path (at least LOOP_GROUP frames, at most
# REVERSAL_GROUP_MAX). whole_clip decides where it is used.
PACE_CHANGE_RATIO = 1.5
PACE_MOTION_DEG = 3.0


class SunRun:
    """The frames with a Sun, in order, and what the tests of the clip going
    back read from them: the Sun's median step, the middle Sun of a group of
    frames and each frame's scatter. suns: per frame the Sun (None: none)."""

    def __init__(self, suns: Sequence[Optional[np.ndarray]]):
        self.seen = [k for k, s in enumerate(suns) if s is not None]
        self.by_position = by_position = np.asarray(
            [np.asarray(suns[k], float) for k in self.seen]).reshape(-1, 3)
        self.step = float(np.median([angles.angle_between_deg(a, b)
                                     for a, b in zip(by_position, by_position[1:])])) \
            if len(self.seen) > 1 else 0.0
        # Every group's middle, per length and first position in `seen`,
        # computed once: the groups around neighbouring positions overlap
        # (computed again at every position, they took 0.2 s of a
        # 1,000-frame run).
        self.medians: Dict[int, np.ndarray] = {}
        self.middles: Dict[Tuple[int, int], np.ndarray] = {}
        # Low Suns' raw zeniths scatter by up to 10 deg along their long
        # shadows: going back must stand out of the frames' own scatter (each
        # frame off the middle of its neighbours: steady motion is no scatter).
        self.scatter_at = [0.0] + [
            angles.angle_between_deg(b, a + c)
            for a, b, c in zip(by_position, by_position[1:], by_position[2:])]

    def middle(self, first: int, length: int) -> np.ndarray:
        """The Sun in the middle of `length` frames from position `first`
        (per component: strays do not move it)."""
        if (first, length) not in self.middles:
            if length not in self.medians:
                self.medians[length] = np.median(
                    sliding_window_view(self.by_position, length, axis=0), axis=-1)
            m = self.medians[length][first]
            self.middles[first, length] = m / np.linalg.norm(m)
        return self.middles[first, length]

    def crosses_start(self, first: int, last: int, starts: Sequence[int]) -> bool:
        """Whether a segment starts after position `first`, up to `last`."""
        return any(starts[j] for j in range(self.seen[first] + 1, self.seen[last] + 1))


def _group(step: float, motion_deg: float, most: int) -> int:
    """Frames in a group spanning motion_deg of a path moving `step` deg a
    frame (at least LOOP_GROUP, at most `most`)."""
    return int(min(most, max(LOOP_GROUP, math.ceil(motion_deg / max(step, 1e-3)))))


def going_back(suns: Sequence[Optional[np.ndarray]], starts: Sequence[int]) -> List[int]:
    """Positions where the clip goes back along the Sun's path (a loop, a
    cut to earlier footage), or turns back over it (turning_back). Around
    each position, a group of frames before and one from there, each
    spanning about LOOP_MOTION_DEG of the Sun's path: where the Sun moves
    the same way through both, the middle Sun of the group from there lies
    behind the middle Sun of the group before, by more than LOOP_BACK_DEG
    and LOOP_SCATTER_TIMES the frames' scatter, and as near as that to a
    Sun of the path already travelled; of neighbouring positions, the one
    going back furthest. suns: per frame the Sun in sunlight (None: none);
    starts: segments already known. Not confidence: a loop the path could
    not follow leaves its frames doubted."""
    run = SunRun(suns)
    seen, middle, scatter_at = run.seen, run.middle, run.scatter_at
    if len(seen) < 2 * LOOP_GROUP:
        return []
    g = _group(run.step, LOOP_MOTION_DEG, LOOP_GROUP_MAX)

    def motion(first: int) -> np.ndarray:
        """From the middle of a group's first half to its second's (a low
        Sun's scatter along its shadows is no motion)."""
        return middle(first + g // 2, g - g // 2) - middle(first, g // 2)
    first_of, first = [], 0  # per position in `seen`: where its segment starts
    for i, k in enumerate(seen):
        if i > 0 and any(starts[j] for j in range(seen[i - 1] + 1, k + 1)):
            first = i
        first_of.append(first)
    back = {}
    for i in range(g, len(seen) - g + 1):
        if run.crosses_start(i - g, i + g - 1, starts):
            continue
        mb, ma = motion(i - g), motion(i)
        if float(np.dot(mb, ma)) <= 0.5 * float(np.linalg.norm(mb) * np.linalg.norm(ma)):
            continue  # not one steady motion on both sides (or none)
        along = mb + ma
        along /= np.linalg.norm(along)
        there = middle(i, g)
        behind = -math.degrees(float(np.dot(there - middle(i - g, g), along)))
        scatter = max(scatter_at[i - g + 1:i - 1] + scatter_at[i + 1:i + g - 1])
        limit = max(LOOP_BACK_DEG, LOOP_SCATTER_TIMES * scatter)
        # ... back onto the path it travelled (a run of frames misled the
        # same way looks like a jump, but leads nowhere the Sun has been).
        if behind > limit and any(angles.angle_between_deg(s, there) <= limit
                                  for s in run.by_position[first_of[i - g]:i - g]):
            back[i] = behind
    cuts = {seen[i] for i in back if back[i] >= max(back.get(i - 1, 0.0), back.get(i + 1, 0.0))}
    return sorted(cuts | set(turns_in(run, starts)))


def turning_back(suns: Sequence[Optional[np.ndarray]], starts: Sequence[int]) -> List[int]:
    """Frames where the clip turns back over the Sun's path (turns_in).
    suns: per frame the Sun (None: none); starts: segments already known."""
    return turns_in(SunRun(suns), starts)


def turns_in(run: SunRun, starts: Sequence[int]) -> List[int]:
    """Frames where the clip turns back over the Sun's path (played backward
    from there, REVERSAL_*): the Sun moves one way through the two groups of
    frames before and the other way through the two from there, by more
    than LOOP_BACK_DEG and LOOP_SCATTER_TIMES the frames' scatter, and the
    last group comes back to the first. Of neighbouring positions, the one
    whose sides mirror each other best."""
    seen, middle = run.seen, run.middle
    h = _group(run.step, REVERSAL_MOTION_DEG, REVERSAL_GROUP_MAX)
    mirror = {}
    for i in range(2 * h, len(seen) - 2 * h + 1):
        if run.crosses_start(i - 2 * h, i + 2 * h - 1, starts):
            continue
        p1, p2, q1, q2 = (middle(i + k * h, h) for k in (-2, -1, 0, 1))
        before, after = p2 - p1, q2 - q1
        if float(np.dot(before, after)) >= \
                -0.5 * float(np.linalg.norm(before) * np.linalg.norm(after)):
            continue
        scatter = max(run.scatter_at[i - 2 * h + 1:i + 2 * h - 1])
        limit = max(LOOP_BACK_DEG, LOOP_SCATTER_TIMES * scatter)
        moved = min(angles.angle_between_deg(p1, p2), angles.angle_between_deg(q1, q2))
        apart = angles.angle_between_deg(p1, q2) + angles.angle_between_deg(p2, q1)
        if moved > limit and apart <= limit:
            mirror[i] = apart
    return [seen[i] for i in sorted(mirror)
            if mirror[i] <= min(mirror.get(i - 1, math.inf), mirror.get(i + 1, math.inf))]


def pace_clock(suns: Sequence[Optional[np.ndarray]], numbers: Sequence[int],
               starts: Sequence[int]) -> Optional[List[float]]:
    """Per frame the clock its segment's Sun circle is fitted on without
    times: its frame number, or where the segment's pace changes
    (PACE_CHANGE_RATIO), its frame number where the segment starts plus the
    way the Sun has come since, in frames of the segment's median pace.
    None when no segment's pace changes. suns: per frame the Sun (None:
    none); numbers: the frame numbers; starts: the segments."""
    clock = [float(f) for f in numbers]
    changed = False
    for lo, hi in motion.segment_ranges(starts):
        run = SunRun(suns[lo:hi])
        h = _group(run.step, PACE_MOTION_DEG, REVERSAL_GROUP_MAX)
        if len(run.seen) < 6 * h:
            continue
        # The pace across each position: the way between the middle Suns of
        # the groups before and from there, over the frames between their
        # middles (deg a frame).
        at, pace = [], []
        for i in range(h, len(run.seen) - h + 1):
            before = [numbers[lo + k] for k in run.seen[i - h:i]]
            after = [numbers[lo + k] for k in run.seen[i:i + h]]
            frames = float(np.mean(after) - np.mean(before))
            if frames > 0:
                at.append(float(numbers[lo + run.seen[i]]))
                pace.append(angles.angle_between_deg(run.middle(i - h, h), run.middle(i, h))
                            / frames)
        thirds = [float(np.median(part)) for part in np.array_split(np.asarray(pace), 3)
                  if len(part)]
        typical = float(np.median(pace)) if pace else 0.0
        if len(thirds) < 3 or typical <= 0.0 or \
                max(thirds) <= PACE_CHANGE_RATIO * max(min(thirds), 1e-9):
            continue  # steady, or a Sun that stands (the same picture again)
        changed = True
        # Each frame's pace (a running median over a group: a stray Sun
        # does not jump it), then the way come, frame to frame.
        width = min(h, len(pace))
        steady = np.median(sliding_window_view(np.asarray(pace), width), axis=-1)
        centres = np.median(sliding_window_view(np.asarray(at), width), axis=-1)
        per_frame = np.interp(np.asarray(numbers[lo:hi], float), centres, steady)
        for k in range(lo + 1, hi):
            step = 0.5 * (per_frame[k - lo - 1] + per_frame[k - lo]) / typical
            clock[k] = clock[k - 1] + (numbers[k] - numbers[k - 1]) * step
    return clock if changed else None
