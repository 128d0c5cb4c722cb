"""Hard ground shadows the model does not cast: the unmodelled-shadow note
recorded in the track, and the hint to the artist to model their casters.

The clip's shadow-free background: in a time-lapse the shadows move, so the per-pixel median of a
few frames spread through the clip is the ground without them (and with the
engraved lines, numerals, stains and the dark casters themselves). Memory is
bounded by the number of samples, not the clip's length.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from . import native_loader
from .options import gamma
from ..core import trackfile

BACKGROUND_SAMPLES = 24


def linear_bgr(bgr: np.ndarray, gamma: float) -> np.ndarray:
    """uint8 BGR -> float32 linear BGR in [0, 1]."""
    return np.power(bgr.astype(np.float32) / 255.0, gamma).astype(np.float32)


def clip_background(frames: Sequence[np.ndarray], rows_per_chunk: int = 64) -> Optional[np.ndarray]:
    """The per-pixel median (uint8 BGR) of a few frames spread over a clip:
    its shadow-free background when the shadows moved between them (None
    for fewer than 3 frames). Done in bands of rows on uint8, so memory stays
    near the frames' own."""
    frames = [f for f in frames if f is not None]
    if len(frames) < 3 or any(f.shape != frames[0].shape for f in frames):
        return None
    k = len(frames) // 2
    out = np.empty_like(frames[0])
    for y in range(0, out.shape[0], rows_per_chunk):
        band = np.stack([f[y:y + rows_per_chunk] for f in frames])
        out[y:y + rows_per_chunk] = np.partition(band, k, axis=0)[k]
    return out


def spread(frames: Sequence[int], n: int = BACKGROUND_SAMPLES) -> List[int]:
    """Up to n of `frames`, evenly spread from the first to the last."""
    k = min(n, len(frames))
    return sorted({frames[round(i * (len(frames) - 1) / max(1, k - 1))] for i in range(k)})


def ground_samples(scene, camera, ground_ids: Sequence[int], rows, cols):
    """Of the pixels (rows, cols), those that see the model's ground: their
    mask over the inputs and their ground points, lifted off the surface
    along the normal so that shadow rays do not hit it."""
    pixels = np.ascontiguousarray(np.stack([cols, rows], axis=1).astype(np.float64))
    hits = scene.intersect_pixels(camera, pixels)
    on = np.isin(hits["object_id"], np.asarray(list(ground_ids), dtype=np.int32))
    scale = max(1e-3, float(np.max(np.abs(hits["point"][on])))) if on.any() else 1.0
    origins = (hits["point"][on] + 1e-4 * scale * hits["normal"][on]).astype(np.float32)
    return on, np.ascontiguousarray(origins)


def ground_and_model_shadow(scene, camera, ground_ids: Sequence[int], sun_in_world,
                            top: int = 0, stride: int = 1):
    """Dense uint8 masks (255 = set): the model's ground as the camera sees
    it (below row `top`), and the model's cast shadow on it toward
    `sun_in_world`; at every `stride`-th pixel of the camera's rows and
    columns (the size of image[::stride, ::stride])."""
    h, w = camera.height, camera.width
    ys, xs = np.mgrid[0:h:stride, 0:w:stride]
    rows, cols = ys.shape
    below = ys[:, 0] >= top
    ys, xs = ys[below], xs[below]
    on, origins = ground_samples(scene, camera, ground_ids, ys.ravel(), xs.ravel())
    d = np.asarray(sun_in_world, dtype=np.float32)
    occ = scene.occluded(origins, np.ascontiguousarray(np.tile(d, (len(origins), 1))))
    ground = np.zeros(ys.size, dtype=np.uint8)
    shadow = np.zeros(ys.size, dtype=np.uint8)
    ground[on] = 255
    shadow[np.flatnonzero(on)[occ.astype(bool)]] = 255
    pad = np.zeros((rows - ys.shape[0], cols), dtype=np.uint8)
    return (np.vstack([pad, ground.reshape(-1, cols)]),
            np.vstack([pad, shadow.reshape(-1, cols)]))


