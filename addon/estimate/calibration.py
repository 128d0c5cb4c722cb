"""Confidence as a probability: the whole-clip estimate's support for a
frame's Sun (whole_clip's margins, circle agreement and tracker contrast)
mapped to the chance that the Sun is within 2 deg of the truth.

The map was fitted on the randomised suite by bench/calibrate.py (pool
adjacent violators over every frame of every scene, docs/accuracy.md §
"Confidence as a probability"); measured to hold for the default method
with two-pass and physical smoothing (finish.py applies it there only).
Refit it when the support changes: `python3 bench/calibrate.py --suite
FIGURES.json` prints the table below from a suite run made with
--uncalibrated-confidence."""

from __future__ import annotations

import bisect
from typing import Iterable, Optional, Sequence, Set, Tuple

# (support, probability within 2 deg) knots, support ascending; a frame
# between two knots is interpolated linearly, beyond the ends held.
SUPPORT_TO_PROBABILITY: Tuple[Tuple[float, float], ...] = (
    (0.2526, 0.9427),
    (0.5801, 0.9831),
    (0.8395, 0.9846),
    (0.9755, 0.9884),
)

# Frames the estimate doubted itself (support below DOUBTED_SUPPORT: off
# their segment's circle, followed by the tracker alone, carried by the path)
# stay below 0.5 whatever their share within 2 deg: a frame at 0.5 or more
# must never be more than 5 deg off (issue 25). Below it the confidence is a
# bound, not a probability. The bound stood at support 0.5 until the clip
# and segment rules below held the frames it had caught (walls1, rough2,
# rough7); in the clips the map applies to, frames of support 0.2-0.5 were
# then within 2 deg 96% of the time (192 of 201) and none more than 5 deg
# off, and held at 0.49 they made most of the calibration error (0.074 ->
# 0.016 fitted, 0.085 -> 0.045 on scenes held out). Below 0.2 there were few
# (29 of 31 within 2 deg), and on 16 fresh members one of rough7's (0.165)
# was 5.04 deg off: that frame set the bound at 0.2.
DOUBTED_SUPPORT = 0.2
DOUBTED_MAX_PROBABILITY = 0.49

# A clip whose Sun was measured on fewer than this share of the frames that
# could show it (all but those without direct sunlight) is not one the
# estimate explains: its support is reported as it is, below 0.5. On the
# suite only walls1 and rough2 (0.79, 0.80; every other member 0.94 or
# more) fall below it, and they held every frame more than 5 deg off at 0.5
# or more; the AMOS webcams, 20-70 deg off, 0.18 and 0.36.
MEASURED_SHARE_MIN = 0.85


# A segment with fewer sunlit frames than this split off the rest of the
# clip (a cut or a jump of the path) has too little of the Sun's path to
# confirm it: its frames stay below 0.5. On 84 suite scenes the only such
# segment was rough7's frames 1-3, 50 deg off at 0.90; on fresh members,
# walls9's frames 1-9, whose 7 dark frames had left 2 sunlit ones 59 deg
# off at 0.93-0.94 (dark frames show nothing of the path).
SHORT_SEGMENT_FRAMES = 4


def unchecked_frames(frames: Iterable[Tuple[int, Optional[bool]]]) -> Set[int]:
    """The frames, of (frame, circle_checked) pairs of the frames with a Sun,
    whose Sun no circle of the Sun's path checked: their segment had too
    few Suns whose shadows pin their height for one (sun_circle.py's
    min_frames()), as in a clip of a few frames. Nothing weighs their support: on
    the suite's scenes cut to 1-12 frames (bench/short_clips.py) frames
    were up to 148 deg off at 0.98-0.99, where the whole clips have none
    more than 5 deg off at 0.5 or more; they stay below 0.5, as short
    segments do (None: a method without the check)."""
    return {f for f, checked in frames if checked is False}


def short_segment_frames(segments: Sequence[Sequence[int]],
                         sunlit: Optional[Set[int]] = None) -> Set[int]:
    """The frames of the short segments of a clip cut into several: those
    with fewer than SHORT_SEGMENT_FRAMES frames in `sunlit` (None: every
    frame counts)."""
    if len(segments) < 2:
        return set()

    def counted(segment: Sequence[int]) -> int:
        return len(segment) if sunlit is None else sum(f in sunlit for f in segment)
    return {f for segment in segments if counted(segment) < SHORT_SEGMENT_FRAMES
            for f in segment}


