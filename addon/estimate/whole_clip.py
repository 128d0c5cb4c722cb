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

5. each segment's Sun circle fitted to its refined Suns, kept with the
   result (the smoothing's prior) and lowering the confidence of frames far
   off it;
6. direct sunlight decided per frame (Sunlight): frames without it keep no
   Sun of their own (no shadows to measure one by: a dark frame's best
   direction is whatever its ambient shading resembles) and confidence 0;
   finish.py predicts theirs from their segment's path.

The controller (_WholeClip) takes these as named steps over one state;
run() drives it over a clip and hands the raw Suns to finish.py: smoothing
never crosses a segment boundary and never reaches past a segment's last
measured frame.
"""

from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Set, Tuple, Union

import numpy as np

from . import calibration, finish, frames as clip_frames, motion, native_loader, notes, untimed
from . import sun_circle
from .moving_view import SHADOWS_IN_VIEW, SHADOWS_OUT_OF_VIEW, MovingView, reference_camera
from .errors import Cancelled, EstimateError
from .frames import Gray
from .options import gamma
from .raw import RawSun
from ..core import angles, clock, smoothing, trackfile
from ..core.trackfile import Sunlight

# Frames spread over the clip whose high quantile per surface sample is its
# reference level (its albedo times its usual lit level).
REFERENCE_FRAMES = 24
# On a short clip the reference frames are a large share of all decoding:
# those that are frames of the run are kept for the pass (up to this many
# bytes) instead of being decoded again. So they are on a clip of any length
# whose frames decode on their own (stills, ProRes): the pass skips them at
# no cost, where a long-GOP video would decode them anyway.
SHORT_CLIP_FRAMES = 4 * REFERENCE_FRAMES
REFERENCE_KEEP_BYTES = 256 << 20
# The estimate works on frames at most this wide: larger ones are reduced
# (area average, by a power of two) as they are decoded, before they are
# made linear, and both the sky's evidence and the shadow tracker see them
# at that size. The tracker's band and ground map grow with the pixels, not
# its accuracy. Its shadow model keeps its sub-pixel rays there (the
# ShadowTracker's own choice, 2 x 2 below 1280 wide): a working pixel on an
# edge is partly lit, and one ray a pixel models it as lit or not. With one
# ray, walls2 read as 24 MP stills erred 1.79 / 5.32 deg in zenith (mean /
# max) against 0.63 / 1.75 with four.
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
# A tracked Sun whose elevation the shadows in view do not pin within this
# (TrackedFrame.elevation_pinned_deg: the casters' tops' shadows out of
# view, so any lower Sun fits alike) answers to the circle of the frames
# that pin it, when there are enough of them (doubt_off_circle): so far
# off it that a pinned Sun would not be taken for the Sun's
# (OFF_CIRCLE_UNLIT_DEG), with its shadows pointing the circle's way, it
# takes the circle's Sun, its support held just under
# calibration.DOUBTED_SUPPORT (UNPINNED_SUPPORT: a doubted frame, under 0.5
# whatever the map). On the static suite raw Suns pinned within 0.5 deg are
# within 2 deg 96% of the time, within 4 or 8 deg 80% and 78%, not within
# 8 deg 63% (45 of 310 more than 5 deg off); moving12's first 21
# frames, their shadows running out of view, came back up to 32 deg too low.
# Nearer the circle such frames are doubted as any Sun off it is: handing
# them to the circle too moved the smoothing at the end of the Marseille
# January clip (1.50 -> 1.75 deg zenith mean), and a limit of 2 deg took
# the dial's midday (its small gnomon shadow pins 4-8 deg) out of the
# circle (1.50 -> 1.97).
ELEVATION_PINNED_MAX_DEG = 8.0
UNPINNED_SUPPORT = 0.95 * calibration.DOUBTED_SUPPORT
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
# sun_circle.py's fit_trimmed) to the first path's measured frames, it is a
# prior for choosing the path again where the first path strayed further
# than PRIOR_STRAY_DEG from it (sun_path.h: prior_*). Not used where the
# fit has too few measured frames (TrimmedCircleOptions.min_frames) or its
# median residual exceeds PRIOR_MAX_RESIDUAL_DEG (the first path too far
# from any circle to trust one).
PRIOR_MAX_RESIDUAL_DEG = 3.0
PRIOR_STRAY_DEG = 4.0


# A frame's Sun further than this from the Sun's circle about the pole,
# fitted to its segment's confident frames, loses confidence with the square
# of the ratio (half at 4.2 deg, a tenth at 9.5): on the randomised suite 15
# of the 18 raw Suns more than 5 deg off at confidence >= 0.8 were over
# 3 deg from it, and 7 of the 759 good ones. The sky's evidence can be
# confidently wrong over a few frames (a pole's shadow along a paving
# joint); the Sun's path over the segment cannot bend that way, and a Sun
# far off it must not steer the smoothing either. The fit is trimmed
# (sun_circle.h): a third of a segment's Suns stuck a few degrees to
# one side (suite scene 16's low-Sun frames) pulled a Huber fit through
# them, and they kept their confidence. Suns within CIRCLE_INLIER_FLOOR_DEG
# of the circle always take part in the fit (a refined Sun's own scatter).
CIRCLE_DOUBT_DEG = 3.0
CIRCLE_INLIER_FLOOR_DEG = 1.5

# Direct sunlight (Sunlight, per frame). The sky's evidence alone cannot
# say it: under the sky's light alone the model's surfaces are darker where
# they see less sky (ambient occlusion), which a Sun near the zenith
# explains well (a dark frame's best direction came out overhead on a real
# sundial webcam, and on test_whole_clip's dusk frames its lead over no
# shadows at all was 50x the evidence threshold). The tracker's fit says
# it: the Sun's shadows, sharp where the Sun puts them, with the
# sun/ambient contrast across their edges at least SUNLIT_MIN_CONTRAST (on
# the static suite 1880 of 1933 frames with the Sun 4 deg up or more fit
# 1.3 or more; the shade at the casters' feet fits 1.1-1.2 on night frames,
# once the shadow rays start 3 mm off the ground, not 4.5 cm: docs/
# accuracy.md "The surface offset's bias"); a frame it could not confirm,
# by how much of it the sky's evidence explains (SUNLIT_EXPLAINED_SHARE).
# A Sun below the horizon, the frame's own or its segment's circle's,
# lights no ground, whatever the frame shows (a grazing Sun's fitted
# contrast means nothing: the tracker fitted 5-9 on suite frames whose Sun
# had set by 0.3 deg). A readable frame without sunlight, in a segment
# whose other frames show it, says NO; else UNKNOWN.
SUNLIT_MIN_CONTRAST = 1.3
# A hazy Sun casts weaker shadows: a frame fitted at least
# SUNLIT_HAZY_CONTRAST is in sunlight too when its segment stands on frames
# at SUNLIT_MIN_CONTRAST, though it never makes a segment stand on its own.
# The Marseille March dial's hazy frames (08:15, 14:30, 17:49, the gnomon's
# shadow faint but there) fit 1.06-1.21 and its frames under cloud 0.77-0.86;
# twilight5's night frames fit 1.11-1.22 in a segment of their own, a jump
# the path would make 32 deg up. Such a frame further than CIRCLE_DOUBT_DEG
# from its segment's circle is not in sunlight (the January dial's last
# capture, in shade, fits 1.11 with a Sun 9 deg off its circle).
SUNLIT_HAZY_CONTRAST = 1.0
# A frame whose Sun is the path's direction, which the tracker could not
# refine: good to the sky grid's cell.
PATH_CELL_ONLY = ("the tracker could not refine this frame's Sun: it is the whole-clip path's "
                  "direction, good to a degree or two")
# A frame the tracker could not confirm, on which the path's Sun casts no
# shadow of the model on the ground in view (TrackedFrameStatus
# no_shadow_in_view: shadows on walls alone, a high Sun's hidden under its
# casters), cannot show sunlight on the ground: it is UNKNOWN, not NO, and
# counts as one whose shadows are out of view. Suite member walls3's facade
# frames in sunlight were NO, their lamp keyed off (13 of its 16 sunlit
# frames flagged NO; docs/accuracy.md).
NO_SHADOW_IN_VIEW = ("the Sun's path casts no shadow of the model on the ground in view on "
                     "this frame: it cannot show whether the Sun shines")
# A frame with evidence of its own that the tracker could not confirm (a
# ground the tracker cannot use: a bollard named as the ground left 8 of the
# plaza's 32 sunny frames unconfirmed) is in sunlight while its best
# direction explains at least this share of what it explains on the median
# frame the tracker confirmed: ambient shading explained 0.2 of the variance
# on test_whole_clip's dusk frames where the Sun's shadows explained 0.7.
SUNLIT_EXPLAINED_SHARE = 0.5
# A segment the path jumped to (no capture times to explain it) stands only
# on a frame in sunlight whose own evidence leads far rivals by this much
# (log-likelihood; path.margin); else it joins the segment before it. At
# dusk on the Marseille January clip the last capture, the dial in shade,
# repeated 13 times, paid for a jump with a grazing Sun along the engraved
# noon line, 58 deg off at confidence up to 0.93: no frame of it led by
# more than 5.1, where a real cut's frames lead by 12-25.
SEGMENT_MIN_MARGIN = 8.0
# Where the frame numbers leave at least this many of a segment's Suns
# further off its circle than OFF_CIRCLE_UNLIT_DEG, and the Sun's own pace
# (untimed.pace_clock) at most half as many, the segment's circle follows
# the pace: low Suns' heights drift along their shadows, which moves their
# pace as much (tried on every segment whose thirds' paces differ, it took
# 8 of the 68 suite scenes off a clock that was right: 4 failed, 14 frames
# more than 5 deg off at confidence >= 0.5; tried in the path's circle
# prior as well, it kept scene 16 and walls4 from the prior that pulls
# their straying path frames back: 3.8 and 5.3 deg mean).
PACE_SWITCH_FRAMES = 3
# A frame whose Sun is this far off its segment's circle shows shadows that
# are not the Sun's where the path puts it (an engraved line, a dark
# object): it is not counted as in sunlight (UNKNOWN) and gets the path.
OFF_CIRCLE_UNLIT_DEG = 10.0
# Without times, a segment the path jumped to between two others whose
# Suns lie on one circle at one pace (at least EXCURSION_SIDE_FRAMES in
# sunlight on either side, most of each side's within OFF_CIRCLE_UNLIT_DEG
# of the circle fitted to both) is footage the clip went on through, not a
# cut: where most of its own Suns are further off that circle, its evidence
# is not the Sun's and the path is chosen again without it. Fresh member
# trees9: the box in a tree's unmodelled shade, frames 17-23 a segment of
# their own 118-127 deg off at the model rule's 0.41, between segments
# within 7 deg.
EXCURSION_SIDE_FRAMES = 3
# With capture times and the place, a frame whose Sun the ephemeris puts
# below the horizon has no direct sunlight, whatever its evidence (a night
# frame's street lights and ambient shading gave a raw Sun 5 deg up on the
# Mulhouse webcam). The tracker's confirmation does not outweigh the clock
# there (street lights cast hard shadows: it confirmed both of Mulhouse's
# night frames) -- unless at least CLOCK_WRONG[0] confirmed frames, and
# more than CLOCK_WRONG[1] of them, have the clock's Sun further below than
# CLOCK_NIGHT_SLACK_DEG (a Sun just set still fits a contrast, and webcam
# stamps run a minute or two off): then the times' zone or the place is
# wrong, and the clock is not used. Either way the run names the frames.
CLOCK_WRONG = (3, 0.5)
CLOCK_NIGHT_SLACK_DEG = 2.0


@dataclass
class RawFrame:
    """One frame's raw estimate: the unit vector toward the Sun in the world
    frame (angles are the caller's: core.angles), or None with a reason when
    the frame has no estimate. confidence is the support of the frame's
    evidence and the path; on_circle the same, lowered where the Sun is far
    off its segment's circle (CIRCLE_DOUBT_DEG): the frame's confidence."""
    frame: int
    sun_in_world: Optional[np.ndarray] = None
    confidence: float = 0.0
    on_circle: float = 0.0
    reason: Optional[str] = None
    segment: int = 0
    measured: bool = False        # the frame's own evidence supports it
    refined: bool = False         # the tracker refined it to sub-degree
    tracked: object = None        # native TrackedFrame when refined (FrameShadow:
    #                               a moving camera's, in its frame's pixels)
    # The Sun on its segment's circle about the pole, where one was fitted,
    # and whether that circle checks this frame's Sun: only a circle fitted
    # to Suns whose shadows pin their height (TrimmedCircleOptions.min_frames of
    # them) does; one bent with the others' open heights agrees with a
    # wrong pinned Sun as well (fresh member urban15: 4 of 32 frames
    # pinned, one 6.5 deg off at 0.98).
    circle_in_world: Optional[np.ndarray] = None
    circle_checked: bool = False
    # Direct sunlight on the frame; without it the frame keeps no Sun of
    # its own (finish.py predicts one from the segment's path).
    sunlight: Sunlight = Sunlight.UNKNOWN
    # False on a frame without sunlight whose moving camera does not see
    # where the shadows fall (SHADOWS_IN_VIEW): it could not show the Sun.
    shadows_in_view: bool = True


@dataclass
class WholeClipResult:
    frames: List[RawFrame] = field(default_factory=list)   # in the order given
    segments: List[List[int]] = field(default_factory=list)  # frame numbers per segment
    jumps: List[int] = field(default_factory=list)  # frames after an unexplained jump
    # Without times, the clock of the frames whose segment's circle follows
    # the Sun's pace (untimed.pace_clock), by frame number: the smoothing's too.
    paced: Dict[int, float] = field(default_factory=dict)
    anchor: Optional[int] = None   # the best-supported frame (for notes)
    # Camera pixels per pixel of the tracker's results (shadow ends).
    tracker_pixel_scale: float = 1.0
    timing: dict = field(default_factory=dict)
    # Per frame (in the order given): the best explained share of the frame's
    # variance and the chosen direction's lead over far rivals.
    evidence: dict = field(default_factory=dict)
    message: Optional[str] = None
    # Frames the tracker confirms in sunlight that the capture times and
    # place put at night, and whether the clock was still used to flag
    # night frames (night_by_the_clock; None: no clock).
    clock_contradicted: List[int] = field(default_factory=list)
    clock_trusted: Optional[bool] = None
    # Frames the clock puts at night (their Sun is the ephemeris's).
    clock_night: List[int] = field(default_factory=list)
    # The model refined by the clip (native ModelRefineResult; None: not
    # asked, or see model_refinement_note).
    model_refinement: Any = None
    model_refinement_note: Optional[str] = None
    # The native scene the estimate ran on when the refinement was used.
    refined_scene: Any = None


@dataclass
class _Path:
    """The Sun's path over the run's frames (native solve_sun_path), per
    frame: its grid direction (-1: none), whether a jump comes before it,
    whether its own evidence supports it, and the evidence's figures."""
    direction: List[int] = field(default_factory=list)
    jump_before: List[bool] = field(default_factory=list)
    measured: List[bool] = field(default_factory=list)
    explained: List[float] = field(default_factory=list)
    margin: List[float] = field(default_factory=list)
    significance: List[float] = field(default_factory=list)
    path_margin: List[float] = field(default_factory=list)


def _path_from(solved) -> _Path:
    """The native SunPathResult's per-frame fields (each read once: a bound
    field converts its whole vector on every access)."""
    return _Path(direction=list(solved.direction), jump_before=list(solved.jump_before),
                 measured=list(solved.measured), explained=list(solved.explained),
                 margin=list(solved.margin), significance=list(solved.significance),
                 path_margin=list(solved.path_margin))


def working_factor(width: int) -> int:
    """The power of two a frame `width` wide is divided by to be at most
    WORKING_MAX_WIDTH wide (halvings are the cheap area averages)."""
    factor = 1
    while width > factor * WORKING_MAX_WIDTH:
        factor *= 2
    return factor


def _circle_prior(fit_circle: Callable[..., Any], path: _Path,
                  directions: Sequence[Sequence[float]],
                  times_s: Optional[Sequence[float]], n: int,
                  spacing_deg: float) -> Optional[np.ndarray]:
    """Per frame the Sun on its circle about the pole fitted (fit_circle:
    sun_circle.py's fit_trimmed) to the path's measured frames in
    the frame's segment ((n, 3), NaN rows where no fit holds), or None when the path
    keeps to the fitted circles (nothing to choose again). The grid's
    cells are the path's precision: the inlier limit never falls below a
    grid step."""
    prior = np.full((n, 3), np.nan)
    strayed = False
    for lo, hi in motion.segment_ranges(path.jump_before):
        ks = list(range(lo, hi))
        suns = [directions[path.direction[k]]
                if path.measured[k] and path.direction[k] >= 0 else None for k in ks]
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


def _evidence_support(first: _Path, again: _Path,
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
    for k, margin in enumerate(again.path_margin):
        d1, d2 = first.direction[k], again.direction[k]
        if d1 < 0 or d2 < 0:
            out.append(margin)
        elif angles.angle_between_deg(directions[d1], directions[d2]) <= 1.5 * spacing_deg:
            out.append(min(margin, first.path_margin[k]))
        else:
            out.append(min(margin, FOLLOWED_CONFIDENCE * FULL_CONFIDENCE_MARGIN))
    return out


def _without_dark_segments(bounds: List[int], measured: Sequence[bool],
                           starts: Sequence[int]) -> List[int]:
    """Segment bounds (frame positions, first 0, last n) without the jumps
    that start or end a segment no frame of which has evidence of its own:
    frames without shadows (night, cloud) show no jump of the Sun, they
    belong to the segment around them. The caller's starts (times going
    back) stay."""
    bounds = list(bounds)
    k = 1
    while k < len(bounds) - 1:
        b = bounds[k]
        dark_before = not any(measured[bounds[k - 1]:b])
        dark_after = not any(measured[b:bounds[k + 1]])
        if not starts[b] and (dark_before or dark_after):
            del bounds[k]
            k = max(1, k - 1)
        else:
            k += 1
    return bounds


def _height_unpinned(r: "RawFrame") -> bool:
    """Whether a frame's tracked Sun has an elevation its shadows in view
    do not pin (ELEVATION_PINNED_MAX_DEG)."""
    spread = _height_spread_deg(r)
    return spread is not None and spread > ELEVATION_PINNED_MAX_DEG


def _height_spread_deg(r: "RawFrame") -> Optional[float]:
    """How far a frame's tracked Sun could move in height unnoticed (deg;
    past ELEVATION_PINNED_MAX_DEG, smoothing.UNPINNED_HEIGHT_SPREAD_DEG),
    None where the tracker did not refine it."""
    pinned = getattr(r.tracked, "elevation_pinned_deg", None)
    if not r.refined or pinned is None:
        return None
    return smoothing.UNPINNED_HEIGHT_SPREAD_DEG if pinned > ELEVATION_PINNED_MAX_DEG \
        else float(pinned)


def _azimuth_apart_deg(a, b) -> float:
    """How far apart two Suns' azimuths are (deg, 0-180)."""
    return angles.azimuth_difference_deg(angles.angles_from_sun_in_world(a)[1],
                                         angles.angles_from_sun_in_world(b)[1])


def _contrast(tracked: Any) -> float:
    """The sun/ambient contrast the tracker fitted on a frame (a native
    TrackedFrame), 0 without one."""
    return 0.0 if tracked is None else float(tracked.contrast)


def _frame(read: Union[np.ndarray, str, None]) -> Optional[np.ndarray]:
    return read if isinstance(read, np.ndarray) else None


# (frames, (width, height)) -> (a native FrameSource, {frame: its index})
SourceFn = Callable[[Sequence[int], Tuple[int, int]], Tuple[object, dict]]


def estimate(native, scene, camera, frames: Sequence[int],
             read_gray: Callable[[int], Gray],
             ground_object_ids: Sequence[int], times_s: Optional[Sequence[float]] = None,
             ignore_top_rows: int = 0,
             progress: Optional[Callable[[float], object]] = None,
             stream: Optional[Callable[..., Iterable[Tuple[int, Gray]]]] = None,
             source: Optional[SourceFn] = None,
             fit_circle: Optional[Callable[..., Any]] = None,
             clock_elevation_deg: Optional[Sequence[float]] = None,
             frame_cameras: Optional[Dict[int, Any]] = None,
             refine_model: bool = False) -> WholeClipResult:
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
    the trimmed fit of the Sun's circle (sun_circle.py's
    fit_trimmed; None: the path gets no circle prior and no frame is
    doubted off a circle), passed in, so this controller can be driven with
    stand-ins. `clock_elevation_deg`: per frame, the Sun's elevation the
    ephemeris gives for its capture time and place (None when either is
    unknown); a frame whose Sun is below the horizon has no direct
    sunlight, unless the footage contradicts the times
    (night_by_the_clock). `frame_cameras`: a moving camera, {frame: the
    native camera on it, of `camera`'s size, or where it has no pose None
    or a sentence saying why};
    every frame is then seen from one of them (motion/view_warp.h).
    `refine_model`: the model and a fixed camera refined by the reference
    frames' stable edges first (refine_model_by_clip); the result's
    `model_refinement` says how."""
    return _WholeClip(native, scene, camera, frames, read_gray, ground_object_ids, times_s,
                      ignore_top_rows, progress, stream, source, fit_circle,
                      clock_elevation_deg, frame_cameras, refine_model).run()


class _WholeClip:
    """One whole-clip estimate: its state, and the steps run() takes over it
    in order. Frames are addressed by k, their position in the run's frames
    (capture order)."""

    def __init__(self, native, scene, camera, frames, read_gray, ground_object_ids, times_s,
                 ignore_top_rows, progress, stream, source, fit_circle,
                 clock_elevation_deg=None, frame_cameras=None, refine_model=False):
        self.native, self.scene, self.camera = native, scene, camera
        self.refine_model = refine_model
        self.refine_s: Optional[float] = None  # the model's refinement, when asked
        self.frames, self.n = list(frames), len(frames)
        self.read_gray, self.stream, self.source = read_gray, stream, source
        self.ground_ids, self.times_s = list(ground_object_ids), times_s
        self.progress, self.fit_circle = progress, fit_circle
        self.clock_elevation = None if clock_elevation_deg is None else \
            list(clock_elevation_deg)
        # Whether the times and place may say which frames are night: decided
        # on the first frames' sunlight (night_by_the_clock).
        self.clock_trusted: Optional[bool] = None
        self.result = WholeClipResult()
        # Frames whose evidence the path does not use (found without direct
        # sunlight; run()).
        self.ignored: List[int] = []
        self.t0 = time.perf_counter()
        self.clock: Dict[str, float] = {}   # step -> seconds since t0 at its end
        self.frames_read = 0
        self.tracking_s = 0.0
        self.checked = 0
        # A moving camera's frames are seen from one of its views, the
        # reference (moving_view.py): the estimate runs on them as on a
        # fixed camera's.
        if frame_cameras is not None:
            camera = reference_camera(scene, frame_cameras, self.frames, ground_object_ids)
        # Large frames are reduced (WORKING_MAX_WIDTH): `work` is the camera
        # of the frames the evidence and the tracker see.
        factor = working_factor(camera.width)
        self.factor = factor
        self.work = camera if factor == 1 else camera.resized(camera.width // factor,
                                                              camera.height // factor)
        self.view: Optional[MovingView] = None if frame_cameras is None else \
            MovingView(native, scene, self.work, frame_cameras)
        self.top = -(-ignore_top_rows // factor)
        self.result.tracker_pixel_scale = camera.width / self.work.width
        # Segments the caller knows of: capture times going back.
        self.starts = [0] * self.n
        if times_s is not None:
            for k in range(1, self.n):
                if times_s[k] < times_s[k - 1]:
                    self.starts[k] = 1
        # The caller's starts; self.starts also gets the loops found (run()).
        self.known_starts = list(self.starts)
        # Frames on which the path's Sun casts no shadow of the model on the
        # ground in view (the tracker's word): they cannot show sunlight.
        # Kept over both checks: the path solved again without the dark
        # frames' evidence is checked without asking the tracker everywhere.
        self.no_shadow_in_view: Set[int] = set()
        # A refined Sun further than steer_deg from the path's direction is
        # not believed (the tracker locked onto something else): the pass's
        # own steering limit, also the check's.
        self.pass_options = native.ClipPassOptions()
        self.refine_max_deg = self.pass_options.steer_deg
        self.path_options = native.SunPathOptions()
        if times_s is not None:
            # Known times say where the clip is continuous: the Sun cannot
            # jump between frames minutes apart (time jumps are the segments).
            self.path_options.jump_cost = -1.0

    def run(self) -> WholeClipResult:
        kept = self.sky_table_and_reference()
        if kept is None:
            return self.result
        self.clip_pass(kept)
        if self.times_s is None:
            self.turns_before_the_path()
        if not self.path_and_check():
            return self.result
        # Frames whose evidence steered the path but that show no direct
        # sunlight: the path chosen again without their evidence (with
        # capture times it may not jump, and their ambient shading's high
        # Sun bent it over the lit frames before them).
        ignored = [int(bool(self.path.measured[k]) and r.sunlight != Sunlight.YES)
                   for k, r in enumerate(self.result.frames)]
        # Without times, the clip going back along the Sun's path (a loop)
        # starts a segment, even where the step is one the path allows.
        cuts = [] if self.times_s is not None else untimed.going_back(
            [r.sun_in_world if r.sunlight == Sunlight.YES else None
             for r in self.result.frames], self.starts)
        for k in self.excursions():
            ignored[k] = 1
        if any(ignored) or cuts:
            self.ignored = ignored
            for k in cuts:
                self.starts[k] = 1
            if not self.path_and_check():
                return self.result
            self.mark("dark_again")
        self.release_sky()
        self.doubt_off_circle()
        self.sunlight_against_circle()
        if self.view is not None:
            self.view.less_sure_where_less_is_seen(self.result.frames, self.done.shadow_view)
            self.view.shadows_in_their_frames(self.result.frames)
        self.result.timing = self.timing()
        return self.result

    def turns_before_the_path(self) -> None:
        """Without times, where the clip turns back over the Sun's path
        (untimed.turning_back) a segment starts: found on the pass's own tracked
        Suns, before the path is chosen. Found after it, by untimed.going_back,
        the path and its check run twice (1.8 s more on the speed
        benchmark's 300-frame 1080p ping-pong clip)."""
        for k in untimed.turning_back(self.tracked_suns(), self.starts):
            self.starts[k] = 1

    def tracked_suns(self) -> List[Optional[np.ndarray]]:
        """Per frame the pass's own tracked Sun where its shadows were
        sharp (SUNLIT_MIN_CONTRAST), else None."""
        suns = []
        for k in range(self.n):
            tracked = self.done.track(k)
            sunlit = tracked is not None and tracked.ok and \
                _contrast(tracked) >= SUNLIT_MIN_CONTRAST
            suns.append(tracked.sun_in_world if sunlit else None)
        return suns

    def path_and_check(self) -> bool:
        """The path chosen, its segments checked and each frame's sunlight
        decided; False when no path could be chosen."""
        if not self.solve_path():
            return False
        self.choose_again_under_circle_prior()
        self.segments_and_evidence()
        self.check_segments()
        self.decide_sunlight()
        return True

    # -- steps ---------------------------------------------------------

    def sky_table_and_reference(self) -> Optional[Dict[int, np.ndarray]]:
        """The visibility table over the whole sky, cast while the reference
        frames spread over the clip are decoded ahead; their levels set each
        surface sample's reference. The tracker is made here too, its ground
        map beside the reference decoding (ShadowTracker.prepare). Returns
        the reference frames that are frames of a short run, kept for the
        pass ({frame: gray}), or None when no frame could be read."""
        frames = self.frames
        wanted_reference = [frames[i] for i in notes.spread(list(range(self.n)), REFERENCE_FRAMES)]
        size = (self.work.width, self.work.height)
        # Reference frames need not be exact: the key frame before each
        # asked is read (one decode after a seek). A moving camera's key
        # frame needs a pose of its own, known when every frame of the run
        # has one (a key frame before the run's first frame has none: that
        # reference frame is left out).
        near = self.view is None or frames == list(range(frames[0], frames[-1] + 1))
        reference_frames: Iterable[Tuple[int, Gray]] = (
            ((f, self.reduced(self.read_gray(f), f)) for f in wanted_reference)
            if self.stream is None else self.stream(wanted_reference, near, size))
        independent = getattr(reference_frames, "frames_independent", False)
        refine = self.refine_model and self.view is None
        if self.refine_model and not refine:
            self.result.model_refinement_note = "not refined: the camera moves"
        self.cast_from_model()
        self.mark("table")
        reference: List[Optional[np.ndarray]] = []
        kept: Dict[int, np.ndarray] = {}
        budget = REFERENCE_KEEP_BYTES if self.n <= SHORT_CLIP_FRAMES or independent else 0
        wanted = set(frames)
        with ThreadPoolExecutor(max_workers=1) as beside:
            prepared = beside.submit(self.tracker.prepare)
            for f, image in reference_frames:
                if self.view is not None and self.stream is not None:
                    image = self.view.from_reference_view(f, image)
                gray = _frame(image)
                reference.append(gray)
                if gray is not None and f in wanted and f not in kept and gray.nbytes <= budget:
                    kept[f], budget = gray, budget - gray.nbytes
            if not refine:
                used = self.sky.set_reference(reference)
            prepared.result()
        if refine:
            # Refined on the reference frames once decoded; the table was
            # cast from the user's model meanwhile, and is cast again (with
            # the tracker's map) only where the refined model is used.
            started = time.perf_counter()
            if self.refine_model_by_clip(reference):
                self.cast_from_model()
                self.tracker.prepare()
            used = self.sky.set_reference(reference)
            self.refine_s = time.perf_counter() - started
        self.frames_read = len(reference)
        self.mark("reference")
        if used == 0:
            why = "no frame of the clip could be read"
            self.result.frames = [RawFrame(f, reason=why) for f in frames]
            self.result.message = why
            return None
        return kept

    def cast_from_model(self) -> None:
        """The sky's visibility table and the tracker, from the model."""
        opts = self.native.SkyEvidenceOptions()
        opts.ignore_top_rows = self.top
        self.sky = self.native.SkyEvidence(self.scene, self.work, opts)
        # The tracker's ground map needs the scene and the camera only: it is
        # made on the other core while a movie's key frames decode on one.
        self.tracker = self.native.ShadowTracker(self.scene, self.work, self.ground_ids,
                                                 ignore_top_rows=self.top)

    def refine_model_by_clip(self, grays: List[Optional[np.ndarray]]) -> bool:
        """The hand-made model and the camera refined so that the model's
        edges fall on the edges that stay put over the reference frames
        (native refine_model); the estimate then runs on the refined model.
        A fixed camera's only (a moving camera's views are solved). Returns
        whether the estimate is to use the refined model."""
        native = self.native
        edges = native.stable_edges(grays, options=native.StableEdgesOptions(
            ignore_top_rows=self.top))
        if edges is None:
            self.result.model_refinement_note = "not refined: fewer than two frames to see it in"
            return False
        refined = native.refine_model(self.scene, self.work, self.ground_ids, edges)
        self.result.model_refinement = refined
        if refined.status != native.ModelRefineStatus.REFINED:
            return False
        self.scene = self.result.refined_scene = native.corrected_scene(self.scene, refined)
        self.work = native.corrected_camera(self.work, refined.camera)
        return True

    def clip_pass(self, kept: Dict[int, np.ndarray]) -> None:
        """The pass over the clip, in native code without Python's lock:
        evidence for every frame, and the tracker following the shadows on
        the same frames (checked against the path afterwards)."""
        native, frames = self.native, self.frames
        self.directions = [tuple(d) for d in self.sky.directions.tolist()]
        self.spacing_deg = self.sky.spacing_deg
        rest = [f for f in frames if f not in kept]
        if self.source is None:
            frame_source = native.FrameList([(i, self.reduced(self.read_gray(f), f))
                                             for i, f in enumerate(rest)])
            index_of = {f: i for i, f in enumerate(rest)}
        else:
            frame_source, index_of = self.source(rest, (self.work.width, self.work.height))
            if self.view is not None:
                frame_source = self.view.source(frame_source, index_of)
        progress = self.progress
        self.done = native.run_clip_pass(
            frame_source, [index_of.get(f, -1) if f not in kept else -1 for f in frames],
            [kept.get(f) for f in frames], self.starts, self.work, self.sky, self.tracker,
            self.pass_options, lambda x: progress is None or progress(0.8 * x) is not False)
        if self.done.cancelled:
            raise Cancelled("cancelled")
        self.frames_read += len(rest)
        self.tracking_s += self.done.tracking_seconds
        # Per frame, in native memory (done.reason(k), done.track(k)): Python
        # objects for every frame would cost kilobytes a frame on long clips.
        usable_status = (int(native.FrameEvidenceStatus.OK),
                         int(native.FrameEvidenceStatus.NO_SHADOWS))
        self.usable = np.isin(self.done.status, usable_status)
        # A moving camera's frame that does not see where the shadows fall
        # cannot say there is no sunlight (decide_sunlight).
        self.out_of_view = np.asarray(self.done.shadow_view) < SHADOWS_IN_VIEW
        self.mark("evidence")

    def solve_path(self) -> bool:
        """The Sun's path chosen globally over the sky's evidence."""
        solved = self.native.solve_sun_path(self.sky, self.times_list(), self.starts,
                                            self.path_options, None, self.ignored)
        if solved.status != self.native.SunPathStatus.SUCCESS:
            self.result.frames = [
                RawFrame(f, reason=solved.message or self.done.reason(k) or "no evidence")
                for k, f in enumerate(self.frames)]
            self.result.message = solved.message
            return False
        self.path = _path_from(solved)
        self.mark("path")
        return True

    def choose_again_under_circle_prior(self) -> None:
        """Where the path strayed from its segments' Sun circles, the path
        chosen again with the circle as a prior (PRIOR_* above)."""
        prior = None if self.fit_circle is None else _circle_prior(
            self.fit_circle, self.path, self.directions, self.times_s, self.n, self.spacing_deg)
        self.path_prior = prior is not None
        self.mark("prior")
        if prior is not None:
            again = self.native.solve_sun_path(self.sky, self.times_list(), self.starts,
                                               self.path_options, prior, self.ignored)
            if again.status == self.native.SunPathStatus.SUCCESS:
                path = _path_from(again)
                path.path_margin = _evidence_support(self.path, path, self.directions,
                                                     self.spacing_deg)
                self.path = path
        self.mark("path_again")

    def release_sky(self) -> None:
        """The sky's table and every frame's kept costs (3 kB a frame) are
        done with: the check needs the path only."""
        self.sky_sizes = {"samples": self.sky.num_samples,
                          "band_entries": self.sky.band_entries}
        del self.sky

    def segments_and_evidence(self) -> None:
        """The path's segments, its unexplained jumps, the per-frame
        evidence figures and the best-supported frame."""
        path, frames, n = self.path, self.frames, self.n
        self.bounds = _without_dark_segments(
            motion.segment_bounds(path.jump_before), path.measured, self.starts)
        self.result.jumps = self.unexplained_jumps()
        d = self.directions
        self.result.evidence = {
            "explained": [round(v, 3) for v in path.explained],
            "margin": [round(v, 2) for v in path.margin],
            "significance": [round(v, 1) for v in path.significance],
            "path_margin": [round(v, 1) for v in path.path_margin],
            "path_sun_in_world": [[round(v, 5) for v in d[k]] for k in path.direction]}
        best = max(range(n), key=lambda k: (path.measured[k], path.margin[k]))
        self.result.anchor = frames[best] if path.measured[best] else None

    def check_segments(self) -> None:
        """Each segment against the path, forward from its first measured
        frame, then back from it to the frames before. A frame the pass
        tracked to a Sun near the path keeps it; the others are read again
        and refined around the path's direction by the pass's tracker (or,
        where it never started, one started on the segment's first measured
        frame)."""
        measured, frames = self.path.measured, self.frames
        self.result.frames, self.result.segments = [], []
        self.before, self.after = [0] * self.n, [0] * self.n  # nearest measured frames
        self.tracker_run: Optional[Tuple[int, int]] = None  # (segment, direction) followed
        self.tracker_last: Optional[int] = None             # the tracker's last frame
        for s in range(len(self.bounds) - 1):
            lo, hi = self.bounds[s], self.bounds[s + 1]
            self.result.segments.append(frames[lo:hi])
            seg = [RawFrame(frames[k], segment=s, measured=measured[k]) for k in range(lo, hi)]
            self.result.frames.extend(seg)
            for k in range(lo, hi):
                seg[k - lo].reason = (
                    "no shadow evidence on this frame or around it in its segment"
                    if self.usable[k] else self.done.reason(k) or "no evidence on this frame")
            first = next((k for k in range(lo, hi) if measured[k]), None)
            last = next((k for k in range(hi - 1, lo - 1, -1) if measured[k]), None)
            if first is None or last is None:
                continue
            for k in range(first, last + 1):
                self.before[k] = k if measured[k] else self.before[k - 1]
            for k in range(last, first - 1, -1):
                self.after[k] = k if measured[k] else self.after[k + 1]
            for order in (range(first, hi), range(first - 1, lo - 1, -1)):
                follow = True
                for k in order:
                    if not self.usable[k]:
                        continue
                    beyond = not first <= k <= last
                    if beyond and not follow:
                        continue  # lost past the evidence: nothing to carry
                    follow = self.refine(k, seg[k - lo], (s, order.step), first, beyond,
                                         last if k > last else first, order.step)
        self.mark("checked")

    def doubt_off_circle(self) -> None:
        """Each segment's Sun circle (doubt_off_circle), on its frames in
        frame order, as they are smoothed."""
        for r in self.result.frames:
            r.on_circle = r.confidence
        if self.fit_circle is None:
            return
        seconds = self.times_s
        paced: Optional[List[float]] = None  # the pace clock, made when first asked
        for lo, hi in zip(self.bounds[:-1], self.bounds[1:]):
            at = {f: k for k, f in enumerate(self.frames[lo:hi], start=lo)}
            seg = sorted(self.result.frames[lo:hi], key=lambda r: r.frame)
            t = [seconds[at[r.frame]] if seconds is not None else float(r.frame) for r in seg]
            circle = _segment_circle(seg, t, seconds is not None, self.fit_circle)
            unlit = _unlit_by(seg, circle)
            if seconds is None and unlit >= PACE_SWITCH_FRAMES:
                # The frame numbers leave Suns far off the circle: the Sun's
                # own pace, where it changes, and where it leaves at most
                # half as many off.
                if paced is None:
                    paced = untimed.pace_clock(self.tracked_suns(), self.frames,
                                               self.starts) or []
                if paced:
                    other = _segment_circle(seg, [paced[at[r.frame]] for r in seg], False,
                                            self.fit_circle)
                    if other is not None and 2 * _unlit_by(seg, other) <= unlit:
                        circle = other
                        self.result.paced.update({r.frame: paced[at[r.frame]] for r in seg})
            if circle is not None:
                _doubt_by(seg, *circle)

    def decide_sunlight(self) -> None:
        """Direct sunlight per frame (SUNLIT_MIN_CONTRAST and
        SUNLIT_HAZY_CONTRAST above): frames without it keep no Sun of their
        own and confidence 0, and a segment of such frames joins the one
        before it (or after)."""
        frames = self.result.frames
        contrast = [_contrast(r.tracked) if r.sun_in_world is not None and r.refined else 0.0
                    for r in frames]
        tracked = [c >= SUNLIT_MIN_CONTRAST for c in contrast]
        explained = self.path.explained
        shares = sorted(explained[k] for k, ok in enumerate(tracked) if ok)
        typical = shares[len(shares) // 2] if shares else 0.0
        for k, r in enumerate(frames):
            # The tracker's fit, else (no ground to track on, or its fit
            # failed) the sky's evidence explaining the frame as well as on
            # the frames the tracker confirmed.
            sunlit = tracked[k] or (r.sun_in_world is not None and r.measured and
                                    explained[k] >= SUNLIT_EXPLAINED_SHARE * typical)
            r.sunlight = Sunlight.YES if sunlit else \
                Sunlight.NO if self.usable[k] and not self.out_of_view[k] else Sunlight.UNKNOWN
            r.shadows_in_view = sunlit or not self.out_of_view[k]
            if not sunlit and self.out_of_view[k]:
                r.reason = SHADOWS_OUT_OF_VIEW
            elif not sunlit and k in self.no_shadow_in_view:
                # Shadows on walls alone, or a high Sun's hidden under their
                # casters: the ground in view shows none whatever the light.
                r.sunlight, r.shadows_in_view, r.reason = \
                    Sunlight.UNKNOWN, False, NO_SHADOW_IN_VIEW
        night = set(self.night_by_the_clock(tracked))
        for k in night:
            frames[k].sunlight = Sunlight.NO
        bounds = _without_dark_segments(
            self.bounds, [r.sunlight == Sunlight.YES and self.path.margin[k] >= SEGMENT_MIN_MARGIN
                          for k, r in enumerate(frames)], self.starts)
        if bounds != self.bounds:
            self.bounds = bounds
            self.result.jumps = self.unexplained_jumps()
            self.result.segments = [self.frames[lo:hi] for lo, hi in zip(bounds, bounds[1:])]
            for s, (lo, hi) in enumerate(zip(bounds, bounds[1:])):
                for r in frames[lo:hi]:
                    r.segment = s
        for lo, hi in zip(self.bounds[:-1], self.bounds[1:]):
            if any(tracked[lo:hi]):
                for k in range(lo, hi):  # a hazy Sun in a segment that shows it
                    if frames[k].sunlight == Sunlight.NO and k not in night and \
                            contrast[k] >= SUNLIT_HAZY_CONTRAST:
                        frames[k].sunlight = Sunlight.YES
            if not any(r.sunlight == Sunlight.YES for r in frames[lo:hi]):
                for r in frames[lo:hi]:  # nothing in the clip shows shadows here
                    r.sunlight = Sunlight.UNKNOWN
        for r in frames:
            if r.sunlight != Sunlight.YES:
                self.unlit(r, "no direct sunlight on this frame"
                           if r.sunlight == Sunlight.NO else r.reason)
        self.anchor_in_sunlight()

    def night_by_the_clock(self, tracked: Optional[Sequence[bool]] = None) -> List[int]:
        """Frames the ephemeris puts below the horizon at their capture time
        and place. Decided once, on the frames the tracker confirms in
        sunlight (`tracked`): those the clock puts further below than
        CLOCK_NIGHT_SLACK_DEG contradict it (result.clock_contradicted);
        when they are most of them (CLOCK_WRONG), the times (their zone)
        or the place are wrong, not the footage, and the clock says nothing
        (result.clock_trusted)."""
        elevation = self.clock_elevation
        if elevation is None:
            return []
        if self.clock_trusted is None and tracked is not None:
            lit = [k for k, ok in enumerate(tracked) if ok]
            against = [self.frames[k] for k in lit if elevation[k] < -CLOCK_NIGHT_SLACK_DEG]
            self.clock_trusted = not (len(against) >= CLOCK_WRONG[0] and
                                      len(against) > CLOCK_WRONG[1] * len(lit))
            self.result.clock_trusted = self.clock_trusted
            self.result.clock_contradicted = against
        return [k for k, e in enumerate(elevation) if e < 0.0] if self.clock_trusted else []

    def sunlight_against_circle(self) -> None:
        """A Sun below the horizon (the frame's own, or its segment's
        circle's) lights no ground: whatever the frame shows, it has no
        direct sunlight. A Sun far off its circle (OFF_CIRCLE_UNLIT_DEG;
        a hazy Sun's faint shadows, CIRCLE_DOUBT_DEG) is not the Sun's."""
        night = set(self.night_by_the_clock())
        self.result.clock_night = [self.frames[k] for k in sorted(night)]
        for k, r in enumerate(self.result.frames):
            if k in night or any(sun is not None and sun[2] <= 0.0
                                 for sun in (r.sun_in_world, r.circle_in_world)):
                r.sunlight = Sunlight.NO
                self.unlit(r, "the Sun is below the horizon here")
            elif r.sunlight == Sunlight.YES and _not_the_suns(r, r.circle_in_world):
                r.sunlight = Sunlight.UNKNOWN
                self.unlit(r, "the shadows on this frame are not where the Sun's path puts "
                              "them")
        self.anchor_in_sunlight()

    def excursions(self) -> List[int]:
        """Without times, the frame positions of each segment the path
        jumped to and back from (EXCURSION_SIDE_FRAMES above): the Suns of the
        segments either side lie on one circle at one pace, so the clip
        went on through it, and most of its own Suns are far off that
        circle. Its evidence is then not the Sun's."""
        if self.times_s is not None or self.fit_circle is None:
            return []
        frames, b = self.result.frames, self.bounds
        out: List[int] = []
        for s in range(1, len(b) - 2):
            lo, hi = b[s], b[s + 1]
            if self.known_starts[lo] or self.known_starts[hi]:
                continue
            span = range(b[s - 1], b[s + 2])
            lit = [k for k in span if frames[k].sunlight == Sunlight.YES and
                   frames[k].sun_in_world is not None]
            before = [k for k in lit if k < lo]
            after = [k for k in lit if k >= hi]
            inside = [k for k in lit if lo <= k < hi]
            if min(len(before), len(after)) < EXCURSION_SIDE_FRAMES or not inside:
                continue
            around = set(before + after)
            fit = self.fit_circle(
                [float(self.frames[k]) for k in span],
                [frames[k].sun_in_world if k in around else None for k in span],
                CIRCLE_INLIER_FLOOR_DEG,
                [max(frames[k].confidence, 1e-3) for k in span], times_are_seconds=False)
            if not fit.success:
                continue

            def far(ks: List[int]) -> int:
                return sum(angles.angle_between_deg(frames[k].sun_in_world,
                                                    fit.sun_in_world[k - span.start])
                           > OFF_CIRCLE_UNLIT_DEG for k in ks)
            # Each side on it, not the fit's inliers alone: a long side makes
            # most of those by itself (a clip played forward, back and forward
            # again: a 90-frame leg and a 20-frame one, 80 deg off the first's
            # circle, left the 89 frames between without a Sun).
            if any(2 * far(side) >= len(side) for side in (before, after)):
                continue
            if 2 * far(inside) > len(inside):
                out.extend(range(lo, hi))
        return out

    def unexplained_jumps(self) -> List[int]:
        """Frames after a segment bound the caller's times do not explain."""
        return [self.frames[k] for k in self.bounds[1:-1] if not self.known_starts[k]]

    def anchor_in_sunlight(self) -> None:
        """The best-supported frame among those with direct sunlight."""
        frames = self.result.frames
        if self.result.anchor is None or \
                frames[self.frames.index(self.result.anchor)].sunlight == Sunlight.YES:
            return
        lit = [k for k, r in enumerate(frames) if r.sunlight == Sunlight.YES]
        best = max(lit, key=lambda k: self.path.margin[k], default=None)
        self.result.anchor = None if best is None else self.frames[best]

    @staticmethod
    def unlit(r: RawFrame, reason: Optional[str]) -> None:
        r.sun_in_world, r.refined, r.tracked = None, False, None
        r.confidence = r.on_circle = 0.0
        r.reason = reason

    # -- the check's parts -----------------------------------------------

    def refine(self, k: int, raw: RawFrame, run: Tuple[int, int], first: int, beyond: bool,
               anchor: int, step: int) -> bool:
        """Refines frame k into `raw`; returns whether the tracker holds.
        Beyond the measured frames the path has no evidence of its own: the
        result is checked against the nearest measured frame's Sun, as far
        as the Sun can move from it."""
        path = self.path
        self.checked += 1
        self.tick(0.8 + 0.2 * self.checked / self.n)
        d = self.directions[path.direction[anchor if beyond else k]]
        limit = self.refine_max_deg + (self.motion_deg(k, anchor) if beyond else 0.0)
        refined = self.passed_track(k, d, limit, beyond)
        if refined is None and self.restart(run, first):
            refined = self.track_again(k, d, limit, step)
        support = max(0.0, min(1.0, path.path_margin[k] / FULL_CONFIDENCE_MARGIN))
        measured = path.measured[k]
        if refined is not None:
            raw.sun_in_world = np.asarray(refined.sun_in_world, dtype=float)
            raw.refined, raw.tracked, raw.reason = True, refined, None
            if measured:
                raw.confidence = refined.confidence * support
                if angles.angle_between_deg(refined.sun_in_world, d) > AGREE_DEG:
                    raw.confidence *= 0.5
            else:
                raw.confidence = refined.confidence * (
                    FOLLOWED_BEYOND_CONFIDENCE if beyond else FOLLOWED_CONFIDENCE)
        elif beyond:
            raw.reason = "shadow lost beyond the frames with shadow evidence"
        else:
            raw.sun_in_world = np.asarray(d, dtype=float)
            raw.confidence = (0.5 * support) if measured else CARRIED_CONFIDENCE
            # Its Sun is the path's grid cell (a degree or two wide), not
            # the evidence-less frame the reason first said.
            raw.reason = PATH_CELL_ONLY
        return refined is not None

    def passed_track(self, k: int, d, limit: float, beyond: bool):
        """The pass's own tracked Sun on frame k, if it is where the path
        (or, between measured frames, the frames around) allows."""
        refined = self.done.track(k)
        if refined is None:
            return None
        off = angles.angle_between_deg(refined.sun_in_world, d)
        if not self.path.measured[k] and not beyond:
            return refined if off <= limit or self.between(k, refined.sun_in_world) else None
        return refined if off <= (AGREE_DEG if self.path.measured[k] else limit) else None

    def track_again(self, k: int, d, limit: float, step: int):
        """Frame k read again and tracked: the tracker's own prediction (the
        last refined Suns' motion) is finer than the path's grid cell when it
        has just followed the neighbouring frame; the path's direction is the
        check, and the fallback when the tracker has drifted."""
        gray = self.read_again(k)
        own = self.tracker_last == k - step
        for attempt in ("own", "path") if own else ("path",):
            if gray is None:
                break
            r = self.tracker.track(gray) if attempt == "own" else \
                self.tracker.track_toward(gray, d)
            self.tracking_s += r.seconds
            self.tracker_last = k
            if r.ok and angles.angle_between_deg(r.sun_in_world, d) <= limit:
                return r
            if attempt == "path" and r.status == self.native.TrackedFrameStatus.no_shadow_in_view:
                self.no_shadow_in_view.add(k)
        return None

    def restart(self, run: Tuple[int, int], first: int) -> bool:
        """A tracker for the frames read again: the pass's own, or, when it
        never started there, one started on frame `first` under the path's
        Sun, once per run (segment, direction)."""
        if self.tracker_run == run or self.done.tracker_started:
            self.tracker_run = run
            return True
        gray = self.read_again(first)
        ok_start = gray is not None and self.native.start_tracker(
            self.tracker, gray, self.directions[self.path.direction[first]],
            self.refine_max_deg)[0]
        self.tracker_run, self.tracker_last = run, first
        return ok_start

    def between(self, k: int, sun_in_world) -> bool:
        """Whether a Sun on a frame without evidence of its own, between
        frames with evidence, is where the Sun can be from both of them: the
        path carries such frames on a grid cell that lags the Sun, so the
        tracker's own Sun is checked against the measured frames instead."""
        for j in (self.before[k], self.after[k]):
            d = self.directions[self.path.direction[j]]
            if angles.angle_between_deg(sun_in_world, d) > \
                    self.refine_max_deg + self.motion_deg(k, j):
                return False
        return True

    # -- small helpers -----------------------------------------------------

    def read_again(self, k: int) -> Optional[np.ndarray]:
        """Frame k at the working size: as the pass kept it (the check was
        likely to want it), else read again."""
        gray = self.done.take_kept(k)
        if gray is not None:
            return gray
        self.frames_read += 1
        f = self.frames[k]
        return _frame(self.reduced(self.read_gray(f), f))

    def reduced(self, image: Gray, f: int) -> Gray:
        """Frame f as read by read_gray, at the working size (and seen from
        the reference view when the camera moves)."""
        gray = _frame(image)
        if gray is None:
            return image
        if gray.shape != (self.work.height, self.work.width):
            gray = self.native.resized_gray(gray, self.work.width, self.work.height)
        return gray if self.view is None else self.view.from_reference_view(f, gray)

    def motion_deg(self, k: int, j: int) -> float:
        return motion.sun_motion_bound_deg(k, j, self.times_s, self.path_options)

    def times_list(self) -> List[float]:
        return [] if self.times_s is None else list(self.times_s)

    def tick(self, fraction: float) -> None:
        if self.progress is not None and self.progress(fraction) is False:
            raise Cancelled("cancelled")

    def mark(self, step: str) -> None:
        """The end of a step (the first time it ends: the steps run again
        without the dark frames' evidence are timed as dark_again)."""
        self.clock.setdefault(step, time.perf_counter() - self.t0)

    def timing(self) -> dict:
        c, n = self.clock, self.n
        refine = self.refine_s or 0.0
        return {"table_s": c["table"], "reference_s": c["reference"] - c["table"] - refine,
                **({"refine_s": refine} if self.refine_s is not None else {}),
                "evidence_ms_per_frame": 1000.0 * (c["evidence"] - c["reference"]) / max(1, n),
                "tracking_ms_per_frame": 1000.0 * self.tracking_s / max(1, n),
                "tracker_start_s": self.done.start_seconds,
                "path_s": c["path"] - c["evidence"], "prior_s": c["prior"] - c["path"],
                "path_again_s": c["path_again"] - c["prior"], "path_prior": self.path_prior,
                "check_s": c["checked"] - c["path_again"],
                "dark_again_s": c["dark_again"] - c["checked"] if "dark_again" in c else 0.0,
                "frames_read": self.frames_read, "frames": n,
                "total_s": time.perf_counter() - self.t0, **self.sky_sizes,
                "directions": len(self.directions), "spacing_deg": self.spacing_deg,
                **({"warp_s": self.view.seconds()} if self.view is not None else {})}


def doubt_off_circle(segment: Sequence[RawFrame], t: Sequence[float], times_are_seconds: bool,
                     fit_circle: Callable[..., Any]) -> None:
    """A segment's Sun circle about the pole, fitted (trimmed) to its
    confident raw Suns (t: their times, seconds or frame numbers), kept with
    each of its frames; a frame whose Sun is off it by more than
    CIRCLE_DOUBT_DEG keeps less confidence (on_circle), with the square of
    the ratio."""
    circle = _segment_circle(segment, t, times_are_seconds, fit_circle)
    if circle is not None:
        _doubt_by(segment, *circle)


def _segment_circle(segment: Sequence[RawFrame], t: Sequence[float], times_are_seconds: bool,
                    fit_circle: Callable[..., Any]) -> Optional[Tuple[Any, bool]]:
    """doubt_off_circle's fit and whether the pinned Suns alone made it;
    None when it failed."""
    suns = [r.sun_in_world if r.sun_in_world is not None and r.confidence >= 0.3 else None
            for r in segment]
    # The frames whose shadows pin the Sun's height set the circle when
    # there are enough of them for a fit (ELEVATION_PINNED_MAX_DEG).
    pinned = [None if sun is None or _height_unpinned(r) else sun
              for sun, r in zip(suns, segment)]
    by_pinned = sum(sun is not None for sun in pinned) >= sun_circle.min_frames()
    fit = fit_circle(list(t), pinned if by_pinned else suns, CIRCLE_INLIER_FLOOR_DEG,
                     [max(r.confidence, 1e-3) for r in segment],
                     times_are_seconds=times_are_seconds)
    return (fit, by_pinned) if fit.success else None


def _not_the_suns(r: "RawFrame", circle_in_world) -> bool:
    """Whether a frame's Sun is so far off its circle's (OFF_CIRCLE_UNLIT_DEG;
    a hazy Sun's faint shadows, CIRCLE_DOUBT_DEG) that its shadows are taken
    for shadows that are not the Sun's."""
    if r.sun_in_world is None or circle_in_world is None:
        return False
    hazy = r.tracked is not None and _contrast(r.tracked) < SUNLIT_MIN_CONTRAST
    return angles.angle_between_deg(r.sun_in_world, circle_in_world) > (
        CIRCLE_DOUBT_DEG if hazy else OFF_CIRCLE_UNLIT_DEG)


def _unlit_by(segment: Sequence[RawFrame], circle: Optional[Tuple[Any, bool]]) -> int:
    """How many of the segment's Suns the circle would take for shadows that
    are not the Sun's (_not_the_suns, as sunlight_against_circle does)."""
    if circle is None:
        return 0
    return sum(_not_the_suns(r, circle[0].sun_in_world[i]) for i, r in enumerate(segment))


def _doubt_by(segment: Sequence[RawFrame], fit: Any, by_pinned: bool) -> None:
    """doubt_off_circle's circle kept with each frame, and the doubt."""
    for i, r in enumerate(segment):
        r.circle_in_world = np.asarray(fit.sun_in_world[i], dtype=float)
        r.circle_checked = by_pinned  # RawFrame.circle_checked
        r.on_circle = r.confidence
        if r.sun_in_world is None:
            continue
        off = angles.angle_between_deg(r.sun_in_world, r.circle_in_world)
        if off > OFF_CIRCLE_UNLIT_DEG and by_pinned and _height_unpinned(r) and \
                _azimuth_apart_deg(r.sun_in_world, r.circle_in_world) <= CIRCLE_DOUBT_DEG:
            # Its shadows point where the circle's Sun puts them and cannot
            # tell its height: the circle's Sun it is, doubted (not taken
            # for shadows that are not the Sun's: sunlight_against_circle).
            r.sun_in_world = r.circle_in_world
            r.on_circle = min(r.confidence, UNPINNED_SUPPORT)
        elif off > CIRCLE_DOUBT_DEG:
            r.on_circle = r.confidence * (CIRCLE_DOUBT_DEG / off) ** 2


class _ClipReads:
    """The clip's frames as the whole-clip estimate asks for them: the
    reference frames and the pass streamed by native readers, the few
    frames read again one at a time. The reference frames also come in
    colour, at the unmodelled-shadow note's size, for the clip's
    shadow-free background (`samples`), when `colour`: the note compares
    frames pixel by pixel, so a moving camera's are not kept."""

    def __init__(self, native, clip_path: str, source, camera, gamma: float,
                 colour: bool = True):
        self.native, self.clip_path, self.source = native, clip_path, source
        self.camera, self.gamma, self.colour = camera, gamma, colour
        self.stride = notes.note_stride(camera)
        self.samples: Dict[int, np.ndarray] = {}
        self.pass_stream: Any = None

    def read_gray(self, f: int) -> Gray:
        try:
            bgr = self.source.read(f)
        except StopIteration:
            return "the clip ended before this frame"
        if bgr is None:
            return self.source.why_not()
        return (clip_frames.wrong_size(bgr, self.camera)
                or self.native.to_linear_gray(bgr, self.gamma))

    def open_stream(self, fs: Sequence[int], near: bool, size: Tuple[int, int]):
        native, camera = self.native, self.camera
        try:
            frame_stream = native.FrameStream(
                self.clip_path, [f - self.source.start for f in fs],
                native.FrameStreamOptions(gamma=self.gamma, near=near,
                                          keep_bgr=near and self.colour,
                                          width=size[0], height=size[1],
                                          bgr_width=-(-camera.width // self.stride),
                                          bgr_height=-(-camera.height // self.stride)))
        except ValueError as e:
            raise EstimateError(f"cannot read the clip: {e}")
        # The frames stream reduced to the estimate's working size: a clip
        # of another size than the camera's would be reduced to it silently.
        clip_frames.check_clip_size(frame_stream.width, frame_stream.height, camera)
        return frame_stream

    def stream(self, fs: Sequence[int], near: bool, size: Tuple[int, int]) -> "_Streamed":
        """The frames in order at `size`, decoded ahead on a native thread
        (started now, before the first is asked for)."""
        return _Streamed(self, self.open_stream(fs, near, size), near)

    def frame_source(self, fs: Sequence[int], size: Tuple[int, int]):
        """The pass's frames at `size`: a native stream, and the index it
        reports for each frame (its 0-based index in the clip)."""
        self.pass_stream = self.open_stream(fs, False, size)
        return self.pass_stream, {f: f - self.source.start for f in fs}

    def streamed(self, frame_stream, near: bool):
        start = self.source.start
        past_end = self.native.StreamedFrameStatus.past_end
        for got in frame_stream:
            f = got.index + start
            if got.gray is not None:
                if near and self.colour:
                    self.samples[f] = got.bgr
                yield f, got.gray
            elif got.status == past_end:
                yield f, "the clip ended before this frame"
            else:
                yield f, got.message or "frame not decodable"

    def wait_seconds(self) -> float:
        return 0.0 if self.pass_stream is None else self.pass_stream.wait_seconds


class _Streamed:
    """A native stream's frames as (frame, gray or why not), in order, and
    whether the clip's frames decode on their own (frames_independent)."""

    def __init__(self, reads: _ClipReads, frame_stream, near: bool):
        self.frames_independent = bool(frame_stream.frames_independent)
        self._frames = reads.streamed(frame_stream, near)

    def __iter__(self):
        return self._frames


def run(scene, camera, clip_path: str, source, frames: Sequence[int], visit: Sequence[int],
        times, options, track: trackfile.Track, progress, t0: float,
        frame_cameras: Optional[Dict[int, Any]] = None) -> trackfile.Track:
    """The default method: the Sun over the whole clip at once (estimate),
    the unmodelled-shadow note on its best-supported frame, then smoothing
    per segment (finish.py)."""
    native = native_loader.require()
    north = options.north_offset_deg
    reads = _ClipReads(native, clip_path, source, camera, gamma(options.method),
                       colour=frame_cameras is None)
    seconds, elevation, ephemeris = None, None, {}
    if times is not None:
        by_time = dict(zip(frames, clock.seconds_since(times)))
        seconds = [by_time[f] for f in visit]
        if options.latitude_deg is not None and options.longitude_deg is not None:
            at = dict(zip(frames, times))
            ephemeris = {f: finish.ephemeris_sun(native, at[f], options.latitude_deg,
                                                 options.longitude_deg) for f in visit}
            elevation = [90.0 - ephemeris[f][0] for f in visit]
    result = estimate(
        native, scene, camera, visit, reads.read_gray, options.ground_object_ids, times_s=seconds,
        ignore_top_rows=options.ignore_top_rows,
        progress=None if progress is None else (lambda x: progress(0.95 * x)),
        stream=reads.stream, source=reads.frame_source, fit_circle=sun_circle.fit_trimmed,
        clock_elevation_deg=elevation, frame_cameras=frame_cameras,
        refine_model=options.refine_model)
    if result.clock_contradicted:
        shown = ", ".join(map(str, sorted(result.clock_contradicted)[:5]))
        n = len(result.clock_contradicted)
        if result.clock_trusted:
            track.report("times", trackfile.ProblemKind.HINT,
                         f"the frames' times and the place put the Sun below the horizon on "
                         f"{n} frame(s) whose shadows look sunlit ({shown}): taken as night "
                         f"(street lights cast hard shadows too); if they are day, check that "
                         f"the times are UTC (or carry their zone)")
        else:
            track.report("times", trackfile.ProblemKind.HINT,
                         f"the frames' times and the place put the Sun below the horizon on "
                         f"{n} frame(s) that show its shadows (e.g. {shown}): check that the "
                         f"times are UTC (or carry their zone) and the latitude and longitude; "
                         f"night frames were found from the footage alone")
    track.method["initial"] = track.method["tracking"] = "whole_clip"
    by_frame = {r.frame: r for r in result.frames}
    night = set(result.clock_night)
    by_clock = _clock_suns(ephemeris, result.clock_trusted)
    raws = [_raw_sun(by_frame[f], north, by_clock.get(f), f in night) for f in frames]
    circle = {k: _geographic(by_frame[f].circle_in_world, north) for k, f in enumerate(frames)
              if by_frame[f].circle_in_world is not None}
    if result.anchor is not None:
        a = by_frame[result.anchor]
        z, az = _geographic(a.sun_in_world, north)
        track.initial = {"frame": a.frame, "zenith_deg": z, "azimuth_deg": az,
                         "residual": None, "confidence": a.confidence,
                         "seconds": result.timing.get("table_s", 0.0)
                         + result.timing.get("reference_s", 0.0),
                         "message": "the best-supported frame of the whole-clip path"}
        if result.refined_scene is not None:
            # Unmodelled shadows are looked for against the model the
            # estimate ran on.
            scene = result.refined_scene
            camera = native.corrected_camera(camera, result.model_refinement.camera)
        _note(track, scene, camera, reads.samples, by_frame, options)
    elif result.message:
        track.report("estimate", trackfile.ProblemKind.FAILED, result.message)
    if options.refine_model:
        refinement = track.extra["model_refinement"] = _refinement(native, result)
        if refinement["used"]:  # else the model is as the user made it: nothing to say
            track.report("model_refinement", trackfile.ProblemKind.HINT,
                         _refinement_said(refinement))
    track.extra["segments"] = [[seg[0], seg[-1]] for seg in result.segments]
    if result.evidence:
        track.extra["evidence"] = dict(result.evidence, frames=list(visit))
    if result.jumps:
        track.extra["jumps"] = result.jumps
    finish.finish(native, track, raws, options, times, progress, result.segments,
                  result.tracker_pixel_scale, circle, result.paced)
    track.extra["timing"] = dict(result.timing, decode_wait_s=reads.wait_seconds(),
                                 total_s=time.perf_counter() - t0)
    return track


def _refinement(native, result: WholeClipResult) -> dict:
    """The track's account of the model refined by the clip: whether the
    estimate used it, and each object's and the camera's correction."""
    r = result.model_refinement
    if r is None:
        return {"used": False, "message": result.model_refinement_note or "not refined"}
    return {
        "used": r.status == native.ModelRefineStatus.REFINED,
        "status": r.status.name.lower(), "message": r.message,
        "camera": {"turn_deg": r.camera.turn_deg, "focal_factor": r.camera.focal_factor,
                   "turn_in_world": np.asarray(r.camera.turn_in_world).tolist()},
        "objects": [{"object_id": o.object_id, "refined": o.refined, "points": o.points,
                     "move_in_world_m": np.asarray(o.move_in_world_m).tolist(),
                     "turn_deg": o.turn_deg, "scale": np.asarray(o.scale).tolist(),
                     "pivot_in_world": np.asarray(o.pivot_in_world).tolist(),
                     "axis_in_world": np.asarray(o.axis_in_world).tolist(),
                     "transform": np.asarray(o.transform()).tolist(),
                     "distance_before_px": o.distance_before_px,
                     "distance_after_px": o.distance_after_px} for o in r.objects]}


def _refinement_said(refinement: dict) -> str:
    """One sentence for the user on what the clip changed in the model the
    estimate used (refinement["used"]; run() says nothing otherwise)."""
    moved = [o for o in refinement["objects"] if o["refined"]]
    move = max(float(np.hypot(*o["move_in_world_m"])) for o in moved)
    turn = max(abs(o["turn_deg"]) for o in moved)
    scale = max(abs(s - 1.0) for o in moved for s in o["scale"])
    cam = refinement["camera"]
    return (f"the clip refined the model: {len(moved)} of {len(refinement['objects'])} "
            f"object(s) in view moved by up to {move:.2f} m, turned by up to {turn:.1f} deg "
            f"and scaled by up to {100 * scale:.0f}%, the camera turned {cam['turn_deg']:.2f} "
            f"deg and its focal length x{cam['focal_factor']:.3f}; the estimate used the "
            f"refined model (the .blend is unchanged; model_refinement in the track file "
            f"lists each object's correction)")


def _geographic(sun_in_world, north: float) -> Tuple[float, float]:
    """(zenith, geographic azimuth) of a direction toward the Sun."""
    z, a_world = angles.angles_from_sun_in_world(sun_in_world)
    return float(z), float(angles.azimuth_geographic_from_world(a_world, north))


def _clock_suns(ephemeris: Dict[int, Tuple[float, float]],
                clock_trusted: Optional[bool]) -> Dict[int, Tuple[float, float]]:
    """The ephemeris's Suns the finishing may predict frames with: none
    where the footage contradicts the clock (a wrong zone: whole_clip's
    CLOCK_WRONG), which would put them hours off."""
    return {} if clock_trusted is False else dict(ephemeris)


def _raw_sun(r: RawFrame, north: float, clock_sun=None, clock_night: bool = False) -> RawSun:
    angles_of = (None, None) if r.sun_in_world is None else _geographic(r.sun_in_world, north)
    return RawSun(r.frame, *angles_of, confidence=r.on_circle, reason=r.reason,
                  tracked=r.tracked, sunlight=r.sunlight, clock_sun=clock_sun,
                  clock_night=clock_night,
                  shadows_in_view=r.shadows_in_view, circle_checked=r.circle_checked,
                  height_spread_deg=_height_spread_deg(r))


def _note(track, scene, camera, samples, by_frame, options) -> None:
    """Unmodelled shadows looked for on the best-supported frame kept in
    colour (no frame is decoded again for the note)."""
    kept = [f for f in samples if f in by_frame and by_frame[f].sun_in_world is not None]
    if kept:
        f = max(kept, key=lambda f: by_frame[f].confidence)
        notes.note_unmodelled_shadows(track, scene, camera, f, samples[f],
                                      by_frame[f].sun_in_world, list(samples.values()), options)