# A hint to model a missing caster needs a shadow of at least this share of
# the frame, at most this bright relative to the lit ground around (under
# direct sun a hard shadow keeps only the sky's light, a third or less, and
# the rendered presets' show 0.27-0.39; the Marseille dial's engraved
# numerals, shifted by the camera's shake, were seen at 0.50-0.65).
# Weaker ones, and those bordering the model's predicted shadow (the Sun of
# the anchor frame may put a modelled shadow a little off and leave part of
# it unexplained), are recorded in the track file only.
HINT_MIN_AREA = 5e-4
HINT_MAX_DARKENING = 0.45
# Unmodelled shadows are looked for on frames reduced to about this width
# (every n-th pixel): the regions worth a hint are a hundred pixels or more
# there, and full frames cost 0.6 s at 720p, seconds and gigabytes at 4K.
NOTE_WIDTH = 640


def note_stride(camera) -> int:
    """Every how many pixels the unmodelled-shadow note looks."""
    return max(1, -(-camera.width // NOTE_WIDTH))


@dataclass
class Found:
    """Unmodelled shadows on one frame, in the camera's pixels: each region
    as the track file records it (area_px, box, centroid_px, darkening,
    edge_contrast, touches_model), and the masks looked in."""
    regions: List[Dict[str, Any]]
    mask: np.ndarray          # uint8, 255 on the regions (at the note's stride)
    ground: np.ndarray        # the ground the model's shadow falls on
    model_shadow: np.ndarray  # the model's own cast shadow


def detect_unmodelled_shadows(scene, camera, ground_ids, bgr, sun_in_world, samples,
                              gamma, top=0) -> Optional[Found]:
    """Hard ground shadows on one frame (uint8 BGR) that the model does not
    cast toward `sun_in_world`: native.detect_unmodelled_shadows against the
    clip's shadow-free background (the median of `samples`, uint8 BGR frames
    spread over the clip), which tells a shadow from dark paint, stains or
    engravings. Also returns the masks used.
    None when fewer than 3 samples make no background.

    Large frames are looked at every note_stride(camera)-th pixel (frame and
    samples may be given reduced so already); the regions are reported in
    the camera's pixels."""
    stride = note_stride(camera)
    h, w = -(-camera.height // stride), -(-camera.width // stride)

    def reduced(image):
        return image if image.shape[:2] == (h, w) else image[::stride, ::stride]
    back = clip_background([reduced(f) for f in samples if f is not None])
    if back is None:
        return None
    native = native_loader.require()
    ground, shadow = ground_and_model_shadow(scene, camera, ground_ids, sun_in_world, top,
                                             stride)
    # A camera shake of about a pixel per 320 of width is forgiven.
    found = native.detect_unmodelled_shadows(
        linear_bgr(reduced(bgr), gamma), linear_bgr(back, gamma), ground, shadow,
        registration_px=max(1, round(w / 320)))
    regions = [{"area_px": r.area_px * stride * stride,
                "box": [v * stride for v in r.box],
                "centroid_px": [v * stride for v in r.centroid_px],
                "darkening": r.darkening, "edge_contrast": r.edge_contrast,
                "touches_model": r.touches_model} for r in found.regions]
    return Found(regions, found.mask, ground, shadow)


def note_unmodelled_shadows(track, scene, camera, frame, bgr, sun_in_world, samples, options):
    """The anchor frame's unmodelled shadows (detect_unmodelled_shadows),
    recorded in the track file (extra.unmodelled_shadows) and, when large and
    dark, turned into a hint for the artist (extra.model_hint). A clip whose
    shadows barely moved has no shadow-free background, so nothing is found.
    Advisory: a failure here only notes itself."""
    try:
        found = detect_unmodelled_shadows(scene, camera, options.ground_object_ids, bgr,
                                          sun_in_world, samples, gamma(options.method),
                                          options.ignore_top_rows)
    except (ValueError, RuntimeError, MemoryError) as e:
        track.extra["unmodelled_shadows"] = {"frame": frame, "error": str(e)}
        return
    if found is None:
        track.extra["unmodelled_shadows"] = {
            "frame": frame, "skipped": "too few frames for a shadow-free background"}
        return
    regions = found.regions
    track.extra["unmodelled_shadows"] = {"frame": frame, "regions": regions,
                                         "background_frames": len(samples)}
    big = [r for r in regions if r["area_px"] >= HINT_MIN_AREA * camera.width * camera.height
           and r["darkening"] <= HINT_MAX_DARKENING and not r["touches_model"]]
    if big:
        x, y = big[0]["centroid_px"]
        track.report("model", trackfile.ProblemKind.HINT, (
            f"{len(big)} hard ground shadow(s) on frame {frame} are not cast by the model "
            f"(the largest, {big[0]['area_px']} px, around pixel ({x:.0f}, {y:.0f})): model "
            f"their casters and the tracker will follow their shadows too"))
