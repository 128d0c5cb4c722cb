"""Finding the Sun from its cast shadows alone, when shading cannot.

The initial estimate (thesis ch. 3) reads the Sun from how the model's
surfaces are shaded. On a flat plate with a thin post (a sundial, a parking
lot with a lamp post) shading says nothing about the azimuth; only the cast
shadow does, and it covers a few hundred pixels. The thesis has no answer for
that case; here the Sun is searched for directly as the direction whose
ray-cast shadow of the model falls where the frame is darker than the clip's
shadow-free background.

Background: in a time-lapse the shadows move, so a high percentile over a
few frames spread through the clip is the ground without them (and with the
engraved lines, numerals, stains and the dark casters themselves, which the
ratio frame / background then cancels). Each frame is divided by its own
median first, so exposure changes do not matter. Memory is bounded by the
number of samples, not the clip's length.

Search: ground pixels on a regular grid are ray cast once; for candidate Sun
directions (a Fibonacci grid over the sky, then finer grids around the best)
the predicted shadow mask P is compared with the observed dark mask D
(ratio below DARK_RATIO) by their overlap 2|P n D| / (|P| + |D|). Unmodelled
shadows only add to |D|, equally for every direction.
"""

from __future__ import annotations

import math
from typing import List, Optional, Sequence

import numpy as np

BACKGROUND_SAMPLES = 24
BACKGROUND_PERCENTILE = 50
DARK_RATIO = 0.7
# Blocks (fraction of the frame width) over which the lit level is taken.
LEVEL_BLOCK = 0.06
# The share of the best direction's predicted shadow that must be dark for
# it to be believed (unmodelled shadows do not lower it, so it can be high).
MIN_PRECISION = 0.5


def background(frames_gray: Sequence[np.ndarray], top: int = 0) -> Optional[np.ndarray]:
    """Shadow-free background from a few gray frames (None if fewer than 3)."""
    stack = []
    for g in frames_gray:
        if g is None:
            continue
        m = float(np.median(g[top:]))
        if m > 1e-4:
            stack.append(g / m)
    if len(stack) < 3:
        return None
    return np.percentile(np.array(stack, dtype=np.float32), BACKGROUND_PERCENTILE,
                         axis=0).astype(np.float32)


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
                            top: int = 0):
    """Dense uint8 masks (H x W, 255 = set): the model's ground as the camera
    sees it (below row `top`), and the model's cast shadow on it toward
    `sun_in_world`."""
    h, w = camera.height, camera.width
    ys, xs = np.mgrid[top:h, 0:w]
    on, origins = ground_samples(scene, camera, ground_ids, ys.ravel(), xs.ravel())
    d = np.asarray(sun_in_world, dtype=np.float32)
    occ = scene.occluded(origins, np.ascontiguousarray(np.tile(d, (len(origins), 1))))
    ground = np.zeros((h - top) * w, dtype=np.uint8)
    shadow = np.zeros((h - top) * w, dtype=np.uint8)
    ground[on] = 255
    shadow[np.flatnonzero(on)[occ.astype(bool)]] = 255
    pad = np.zeros((top, w), dtype=np.uint8)
    return (np.vstack([pad, ground.reshape(h - top, w)]),
            np.vstack([pad, shadow.reshape(h - top, w)]))


def fibonacci_sky(n: int, min_elevation_deg: float = 1.0) -> np.ndarray:
    """About n unit directions spread evenly over the sky above the given elevation."""
    top = 1.0
    bottom = math.sin(math.radians(min_elevation_deg))
    k = np.arange(n) + 0.5
    z = top - (top - bottom) * k / n
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    r = np.sqrt(np.maximum(0.0, 1.0 - z * z))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1)


