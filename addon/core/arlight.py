"""Light for AR inserts taken from the footage's own shadows. bpy-free.

A shadow catcher darkens the plate by the ratio of the light a ground point
gets with the insert to the light it gets without it; under a Sun lamp of
irradiance S (per channel) and a uniform sky of radiance W, a horizontal
ground point in the insert's shadow keeps pi W / (S cos z + pi W). The
footage shows that same ratio in its real shadows: the median of the plate
(linear, as Blender composites it) in the model's cast shadow over the median
of the lit ground next to it. Solving for S and W per channel makes the
insert's shadow as dark, and as tinted, as the real ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Optional, Sequence, Tuple

import numpy as np

# Assumed ground albedo: it sets only the overall exposure of the light (the
# lit ground's plate value over it is the irradiance / pi); the shadow ratios
# do not depend on it.
GROUND_ALBEDO = 0.35
# Shadow ratios are kept in this range: 1 would mean no Sun, 0 no sky.
MIN_RATIO, MAX_RATIO = 0.02, 0.95
# Fewest pixels on each side for a measurement.
MIN_PIXELS = 6


def srgb_to_linear(v: np.ndarray) -> np.ndarray:
    """sRGB-encoded values in 0..1 to linear (what Blender's clip node gives)."""
    v = np.asarray(v, dtype=np.float64)
    return np.where(v <= 0.04045, v / 12.92, ((v + 0.055) / 1.055) ** 2.4)


def linear_to_srgb(v: np.ndarray) -> np.ndarray:
    v = np.clip(np.asarray(v, dtype=np.float64), 0.0, None)
    return np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)


def _shift_or(mask: np.ndarray, r: int) -> np.ndarray:
    """Dilation by a (2r+1) square, by shifts (no OpenCV/scipy in the glue)."""
    out = mask.copy()
    h, w = mask.shape
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dy == 0 and dx == 0:
                continue
            ys, yd = (slice(0, h - dy), slice(dy, h)) if dy >= 0 else (slice(-dy, h), slice(0, h + dy))
            xs, xd = (slice(0, w - dx), slice(dx, w)) if dx >= 0 else (slice(-dx, w), slice(0, w + dx))
            out[yd, xd] |= mask[ys, xs]
    return out


def dilate(mask: np.ndarray, r: int) -> np.ndarray:
    return _shift_or(mask.astype(bool), r) if r > 0 else mask.astype(bool)


def erode(mask: np.ndarray, r: int) -> np.ndarray:
    return ~_shift_or(~mask.astype(bool), r) if r > 0 else mask.astype(bool)


@dataclass
class ShadowBalance:
    shadow_ratio: Tuple[float, float, float]   # shadow / lit, linear R, G, B
    lit_linear: Tuple[float, float, float]     # lit ground's median, linear R, G, B
    shadow_pixels: int
    lit_pixels: int


def measure_shadow_balance(rgb_linear: np.ndarray, ground: np.ndarray, shadow: np.ndarray,
                           band_px: Optional[int] = None) -> Optional[ShadowBalance]:
    """Per-channel shadow/lit ratio of the real shadows on one frame.

    rgb_linear: H x W x 3 linear plate; ground, shadow: H x W masks (the
    model's ground, and its cast shadow toward the estimated Sun). The edges
    (a pixel's worth, more on large frames) are left out: a Sun a little off
    moves them. Lit pixels are taken within `band_px` of the shadows, so the
    same kind of ground is compared. None when either side is too small."""
    h, w = ground.shape
    ground = ground.astype(bool)
    shadow = shadow.astype(bool) & ground
    margin = max(1, round(w / 400))
    band = band_px if band_px is not None else max(4, round(w / 25))
    core = erode(shadow, margin) & erode(ground, margin)
    near = dilate(shadow, band) & ~dilate(shadow, margin + 1) & erode(ground, margin)
    if core.sum() < MIN_PIXELS or near.sum() < MIN_PIXELS:
        return None
    dark = np.median(rgb_linear[core], axis=0)
    lit = np.median(rgb_linear[near], axis=0)
    if np.any(lit <= 1e-6):
        return None
    ratio = np.clip(dark / lit, MIN_RATIO, MAX_RATIO)
    return ShadowBalance(tuple(float(x) for x in ratio), tuple(float(x) for x in lit),
                         int(core.sum()), int(near.sum()))


def sun_and_sky(shadow_ratio: Sequence[float], lit_linear: Sequence[float], zenith_deg: float,
                ground_albedo: float = GROUND_ALBEDO):
    """(Sun irradiance RGB, sky radiance RGB) that give a horizontal ground
    `shadow_ratio` in a hard shadow and light it as bright as the plate's lit
    ground (for an albedo of `ground_albedo`):
        pi W / (S cos z + pi W) = ratio,   S cos z + pi W = pi lit / albedo."""
    cos_z = max(0.05, math.cos(math.radians(zenith_deg)))  # grazing Sun: bounded
    sun, sky = [], []
    for r, lit in zip(shadow_ratio, lit_linear):
        r = min(MAX_RATIO, max(MIN_RATIO, r))
        irradiance = math.pi * lit / ground_albedo
        sky.append(r * irradiance / math.pi)
        sun.append((1.0 - r) * irradiance / cos_z)
    return tuple(sun), tuple(sky)


def as_strength_and_color(rgb: Sequence[float]):
    """(strength, colour with max channel 1) for a lamp or a background."""
    peak = max(max(rgb), 1e-9)
    return peak, tuple(c / peak for c in rgb)
