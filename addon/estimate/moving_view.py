"""A moving camera's frames seen from one of its views (issue 26; bpy-free).

The whole-clip estimate measures on the model's surfaces, which do not move:
a moving camera's frames are resampled through the model into one reference
view (native ViewWarp, motion/view_warp.h), and the estimate runs on them as
on a fixed camera's. This module holds what is particular to that: which
view is the reference, the frames' cameras at the working size and why some
have none, the resampling, and what the estimate does after, on a frame that
sees only part of where the shadows fall and for the overlay, which draws
each frame's shadow in its own pixels.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Dict, List, Sequence, Tuple

import numpy as np

from . import notes
from .errors import EstimateError
from .frames import Gray

# A frame that sees less than this share of the samples where shadows can
# show has them out of view: its sunlight is unknown, not "no".
SHADOWS_IN_VIEW = 0.8
SHADOWS_OUT_OF_VIEW = "the model's shadows are out of the camera's view on this frame"
# The reference view is chosen among this many posed frames spread over the
# run, each probed with a ray per pixel of a view this small
# (reference_camera).
REFERENCE_CANDIDATES = 16
REFERENCE_PROBE_WIDTH = 96
# Why a frame is not used when its pose is missing.
NO_POSE = "the camera has no pose on this frame (not solved)"


@dataclass
class FrameShadow:
    """The tracked shadow on a moving camera's frame, in the frame's own
    pixels at the working size (what finish.py reads of a TrackedFrame)."""
    shadow_start_px: Tuple[float, float]
    shadow_end_px: Tuple[float, float]
    contrast: float
    misfit: float
    elevation_pinned_deg: float


def posed(camera: Any) -> Any:
    """A frame_cameras value as a camera, or None where the frame has no
    pose (None, or a sentence saying why)."""
    return None if camera is None or isinstance(camera, str) else camera


def reference_camera(scene, frame_cameras: Dict[int, Any], frames: Sequence[int],
                     ground_ids: Sequence[int]):
    """The view a moving camera's frames are seen from: among posed frames
    spread over the run (REFERENCE_CANDIDATES), the pose that sees the most
    of the casters (the model off the ground, where the shadows start), the
    ground counting for a tenth; ties go to the middle of the run (the views
    either side differ least from it)."""
    posed_frames = [f for f in frames if posed(frame_cameras.get(f)) is not None]
    if not posed_frames:
        raise EstimateError("the camera has no pose on any frame of the run")
    middle = len(posed_frames) // 2
    picks = sorted(set(notes.spread(posed_frames, REFERENCE_CANDIDATES)) | {posed_frames[middle]})
    some = frame_cameras[posed_frames[middle]]
    w = REFERENCE_PROBE_WIDTH
    h = max(1, round(w * some.height / some.width))
    ys, xs = np.mgrid[0:h, 0:w]
    pixels = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)
    ground = np.array(list(ground_ids), dtype=np.int64)

    def seen(f: int) -> float:
        ids = scene.intersect_pixels(frame_cameras[f].resized(w, h), pixels)["object_id"]
        on_ground = np.isin(ids, ground)
        return float(np.count_nonzero((ids >= 0) & ~on_ground)
                     + 0.1 * np.count_nonzero(on_ground))

    scores = {f: seen(f) for f in picks}
    best = max(scores.values())
    return frame_cameras[min((f for f in picks if scores[f] >= 0.98 * best),
                             key=lambda f: abs(posed_frames.index(f) - middle))]


class MovingView:
    """The reference view of a moving camera's run and its frames' cameras
    at the working size `work` (the reference camera reduced as the frames
    are). frame_cameras: {frame: the native camera on it, of the clip's
    size, or where it has no pose None or a sentence saying why}."""

    def __init__(self, native, scene, work, frame_cameras: Dict[int, Any]):
        self.native, self.scene, self.work = native, scene, work
        try:
            self.view = native.ViewWarp(scene, work)
        except ValueError:
            raise EstimateError("the camera sees none of the model on the frame its "
                                "moving view is taken from")
        # The frames' cameras at the working size (None: no pose) and, for
        # those without a pose, why.
        self.frame_work: Dict[int, Any] = {}
        self.why_no_pose: Dict[int, str] = {}
        for f, c in frame_cameras.items():
            camera = posed(c)
            same = camera is None or (camera.width, camera.height) == (work.width, work.height)
            self.frame_work[f] = camera if same else camera.resized(work.width, work.height)
            if camera is None:
                self.why_no_pose[f] = c or NO_POSE
        self.warped: Any = None  # the pass's WarpedSource
        self.warp_s = 0.0        # resampling outside the pass

    def has_pose(self, f: int) -> bool:
        return self.frame_work.get(f) is not None

    def from_reference_view(self, f: int, gray: Gray) -> Gray:
        """Frame f (at the working size; or why there is none, passed on)
        resampled into the reference view, or why it cannot be."""
        if not isinstance(gray, np.ndarray):
            return gray
        camera = self.frame_work.get(f)
        if camera is None:
            return self.why_no_pose.get(f, NO_POSE)
        t0 = time.perf_counter()
        warped, _, why, _ = self.view.warp(gray, camera)
        self.warp_s += time.perf_counter() - t0
        return warped if warped is not None else why

    def source(self, frame_source, index_of: Dict[int, int]):
        """The pass's native frame source, its frames resampled into the
        reference view ahead, on a thread of its own."""
        size = max(index_of.values(), default=-1) + 1
        by_index: List[Any] = [None] * size
        why_not = [""] * size
        for f, i in index_of.items():
            by_index[i] = self.frame_work.get(f)
            why_not[i] = self.why_no_pose.get(f, "")
        self.warped = self.native.WarpedSource(frame_source, self.view, by_index, why_not)
        return self.warped

    def seconds(self) -> float:
        """Time spent resampling, in the pass and outside it."""
        return self.warp_s + (self.warped.seconds if self.warped is not None else 0.0)

    @staticmethod
    def less_sure_where_less_is_seen(frames, shadow_view: Sequence[float]) -> None:
        """A frame that sees only part of where the shadows can fall holds
        that share of the evidence: its confidence is scaled by it (a frame
        seeing 73% of it, half the shadows out of view, came out 9 deg off
        at 0.5)."""
        seen = np.clip(np.asarray(shadow_view, dtype=float), 0.0, 1.0)
        for k, r in enumerate(frames):
            r.confidence *= float(seen[k])
            r.on_circle *= float(seen[k])

    def shadows_in_their_frames(self, frames) -> None:
        """The tracked shadows were found in the reference view: each is
        carried through the model to its own frame's pixels (at the working
        size), where the overlay draws it on the footage."""
        for r in frames:
            t: Any = r.tracked
            if t is None:
                continue
            camera = self.frame_work.get(r.frame)
            ends = np.array([t.shadow_start_px, t.shadow_end_px], dtype=np.float64)
            moved = np.full((2, 2), np.nan)
            if camera is not None and np.isfinite(ends).all():
                points = self.scene.intersect_pixels(self.work, ends)["point"]
                if np.isfinite(points).all():
                    moved = camera.project(points.astype(np.float64))[0]
            r.tracked = FrameShadow((float(moved[0][0]), float(moved[0][1])),
                                    (float(moved[1][0]), float(moved[1][1])),
                                    float(t.contrast), float(t.misfit),
                                    float(t.elevation_pinned_deg))
