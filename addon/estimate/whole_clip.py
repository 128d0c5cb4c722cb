"""The Sun over the whole clip at once (bpy-free controller over _native).

Frames in, raw per-frame Suns out:

1. a visibility table of the model's visible surfaces over the whole sky
   (native SkyEvidence), with each surface sample's reference level taken
   from frames spread over the clip;
2. every frame scored against every sky direction (table look-ups);
3. the Sun's path chosen globally (native solve_sun_path): segments where
   the capture times jump back, the frame size changes, or the evidence
   demands a jump the times do not explain;
4. each segment refined to sub-degree by the shadow tracker, searching
   around the path's direction on every frame (no anchor frame, no
   re-acquisition heuristics).

Smoothing and the track file are the caller's (pipeline.py); smoothing never
crosses a segment boundary and never reaches past a segment's last measured
frame.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Sequence, Union

import numpy as np

# Frames spread over the clip whose high quantile per surface sample is its
# reference level (its albedo times its usual lit level).
REFERENCE_FRAMES = 24
# A refined Sun further than this from the path's direction is not believed
# (the tracker locked onto something else); the path's own direction is a
# grid cell that the evidence's ridge along the shadows can leave a few
# degrees off.
REFINE_MAX_DEG = 8.0
# Confidence of a frame grows with the chosen path's lead over the best path
# through a direction well away from it on that frame (log-likelihood units,
# see sun_path.h; the frame's own evidence and its neighbours'): full at this
# lead.
FULL_CONFIDENCE_MARGIN = 12.0
# The Sun's apparent motion bound (deg per hour), and per frame when the
# frames' times are unknown (sun_path.h's generous bound).
SUN_DEG_PER_HOUR = 15.5
UNTIMED_STEP_DEG = 12.0
# Confidence of frames without sky evidence of their own: carried by the
# path alone; followed by the tracker between frames with evidence (its
# sub-pixel fit sees thin shadows the sky's samples miss); followed past the
# segment's last frame with evidence (times the tracker's confidence).
CARRIED_CONFIDENCE = 0.05
FOLLOWED_CONFIDENCE = 0.5
FOLLOWED_BEYOND_CONFIDENCE = 0.25


@dataclass
class RawFrame:
    """One frame's raw estimate: the unit vector toward the Sun in the world
    frame (angles are the caller's: core.angles), or None with a reason when
    the frame has no estimate."""
    frame: int
    sun_in_world: Optional[np.ndarray] = None
    confidence: float = 0.0
    reason: Optional[str] = None
    segment: int = 0
    measured: bool = False        # the frame's own evidence supports it
    refined: bool = False         # the tracker refined it to sub-degree
    tracked: object = None        # native TrackedFrame when refined


@dataclass
class WholeClipResult:
    frames: List[RawFrame] = field(default_factory=list)   # in the order given
    segments: List[List[int]] = field(default_factory=list)  # frame numbers per segment
    jumps: List[int] = field(default_factory=list)  # frames after an unexplained jump
    anchor: Optional[int] = None   # the best-supported frame (for notes)
    timing: dict = field(default_factory=dict)
    # Per frame (in the order given): the best explained share of the frame's
    # variance and the chosen direction's lead over far rivals.
    evidence: dict = field(default_factory=dict)
    message: Optional[str] = None


class Cancelled(Exception):
    """The progress callback asked to stop."""


def _angle_deg(a, b) -> float:
    a, b = np.asarray(a, float), np.asarray(b, float)
    return math.degrees(math.atan2(np.linalg.norm(np.cross(a, b)), float(np.dot(a, b))))


def spread(n: int, k: int = REFERENCE_FRAMES) -> List[int]:
    """k positions spread evenly over range(n) (all of them when n <= k)."""
    if n <= k:
        return list(range(n))
    return sorted({round(i * (n - 1) / (k - 1)) for i in range(k)})


def _frame(read: Union[np.ndarray, str, None]) -> Optional[np.ndarray]:
    return read if isinstance(read, np.ndarray) else None


def estimate(native, scene, camera, frames: Sequence[int],
             read_gray: Callable[[int], Union[np.ndarray, str, None]],
             ground_object_ids: Sequence[int], times_s: Optional[Sequence[float]] = None,
             ignore_top_rows: int = 0,
             progress: Optional[Callable[[float], object]] = None) -> WholeClipResult:
    """Raw Suns on `frames` (in capture order). `read_gray(frame)` returns
    the frame as float32 linear gray of the camera's size, or None or a
    sentence saying why there is none (not decodable, another size, a file
    missing from a sequence). `times_s`: capture times
    in seconds (None when unknown). `native`: the compiled module (passed in,
    so this controller imports nothing of the add-on's package)."""
    frames = list(frames)
    n = len(frames)
    result = WholeClipResult()
    t0 = time.perf_counter()

    def tick(fraction):
        if progress is not None and progress(fraction) is False:
            raise Cancelled()

    opts = native.SkyEvidenceOptions()
    opts.ignore_top_rows = ignore_top_rows
    sky = native.SkyEvidence(scene, camera, opts)
    t_table = time.perf_counter() - t0
    reference = [_frame(read_gray(frames[i])) for i in spread(n)]
    used = sky.set_reference(reference)
    del reference
    t_setup = time.perf_counter() - t0
    if used == 0:
        result.frames = [RawFrame(f, reason="no frame of the clip could be read") for f in frames]
        result.message = "no frame of the clip could be read"
        return result

    # Pass 1: evidence for every frame.
    status, reasons = [], []
    ok = native.FrameEvidenceStatus.OK
    for k, f in enumerate(frames):
        tick(0.5 * k / n)
        got = read_gray(f)
        e = sky.add_frame(_frame(got))
        status.append(e.status)
        reasons.append(got if isinstance(got, str) else (e.message or None))
    t_evidence = time.perf_counter() - t0

    # Segments the caller knows of: capture times going back.
    starts = [0] * n
    if times_s is not None:
        for k in range(1, n):
            if times_s[k] < times_s[k - 1]:
                starts[k] = 1
    path_options = native.SunPathOptions()
    if times_s is not None:
        # Known times say where the clip is continuous: the Sun cannot jump
        # between frames minutes apart (time jumps are the segments above).
        path_options.jump_cost = -1.0
    path = native.solve_sun_path(sky, [] if times_s is None else list(times_s), starts,
                                 path_options)
    if not path["success"]:
        result.frames = [RawFrame(f, reason=path["message"] or reasons[k] or "no evidence")
                         for k, f in enumerate(frames)]
        result.message = path["message"]
        return result
    directions = sky.directions
    spacing = sky.spacing_deg
    bounds = [0]
    for k in range(1, n):
        if path["jump_before"][k]:
            bounds.append(k)
            if not starts[k]:
                result.jumps.append(frames[k])
    bounds.append(n)
    margins = path["margin"]
    measured = path["measured"]
    result.evidence = {"explained": [round(float(v), 3) for v in path["explained"]],
                       "margin": [round(float(v), 2) for v in margins],
                       "significance": [round(float(v), 1) for v in path["significance"]],
                       "path_margin": [round(float(v), 1) for v in path["path_margin"]],
                       "path_sun_in_world": [[round(float(v), 5) for v in directions[d]]
                                             for d in path["direction"]]}
    best = max(range(n), key=lambda k: (measured[k], margins[k]))
    result.anchor = frames[best] if measured[best] else None

    # Pass 2: refine each segment with the shadow tracker, forward from its
    # first measured frame, then back from it to the frames before.
    tracker = native.ShadowTracker(scene, camera, list(ground_object_ids),
                                   ignore_top_rows=ignore_top_rows)
    raws: List[RawFrame] = []
    clock = {"tracking": 0.0, "done": 0}

    def motion_deg(k, j):
        """How far the Sun can move between frames k and j (deg)."""
        if times_s is not None:
            return abs(times_s[k] - times_s[j]) / 3600.0 * SUN_DEG_PER_HOUR
        return abs(k - j) * UNTIMED_STEP_DEG

    def refine(k, raw, follow, beyond, anchor):
        """Refines frame k into `raw`; returns whether the tracker holds.
        Beyond the measured frames the path has no evidence of its own: the
        result is checked against the nearest measured frame's Sun, as far
        as the Sun can move from it."""
        clock["done"] += 1
        tick(0.5 + 0.5 * clock["done"] / n)
        d = directions[path["direction"][anchor if beyond else k]]
        limit = REFINE_MAX_DEG + (motion_deg(k, anchor) if beyond else 0.0)
        gray = _frame(read_gray(frames[k]))
        refined = None
        if gray is not None:
            # The tracker's own prediction (the last refined Suns' motion) is
            # finer than the path's grid cell; the path's direction is the
            # check, and the fallback when the tracker has drifted.
            for attempt in ("own", "path") if follow else ("path",):
                r = tracker.track(gray) if attempt == "own" else tracker.track_toward(gray, d)
                clock["tracking"] += r.seconds
                if r.ok and _angle_deg(r.sun_in_world, d) <= limit:
                    refined = r
                    break
        support = max(0.0, min(1.0, path["path_margin"][k] / FULL_CONFIDENCE_MARGIN))
        if refined is not None:
            raw.sun_in_world = np.asarray(refined.sun_in_world, dtype=float)
            raw.refined, raw.tracked, raw.reason = True, refined, None
            if measured[k]:
                raw.confidence = refined.confidence * support
            else:
                raw.confidence = refined.confidence * (
                    FOLLOWED_BEYOND_CONFIDENCE if beyond else FOLLOWED_CONFIDENCE)
        elif beyond:
            raw.reason = "shadow lost beyond the frames with shadow evidence"
        else:
            raw.sun_in_world = np.asarray(d, dtype=float)
            raw.confidence = (0.5 * support) if measured[k] else CARRIED_CONFIDENCE
        return refined is not None

    for s in range(len(bounds) - 1):
        lo, hi = bounds[s], bounds[s + 1]
        result.segments.append(frames[lo:hi])
        seg = [RawFrame(frames[k], segment=s, measured=bool(measured[k])) for k in range(lo, hi)]
        raws.extend(seg)
        usable = [status[k] in (ok, native.FrameEvidenceStatus.NO_SHADOWS) for k in range(lo, hi)]
        for k in range(lo, hi):
            if not usable[k - lo]:
                seg[k - lo].reason = reasons[k] or "no evidence on this frame"
            else:
                seg[k - lo].reason = "no shadow evidence on this frame or around it in its segment"
        first = next((k for k in range(lo, hi) if measured[k]), None)
        last = next((k for k in range(hi - 1, lo - 1, -1) if measured[k]), None)
        if first is None or last is None:
            continue
        for order in (range(first, hi), range(first, lo - 1, -1)):
            gray = _frame(read_gray(frames[first]))
            if gray is None or not tracker.initialize(
                    gray, directions[path["direction"][first]]).ok:
                break
            # The tracker takes the ground's albedo from this frame under the
            # Sun it is given: the grid cell's shadows are a little off, so
            # the frame is refined once and the tracker started again from
            # the refined Sun (albedo by shadow edges measured, not guessed).
            r = tracker.track_toward(gray, directions[path["direction"][first]])
            if r.ok and _angle_deg(r.sun_in_world,
                                   directions[path["direction"][first]]) <= REFINE_MAX_DEG:
                tracker.initialize(gray, np.asarray(r.sun_in_world, dtype=float))
            # Backward, the tracker holds from the first measured frame on.
            follow = order.step < 0
            for k in order:
                if k == first and order.step < 0:
                    continue  # refined on the way forward
                if not usable[k - lo]:
                    continue
                beyond = not first <= k <= last
                if beyond and not follow:
                    continue  # lost past the evidence: nothing to carry
                follow = refine(k, seg[k - lo], follow, beyond, last if k > last else first)
    result.frames = raws
    t_end = time.perf_counter() - t0
    result.timing = {"table_s": t_table, "reference_s": t_setup - t_table,
                     "evidence_ms_per_frame": 1000.0 * (t_evidence - t_setup) / max(1, n),
                     "tracking_ms_per_frame": 1000.0 * clock["tracking"] / max(1, n),
                     "total_s": t_end, "samples": sky.num_samples,
                     "directions": len(directions), "spacing_deg": spacing}
    return result
