"""The Sun over the whole clip at once (bpy-free controller over _native).

Frames in, raw per-frame Suns out:

1. a visibility table of the model's visible surfaces over the whole sky
   (native SkyEvidence), with each surface sample's reference level taken
   from frames spread over the clip;
2. one pass over the clip, each frame decoded once: every frame scored
   against every sky direction (table look-ups), and the shadow tracker
   following the shadows to sub-degree on the same frame, started on the
   first frame whose own evidence is unmistakable;
3. the Sun's path chosen globally (native solve_sun_path): segments where
   the capture times jump back, the frame size changes, or the evidence
   demands a jump the times do not explain; then the Sun's small circle
   about the pole fitted to each segment's measured frames, and the path
   chosen again with that circle as a prior where it strayed from it;
4. each segment checked against the path: a frame whose tracked Sun is
   further from the path than the tracker can be off is read again and
   refined around the path's direction (no anchor frame, no re-acquisition
   heuristics). Only those frames are decoded twice.

Smoothing and the track file are the caller's (pipeline.py); smoothing never
crosses a segment boundary and never reaches past a segment's last measured
frame.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import finish, frames as clip_frames, motion, native_loader, notes
from .errors import Cancelled, EstimateError
from .options import GAMMA
from ..core import angles, frametimes, trackfile, trimmed_circle

# Frames spread over the clip whose high quantile per surface sample is its
# reference level (its albedo times its usual lit level).
REFERENCE_FRAMES = 24
# On a short clip the reference frames are a large share of all decoding:
# those that are frames of the run are kept for the pass (up to this many
# bytes) instead of being decoded again.
SHORT_CLIP_FRAMES = 4 * REFERENCE_FRAMES
REFERENCE_KEEP_BYTES = 256 << 20
# The estimate works on frames at most this wide: larger ones are reduced
# (area average, by a power of two) as they are decoded, before they are
# made linear, and both the sky's evidence and the shadow tracker see them
# at that size (one ray a pixel: a reduced pixel is already the average the
# sub-pixel rays model). The tracker's band and ground map grow with the
# pixels, not its accuracy.
WORKING_MAX_WIDTH = 1280


# Confidence of a frame grows with the chosen path's lead over the best path
# through a direction well away from it on that frame (log-likelihood units,
# see sun_path.h; the frame's own evidence and its neighbours'): full at this
# lead.
FULL_CONFIDENCE_MARGIN = 12.0
# On a frame with evidence of its own, a tracked Sun further than this from
# the path's grid cell (about 1.5 cells) has drifted along its shadows: the
# frame is refined again around the path's direction, and a result still
# that far keeps half its confidence.
AGREE_DEG = 4.0
# Confidence of frames without sky evidence of their own: carried by the
# path alone; followed by the tracker between frames with evidence (its
# sub-pixel fit sees thin shadows the sky's samples miss); followed past the
# segment's last frame with evidence (times the tracker's confidence).
CARRIED_CONFIDENCE = 0.05
FOLLOWED_CONFIDENCE = 0.5
FOLLOWED_BEYOND_CONFIDENCE = 0.25
# The Sun's circle about the pole as a prior for the path. The sky grid's
# cells are points ~2.6 deg apart: along a long thin shadow (a pole's, low
# Sun) a cell scores by how well its azimuth happens to match the shadow,
# whatever its zenith, so a frame's best cell can lie 10-17 deg along the
# shadow from the Sun (the tip, the only cue to the zenith, weighs a few
# samples), and without capture times the path may step 12 deg a frame:
# it zigzagged along such ridges with full margins. The Sun's path over a
# segment is a small circle at a steady rate; fitted (trimmed:
# core/trimmed_circle.py) to the first path's measured frames, it is a
# prior for choosing the path again where the first path strayed further
# than PRIOR_STRAY_DEG from it (sun_path.h: prior_*). Not used on fewer
# than PRIOR_MIN_FRAMES measured frames or when the fit's median residual
# exceeds PRIOR_MAX_RESIDUAL_DEG (the first path too far from any circle
# to trust one).
PRIOR_MIN_FRAMES = 8
PRIOR_MAX_RESIDUAL_DEG = 3.0
PRIOR_STRAY_DEG = 4.0


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
    # Camera pixels per pixel of the tracker's results (shadow ends).
    tracker_pixel_scale: float = 1.0
    timing: dict = field(default_factory=dict)
    # Per frame (in the order given): the best explained share of the frame's
    # variance and the chosen direction's lead over far rivals.
    evidence: dict = field(default_factory=dict)
    message: Optional[str] = None


def _angle_deg(a, b) -> float:
    """Angle between two 3-vectors (deg); plain floats, as it runs per frame
    (numpy's per-call overhead was most of the check's time)."""
    ax, ay, az = (float(v) for v in a)
    bx, by, bz = (float(v) for v in b)
    cross = math.sqrt((ay * bz - az * by) ** 2 + (az * bx - ax * bz) ** 2
                      + (ax * by - ay * bx) ** 2)
    return math.degrees(math.atan2(cross, ax * bx + ay * by + az * bz))


def working_factor(width: int) -> int:
    """The power of two a frame `width` wide is divided by to be at most
    WORKING_MAX_WIDTH wide (halvings are the cheap area averages)."""
    factor = 1
    while width > factor * WORKING_MAX_WIDTH:
        factor *= 2
    return factor


def spread(n: int, k: int = REFERENCE_FRAMES) -> List[int]:
    """k positions spread evenly over range(n) (all of them when n <= k)."""
    if n <= k:
        return list(range(n))
    return sorted({round(i * (n - 1) / (k - 1)) for i in range(k)})


def _segments(jump_before: Sequence[bool], n: int) -> List[Tuple[int, int]]:
    """[lo, hi) index ranges between the path's jumps and segment starts."""
    bounds = [0] + [k for k in range(1, n) if jump_before[k]] + [n]
    return list(zip(bounds[:-1], bounds[1:]))


