"""The clip's shadow-free background and the model's shadow masks, for the
unmodelled-shadow note (pipeline.detect_unmodelled_shadows).

Background: in a time-lapse the shadows move, so the per-pixel median of a
few frames spread through the clip is the ground without them (and with the
engraved lines, numerals, stains and the dark casters themselves). Memory is
bounded by the number of samples, not the clip's length.

(The cast-shadow search that used to live here, for frames whose shading
could not fix the Sun, is now part of the whole-sky evidence every frame gets
natively: native/src/sky.)
"""

from __future__ import annotations

from typing import List, Optional, Sequence

import numpy as np

BACKGROUND_SAMPLES = 24


def linear_bgr(bgr: np.ndarray, gamma: float = 2.2) -> np.ndarray:
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