# A clip whose model's shadows miss the footage's on most frames: the
# median over its tracked frames of ShadowTracker's misfit (the share of the
# shadows' band the fitted Sun leaves a whole lit/shaded step off) at or
# above this. A hand-made model's misplaced casters bias every frame's Sun
# alike (2-9 deg on the suite's rough members), which no other figure of
# the clip shows. Set between the development members (docs/accuracy.md §
# "The surface offset's bias"): rough ones 0.083-0.33 but rough3 (0.043);
# true models up to 0.074 but one room, multiday3, 46 and walls9
# (0.085-0.27).
MODEL_MISFIT_MAX = 0.08

# The confidence such a clip's frames get at most: the share of the
# development members' frames in clips held by the model rule that were
# within 2 deg (bench/calibrate.py --write refits it), below 0.5 whatever
# it measures.
MODEL_DOUBTED_PROBABILITY = 0.4900


def model_misfit(misfits: Iterable[Optional[float]]) -> Optional[float]:
    """The clip's model misfit: the median of its tracked frames' misfits
    (None ignored); None when no frame was tracked."""
    values = sorted(float(v) for v in misfits if v is not None)
    if not values:
        return None
    mid = len(values) // 2
    return values[mid] if len(values) % 2 else 0.5 * (values[mid - 1] + values[mid])


# A clip whose model the clip refined (the estimate used the corrections)
# is a hand-made one: only such models' edges miss the clip's as far as the
# refinement's gate asks (it left every true model of the suite as it was),
# and what the refinement cannot see of a model still biases every frame's
# Sun alike. Its shadows must then fit the footage closely, not merely as
# well as a true model's may: its clip is doubted from this misfit on. On
# the suite's 13 refined rough members those at 0.021 or less were every
# frame within 2 deg (5 of them), those at 0.054 or more 0-68% (7; rough10,
# at 0.054, had 25 frames more than 5 deg off at 0.9 and more); rough15, at
# 0.087, all within.
REFINED_MISFIT_MAX = 0.03


def model_doubted(misfit: Optional[float], refined: bool = False) -> bool:
    """Whether a clip of this model misfit (model_misfit) is one whose
    model the footage does not fit: its support stays below 0.5. For a
    model the clip refined (`refined`) the bar is REFINED_MISFIT_MAX, and
    without a misfit it is doubted."""
    if refined:
        return misfit is None or misfit >= REFINED_MISFIT_MAX
    return misfit is not None and misfit >= MODEL_MISFIT_MAX


def clip_doubted(measured_share: float, misfit: Optional[float] = None,
                 refined: bool = False) -> bool:
    """Whether a clip keeps its support below 0.5 instead of the map: its
    Sun was measured on too small a share of the frames that could show it,
    or its model does not fit the footage (model_doubted)."""
    return measured_share < MEASURED_SHARE_MIN or model_doubted(misfit, refined)


def probability(support: float,
                knots: Sequence[Tuple[float, float]] = SUPPORT_TO_PROBABILITY,
                doubted_clip: bool = False, short_segment: bool = False,
                model_doubted_clip: bool = False,
                model_cap: float = MODEL_DOUBTED_PROBABILITY) -> float:
    """The calibrated confidence of a frame whose support is `support`
    (0 stays 0: a frame without evidence of its own is never likely); in a
    doubted clip (clip_doubted) the support itself, below 0.5, and in a clip
    whose model does not fit (model_doubted) at most model_cap (below 0.5
    whatever it is); below 0.5 too on a doubted frame and in a short segment
    (short_segment_frames)."""
    if support <= 0.0 or not knots:
        return max(0.0, support)
    if model_doubted_clip:
        return min(support, model_cap, DOUBTED_MAX_PROBABILITY)
    if doubted_clip:
        return min(support, DOUBTED_MAX_PROBABILITY)
    value = _interpolated(support, knots)
    if support < DOUBTED_SUPPORT or short_segment:
        return min(value, DOUBTED_MAX_PROBABILITY)
    return value


def _interpolated(support: float, knots: Sequence[Tuple[float, float]]) -> float:
    xs = [k[0] for k in knots]
    i = bisect.bisect_right(xs, support)
    if i == 0:
        # Below the first knot, its value: the fit pooled the frames of
        # little support with those at the knot (PAV: their share within
        # 2 deg was no lower), so the data say no less of them.
        return knots[0][1]
    if i == len(knots):
        return knots[-1][1]
    (x0, y0), (x1, y1) = knots[i - 1], knots[i]
    return y0 + (y1 - y0) * (support - x0) / (x1 - x0) if x1 > x0 else y1