def _circle_prior(fit_circle: Callable[..., Any], path: dict,
                  directions: Sequence[Sequence[float]],
                  times_s: Optional[Sequence[float]], n: int,
                  spacing_deg: float) -> Optional[np.ndarray]:
    """Per frame the Sun on its circle about the pole fitted (fit_circle:
    core/trimmed_circle.py's fit_trimmed) to the path's measured frames in
    the frame's segment ((n, 3), NaN rows where no fit holds), or None when the path
    keeps to the fitted circles (nothing to choose again). The grid's
    cells are the path's precision: the inlier limit never falls below a
    grid step."""
    prior = np.full((n, 3), np.nan)
    strayed = False
    for lo, hi in _segments(path["jump_before"], n):
        ks = list(range(lo, hi))
        suns = [directions[path["direction"][k]]
                if path["measured"][k] and path["direction"][k] >= 0 else None for k in ks]
        if sum(s is not None for s in suns) < PRIOR_MIN_FRAMES:
            continue
        times = [float(k) if times_s is None else float(times_s[k]) for k in ks]
        fit = fit_circle(times, suns, spacing_deg, times_are_seconds=times_s is not None)
        if not fit.success or fit.residual_deg is None or \
                fit.residual_deg > PRIOR_MAX_RESIDUAL_DEG:
            continue
        for i, k in enumerate(ks):
            prior[k] = fit.sun_in_world[i]
        strayed = strayed or any(off is not None and off > PRIOR_STRAY_DEG
                                 for off in fit.off_deg)
    return prior if strayed else None