def _local_grid(center: np.ndarray, radius_deg: float, step_deg: float) -> np.ndarray:
    c = center / np.linalg.norm(center)
    e1 = np.cross(c, [0.0, 0.0, 1.0])
    if np.linalg.norm(e1) < 1e-6:
        e1 = np.array([1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(c, e1)
    steps = np.arange(-radius_deg, radius_deg + 1e-9, step_deg)
    uu, vv = np.meshgrid(np.radians(steps), np.radians(steps))
    d = c[None, :] + uu.reshape(-1, 1) * e1[None, :] + vv.reshape(-1, 1) * e2[None, :]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return d[d[:, 2] > 0.005]


class ShadowSearch:
    """Ground samples of one camera and model, reused for every frame."""

    def __init__(self, scene, camera, ground_ids: Sequence[int], top: int = 0,
                 max_pixels: int = 20000):
        h, w = camera.height, camera.width
        step = max(1, int(math.ceil(math.sqrt((h - top) * w / max_pixels))))
        ys, xs = np.mgrid[top:h:step, 0:w:step]
        ok, self.origins = ground_samples(scene, camera, ground_ids, ys.ravel(), xs.ravel())
        self.scene = scene
        self.rows = ys.ravel()[ok].astype(np.int64)
        self.cols = xs.ravel()[ok].astype(np.int64)

    def __len__(self):
        return len(self.rows)

    def dark(self, gray: np.ndarray, back: np.ndarray) -> np.ndarray:
        """Observed dark mask on the samples: frame / background well below
        the lit level around it. The level is the median ratio in blocks of
        LEVEL_BLOCK of the frame's width, smoothed over neighbouring blocks:
        glare, vignetting and thin cloud change it slowly across the frame,
        a hard shadow does not."""
        b = back[self.rows, self.cols]
        g = gray[self.rows, self.cols]
        valid = b > 0.1 * max(1e-6, float(np.median(b)))
        ratio = np.where(valid, g / np.maximum(b, 1e-6), np.nan)
        size = max(4, int(round(LEVEL_BLOCK * gray.shape[1])))
        by, bx = self.rows // size, self.cols // size
        ny, nx = int(by.max()) + 1, int(bx.max()) + 1
        key = by * nx + bx
        level = np.full(ny * nx, np.nan)
        order = np.argsort(key, kind="stable")
        bounds = np.searchsorted(key[order], np.arange(ny * nx + 1))
        for k in range(ny * nx):
            vals = ratio[order[bounds[k]:bounds[k + 1]]]
            vals = vals[~np.isnan(vals)]
            if len(vals) >= 4:
                level[k] = np.median(vals)
        grid = level.reshape(ny, nx)
        padded = np.pad(grid, 1, constant_values=np.nan)
        stack = np.stack([padded[dy:dy + ny, dx:dx + nx] for dy in range(3) for dx in range(3)])
        with np.errstate(all="ignore"):
            smooth = np.nanmedian(stack, axis=0)
        fallback = float(np.nanmedian(ratio)) if valid.any() else 1.0
        smooth = np.where(np.isnan(smooth), fallback, smooth).ravel()
        return valid & (np.nan_to_num(ratio, nan=1e9) < DARK_RATIO * smooth[key])

    def shadowed(self, directions: np.ndarray) -> np.ndarray:
        """(len(directions), samples) bool: sample in the model's cast shadow."""
        n = len(self.origins)
        out = np.empty((len(directions), n), dtype=bool)
        chunk = max(1, 400000 // max(1, n))
        for i in range(0, len(directions), chunk):
            d = directions[i:i + chunk].astype(np.float32)
            o = np.broadcast_to(self.origins[None], (len(d), n, 3)).reshape(-1, 3)
            dd = np.repeat(d, n, axis=0)
            out[i:i + len(d)] = self.scene.occluded(np.ascontiguousarray(o),
                                                    np.ascontiguousarray(dd)).reshape(len(d), n)
        return out

    def overlap(self, directions: np.ndarray, dark: np.ndarray) -> np.ndarray:
        p = self.shadowed(directions)
        inter = (p & dark[None, :]).sum(axis=1)
        size = p.sum(axis=1) + dark.sum()
        return np.where(p.sum(axis=1) >= 3, 2.0 * inter / np.maximum(size, 1), 0.0)

    def search(self, gray: np.ndarray, back: np.ndarray, coarse: int = 1500) -> dict:
        """The best Sun direction for this frame: {"sun_in_world", "overlap",
        "zenith_deg", "azimuth_deg", "message"}."""
        import time
        t0 = time.perf_counter()
        r = self._search(gray, back, coarse)
        r["seconds"] = time.perf_counter() - t0
        return r

    def _search(self, gray, back, coarse):
        if len(self) == 0:
            return {"sun_in_world": None, "overlap": 0.0,
                    "message": "no ground in view to search for shadows on"}
        dark = self.dark(gray, back)
        if dark.sum() < 3:
            return {"sun_in_world": None, "overlap": 0.0,
                    "message": "no shadow on the ground (nothing darker than the background)"}
        dirs = fibonacci_sky(coarse)
        score = self.overlap(dirs, dark)
        best: List[tuple] = sorted(zip(score, range(len(dirs))), reverse=True)[:6]
        candidates = [(s, dirs[i]) for s, i in best if s > 0]
        for radius, step in ((4.0, 1.0), (1.2, 0.3), (0.35, 0.1)):
            refined = []
            for _, c in candidates:
                grid = _local_grid(c, radius, step)
                sc = self.overlap(grid, dark)
                k = int(np.argmax(sc))
                refined.append((float(sc[k]), grid[k]))
            candidates = sorted(refined, key=lambda t: -t[0])[:3]
        if not candidates:
            return {"sun_in_world": None, "overlap": 0.0,
                    "message": "no model shadow matches the dark ground"}
        s, d = candidates[0]
        p = self.shadowed(np.asarray([d]))[0]
        precision = float((p & dark).sum()) / max(1, int(p.sum()))
        z = math.degrees(math.acos(max(-1.0, min(1.0, d[2]))))
        a = math.degrees(math.atan2(d[0], d[1])) % 360.0
        msg = "" if precision >= MIN_PRECISION else \
            (f"the best shadow match is weak: {100 * precision:.0f}% of its predicted "
             f"shadow is dark (at least {100 * MIN_PRECISION:.0f}% wanted)")
        return {"sun_in_world": tuple(float(v) for v in d), "overlap": s, "precision": precision,
                "zenith_deg": z, "azimuth_deg": a, "message": msg}