def _evidence_support(first: dict, again: dict,
                      directions: Sequence[Sequence[float]], spacing_deg: float) -> List[float]:
    """Per frame the path margin that the frames' confidence is built on,
    after the path was chosen again under the circle prior. The prior is
    fitted to the other frames' evidence: counted in the margin it would
    count them twice (indoor_window's first frames, 2 deg off, rose from
    confidence 0.4 to 0.9). Where the path kept its direction (within a
    grid cell and a half), the first path's margin (evidence only) caps
    it; where the prior moved it, the frame's evidence chose otherwise: the
    direction rests on the circle, i.e. on the other frames, and gets at
    most half the support (FOLLOWED_CONFIDENCE, as frames the tracker
    follows between frames with evidence; none left it at confidence 0 and
    let a wrong neighbour steer the smoothing)."""
    out = []
    for k, margin in enumerate(again["path_margin"]):
        d1, d2 = first["direction"][k], again["direction"][k]
        if d1 < 0 or d2 < 0:
            out.append(float(margin))
        elif _angle_deg(directions[d1], directions[d2]) <= 1.5 * spacing_deg:
            out.append(min(float(margin), float(first["path_margin"][k])))
        else:
            out.append(min(float(margin), FOLLOWED_CONFIDENCE * FULL_CONFIDENCE_MARGIN))
    return out


def _frame(read: Union[np.ndarray, str, None]) -> Optional[np.ndarray]:
    return read if isinstance(read, np.ndarray) else None


Gray = Union[np.ndarray, str, None]
# (frames, (width, height)) -> (a native FrameSource, {frame: its index})
SourceFn = Callable[[Sequence[int], Tuple[int, int]], Tuple[object, dict]]


def estimate(native, scene, camera, frames: Sequence[int],
             read_gray: Callable[[int], Gray],
             ground_object_ids: Sequence[int], times_s: Optional[Sequence[float]] = None,
             ignore_top_rows: int = 0,
             progress: Optional[Callable[[float], object]] = None,
             stream: Optional[Callable[..., Iterable[Tuple[int, Gray]]]] = None,
             source: Optional[SourceFn] = None,
             fit_circle: Optional[Callable[..., Any]] = None
             ) -> WholeClipResult:
    """Raw Suns on `frames` (in capture order). `read_gray(frame)` returns
    the frame as float32 linear gray of the camera's size, or None or a
    sentence saying why there is none (not decodable, another size, a file
    missing from a sequence); it reads the few frames read again after the
    pass. `stream(frames, near, size)`, when given, yields (frame, the same
    reduced to size = (width, height)) for the reference frames spread over
    the clip, decoded ahead; near=True lets a frame be one shortly before
    the one asked that is cheaper to reach (a movie's key frame), or leaves
    some out. `source(frames, size)`, when given, returns (a native
    FrameSource giving those frames in that order at that size, decoded
    ahead, {frame: the index it reports for it}) for the pass over the clip;
    without them the frames are read with read_gray, and the pass's held in
    memory (tests, synthetic clips). `times_s`: capture times in seconds
    (None when unknown). `native`: the compiled module, and `fit_circle`:
    the trimmed fit of the Sun's circle (core/trimmed_circle.py's
    fit_trimmed; None: the path gets no circle prior), passed in, so this
    controller imports nothing of the add-on's package."""
    frames = list(frames)
    n = len(frames)
    result = WholeClipResult()
    t0 = time.perf_counter()

    def tick(fraction):
        if progress is not None and progress(fraction) is False:
            raise Cancelled()

    # Large frames are reduced (WORKING_MAX_WIDTH): `work` is the camera of
    # the frames the evidence and the tracker see.
    factor = working_factor(camera.width)
    work = camera if factor == 1 else camera.resized(camera.width // factor,
                                                     camera.height // factor)
    size = (work.width, work.height)
    top = -(-ignore_top_rows // factor)
    result.tracker_pixel_scale = camera.width / work.width

    def reduced(image: Gray) -> Gray:
        """A frame read by read_gray at the working size."""
        gray = _frame(image)
        if gray is None or gray.shape == (work.height, work.width):
            return image
        return native.resized_gray(gray, work.width, work.height)

    # The reference frames are decoded ahead while the table is cast.
    wanted_reference = [frames[i] for i in spread(n)]
    reference_frames: Iterable[Tuple[int, Gray]] = (
        ((f, reduced(read_gray(f))) for f in wanted_reference) if stream is None
        else stream(wanted_reference, True, size))
    opts = native.SkyEvidenceOptions()
    opts.ignore_top_rows = top
    sky = native.SkyEvidence(scene, work, opts)
    t_table = time.perf_counter() - t0
    reference, kept = [], {}
    budget = REFERENCE_KEEP_BYTES if n <= SHORT_CLIP_FRAMES else 0
    wanted = set(frames)
    for f, image in reference_frames:
        gray = _frame(image)
        reference.append(gray)
        if gray is not None and f in wanted and f not in kept and gray.nbytes <= budget:
            kept[f], budget = gray, budget - gray.nbytes
    used = sky.set_reference(reference)
    used_frames = len(reference)
    del reference
    t_setup = time.perf_counter() - t0
    if used == 0:
        result.frames = [RawFrame(f, reason="no frame of the clip could be read") for f in frames]
        result.message = "no frame of the clip could be read"
        return result

    # Segments the caller knows of: capture times going back.
    starts = [0] * n
    if times_s is not None:
        for k in range(1, n):
            if times_s[k] < times_s[k - 1]:
                starts[k] = 1
    reads = {"count": used_frames}

    def read_again(k):
        """Frame k at the working size: as the pass kept it, else read
        again."""
        # Frames the pass kept because the check was likely to want them.
        gray = done.take_kept(k)
        if gray is not None:
            return gray
        reads["count"] += 1
        return _frame(reduced(read_gray(frames[k])))

    # The pass over the clip, in native code without Python's lock: evidence
    # for every frame, and the tracker following the shadows on the same
    # frames (checked against the path afterwards).
    usable_status = (int(native.FrameEvidenceStatus.OK),
                     int(native.FrameEvidenceStatus.NO_SHADOWS))
    directions = [tuple(d) for d in sky.directions.tolist()]
    tracker = native.ShadowTracker(scene, work, list(ground_object_ids), ignore_top_rows=top,
                                   subsamples=1 if factor > 1 else 0)
    clock = {"tracking": 0.0, "done": 0}
    rest = [f for f in frames if f not in kept]
    if source is None:
        frame_source = native.FrameList([(i, reduced(read_gray(f))) for i, f in enumerate(rest)])
        index_of = {f: i for i, f in enumerate(rest)}
    else:
        frame_source, index_of = source(rest, size)
    # A refined Sun further than steer_deg from the path's direction is not
    # believed (the tracker locked onto something else): the pass's own
    # steering limit, also the check's.
    pass_options = native.ClipPassOptions()
    refine_max_deg = pass_options.steer_deg
    done = native.run_clip_pass(
        frame_source, [index_of.get(f, -1) if f not in kept else -1 for f in frames],
        [kept.get(f) for f in frames], starts, work, sky, tracker, pass_options,
        lambda x: progress is None or progress(0.8 * x) is not False)
    del kept, frame_source
    if done.cancelled:
        raise Cancelled()
    reads["count"] += len(rest)
    clock["tracking"] += done.tracking_seconds
    clock["start"] = done.start_seconds
    tracker_started = done.tracker_started
    # Per frame, in native memory (done.reason(k), done.track(k)): Python
    # objects for every frame would cost kilobytes a frame on long clips.
    usable_frames = np.isin(done.status, usable_status)
    t_evidence = time.perf_counter() - t0

    path_options = native.SunPathOptions()
    if times_s is not None:
        # Known times say where the clip is continuous: the Sun cannot jump
        # between frames minutes apart (time jumps are the segments above).
        path_options.jump_cost = -1.0
    path = native.solve_sun_path(sky, [] if times_s is None else list(times_s), starts,
                                 path_options)
    if not path["success"]:
        result.frames = [RawFrame(f, reason=path["message"] or done.reason(k) or "no evidence")
                         for k, f in enumerate(frames)]
        result.message = path["message"]
        return result
    t_path = time.perf_counter() - t0
    prior = None if fit_circle is None else _circle_prior(
        fit_circle, path, directions, times_s, n, sky.spacing_deg)
    t_prior = time.perf_counter() - t0
    if prior is not None:
        again = native.solve_sun_path(sky, [] if times_s is None else list(times_s), starts,
                                      path_options, prior)
        if again["success"]:
            path = dict(again, path_margin=_evidence_support(path, again, directions,
                                                             sky.spacing_deg))
    t_solved = time.perf_counter() - t0
    spacing = sky.spacing_deg
    sky_sizes = {"samples": sky.num_samples, "band_entries": sky.band_entries}
    # The sky's table and every frame's kept costs (3 kB a frame) are done
    # with: the check needs the path only.
    del sky
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
                       "path_sun_in_world": [[round(v, 5) for v in directions[d]]
                                             for d in path["direction"]]}
    best = max(range(n), key=lambda k: (measured[k], margins[k]))
    result.anchor = frames[best] if measured[best] else None

    # Each segment against the path, forward from its first measured frame,
    # then back from it to the frames before. A frame the pass tracked to a
    # Sun near the path keeps it; the others are read again and refined
    # around the path's direction by the pass's tracker (or, where it never
    # started, one started on the segment's first measured frame).
    raws: List[RawFrame] = []
    before, after = [0] * n, [0] * n  # nearest measured frames, in a segment's span
    where = {"run": None, "last": None}  # the tracker's run and its last frame

    def motion_deg(k, j):
        return motion.sun_motion_bound_deg(k, j, times_s, path_options)

    def restart(run, first):
        """A tracker for the frames read again: the pass's own, or, when it
        never started there, one started on frame `first` under the path's
        Sun, once per run (segment, direction)."""
        if where["run"] == run or tracker_started:
            where["run"] = run
            return True
        gray = read_again(first)
        ok_start = gray is not None and native.start_tracker(
            tracker, gray, directions[path["direction"][first]], refine_max_deg)[0]
        where["run"], where["last"] = run, first
        return ok_start

    def between(k, sun_in_world):
        """Whether a Sun on a frame without evidence of its own, between
        frames with evidence, is where the Sun can be from both of them: the
        path carries such frames on a grid cell that lags the Sun, so the
        tracker's own Sun is checked against the measured frames instead."""
        for j in (before[k], after[k]):
            d = directions[path["direction"][j]]
            if _angle_deg(sun_in_world, d) > refine_max_deg + motion_deg(k, j):
                return False
        return True

    def refine(k, raw, run, first, beyond, anchor, step):
        """Refines frame k into `raw`; returns whether the tracker holds.
        Beyond the measured frames the path has no evidence of its own: the
        result is checked against the nearest measured frame's Sun, as far
        as the Sun can move from it."""
        clock["done"] += 1
        tick(0.8 + 0.2 * clock["done"] / n)
        d = directions[path["direction"][anchor if beyond else k]]
        limit = refine_max_deg + (motion_deg(k, anchor) if beyond else 0.0)
        refined = done.track(k)
        if refined is not None and not measured[k] and not beyond:
            if _angle_deg(refined.sun_in_world, d) > limit and not between(
                    k, refined.sun_in_world):
                refined = None
        elif refined is not None and _angle_deg(refined.sun_in_world, d) > (
                AGREE_DEG if measured[k] else limit):
            refined = None
        if refined is None and restart(run, first):
            gray = read_again(k)
            # The tracker's own prediction (the last refined Suns' motion) is
            # finer than the path's grid cell, when it has just followed the
            # neighbouring frame; the path's direction is the check, and the
            # fallback when the tracker has drifted.
            own = where["last"] == k - step
            for attempt in ("own", "path") if own else ("path",):
                if gray is None:
                    break
                r = tracker.track(gray) if attempt == "own" else tracker.track_toward(gray, d)
                clock["tracking"] += r.seconds
                where["last"] = k
                if r.ok and _angle_deg(r.sun_in_world, d) <= limit:
                    refined = r
                    break
        support = max(0.0, min(1.0, path["path_margin"][k] / FULL_CONFIDENCE_MARGIN))
        if refined is not None:
            raw.sun_in_world = np.asarray(refined.sun_in_world, dtype=float)
            raw.refined, raw.tracked, raw.reason = True, refined, None
            if measured[k]:
                raw.confidence = refined.confidence * support
                if _angle_deg(refined.sun_in_world, d) > AGREE_DEG:
                    raw.confidence *= 0.5
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
        usable = usable_frames[lo:hi]
        for k in range(lo, hi):
            if not usable[k - lo]:
                seg[k - lo].reason = done.reason(k) or "no evidence on this frame"
            else:
                seg[k - lo].reason = "no shadow evidence on this frame or around it in its segment"
        first = next((k for k in range(lo, hi) if measured[k]), None)
        last = next((k for k in range(hi - 1, lo - 1, -1) if measured[k]), None)
        if first is None or last is None:
            continue
        for k in range(first, last + 1):
            before[k] = k if measured[k] else before[k - 1]
        for k in range(last, first - 1, -1):
            after[k] = k if measured[k] else after[k + 1]
        for order in (range(first, hi), range(first - 1, lo - 1, -1)):
            follow = True
            for k in order:
                if not usable[k - lo]:
                    continue
                beyond = not first <= k <= last
                if beyond and not follow:
                    continue  # lost past the evidence: nothing to carry
                follow = refine(k, seg[k - lo], (s, order.step), first, beyond,
                                last if k > last else first, order.step)
    t_checked = time.perf_counter() - t0
    result.frames = raws
    t_end = time.perf_counter() - t0
    result.timing = {"table_s": t_table, "reference_s": t_setup - t_table,
                     "evidence_ms_per_frame": 1000.0 * (t_evidence - t_setup) / max(1, n),
                     "tracking_ms_per_frame": 1000.0 * clock["tracking"] / max(1, n),
                     "tracker_start_s": clock["start"],
                     "path_s": t_path - t_evidence, "prior_s": t_prior - t_path,
                     "path_again_s": t_solved - t_prior, "path_prior": prior is not None,
                     "check_s": t_checked - t_solved,
                     "frames_read": reads["count"], "frames": n,
                     "total_s": t_end, **sky_sizes,
                     "directions": len(directions), "spacing_deg": spacing}
    return result


def run(scene, camera, clip_path, source, frames, visit, times, options, track, progress, t0):
    """The default method: the Sun over the whole clip at once
    (estimate/whole_clip.py), then smoothing per segment."""
    native = native_loader.require()
    north = options.north_offset_deg
    # The frames spread over the clip for the reference levels are kept in
    # colour, at the unmodelled-shadow note's size, for the clip's shadow-free
    # background.
    samples = {}
    stride = notes.note_stride(camera)

    def read_gray(f):
        try:
            bgr = source.read(f)
        except StopIteration:
            return "the clip ended before this frame"
        if bgr is None:
            return source.why_not()
        return (clip_frames.wrong_size(bgr, camera)
                or native.to_linear_gray(bgr, GAMMA[options.method]))

    # The frames stream reduced to the estimate's working size: a clip of
    # another size than the camera's would be reduced to it silently.
    clip_frames.check_clip_size(source.reader.width, source.reader.height, camera)

    def open_stream(fs, near, size):
        # The reference frames also come in colour for the note, at its size.
        try:
            return native.FrameStream(
                clip_path, [f - source.start for f in fs],
                native.FrameStreamOptions(gamma=GAMMA[options.method], near=near,
                                          keep_bgr=near, width=size[0], height=size[1],
                                          bgr_width=-(-camera.width // stride),
                                          bgr_height=-(-camera.height // stride)))
        except ValueError as e:
            raise EstimateError(f"cannot read the clip: {e}")

    def stream(fs, near, size):
        """The frames in order at `size`, decoded ahead on a native thread
        (started now, before the first is asked for)."""
        return streamed(open_stream(fs, near, size), near)

    def frame_source(fs, size):
        """The pass's frames at `size`: a native stream, and the index it
        reports for each frame (its 0-based index in the clip)."""
        pass_stream["stream"] = open_stream(fs, False, size)
        return pass_stream["stream"], {f: f - source.start for f in fs}

    def streamed(frame_stream, near):
        start = source.start
        past_end = native.StreamedFrameStatus.past_end
        for got in frame_stream:
            f = got.index + start
            if got.gray is not None:
                if near:
                    samples[f] = got.bgr
                yield f, got.gray
            elif got.status == past_end:
                yield f, "the clip ended before this frame"
            else:
                yield f, got.message or "frame not decodable"

    pass_stream = {"stream": None}

    seconds = None
    if times is not None:
        by_frame = dict(zip(frames, frametimes.seconds_since(times)))
        seconds = [by_frame[f] for f in visit]
    result = estimate(
        native, scene, camera, visit, read_gray, options.ground_object_ids, times_s=seconds,
        ignore_top_rows=options.ignore_top_rows,
        progress=None if progress is None else (lambda x: progress(0.95 * x)),
        stream=stream, source=frame_source, fit_circle=trimmed_circle.fit_trimmed)
    track.method["initial"] = track.method["tracking"] = "whole_clip"
    by_frame = {r.frame: r for r in result.frames}
    raws = []
    geographic = {}  # frame -> (zenith, geographic azimuth)
    for f in frames:
        r = by_frame[f]
        if r.sun_in_world is None:
            raws.append((f, None, None, r.confidence, r.reason, r.tracked))
            continue
        z, a_world = angles.angles_from_sun_in_world(r.sun_in_world)
        geographic[f] = (float(z), float(angles.azimuth_geographic_from_world(a_world, north)))
        raws.append((f, *geographic[f], r.confidence, r.reason, r.tracked))
    raws, circle = finish.doubt_off_circle(raws, result.segments, frames, times, north)
    if result.anchor is not None:
        a = by_frame[result.anchor]
        track.initial = {"frame": a.frame, "zenith_deg": geographic[a.frame][0],
                         "azimuth_deg": geographic[a.frame][1],
                         "residual": None, "confidence": a.confidence,
                         "seconds": result.timing.get("table_s", 0.0)
                         + result.timing.get("reference_s", 0.0),
                         "message": "the best-supported frame of the whole-clip path"}
        # Unmodelled shadows are looked for on the best-supported frame kept
        # in colour (no frame is decoded again for the note).
        kept = [f for f in samples if f in by_frame and by_frame[f].sun_in_world is not None]
        if kept:
            f = max(kept, key=lambda f: by_frame[f].confidence)
            notes.note_unmodelled_shadows(track, scene, camera, f, samples[f],
                                          by_frame[f].sun_in_world, list(samples.values()), options)
    elif result.message:
        track.report("estimate", trackfile.ProblemKind.FAILED, result.message)
    track.extra["segments"] = [[seg[0], seg[-1]] for seg in result.segments]
    if result.evidence:
        track.extra["evidence"] = dict(result.evidence, frames=list(visit))
    if result.jumps:
        track.extra["jumps"] = result.jumps
    finish.finish(native, track, raws, options, times, progress, result.segments,
                  result.tracker_pixel_scale, circle)
    wait = 0.0 if pass_stream["stream"] is None else pass_stream["stream"].wait_seconds
    pass_stream["stream"] = None
    track.extra["timing"] = dict(result.timing, decode_wait_s=wait,
                                 total_s=time.perf_counter() - t0)
    return track
