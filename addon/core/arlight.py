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
from typing import Dict, List, Optional, Sequence, Tuple

import numpy as np

from .trackfile import Sunlight

# Assumed ground albedo: it sets only the overall exposure of the light (the
# lit ground's plate value over it is the irradiance / pi); the shadow ratios
# do not depend on it.
GROUND_ALBEDO = 0.35
# Shadow ratios are kept in this range: 1 would mean no Sun, 0 no sky.
MIN_RATIO, MAX_RATIO = 0.02, 0.95
# Fewest pixels on each side for a measurement.
MIN_PIXELS = 6
# Pixels are told lit or shaded by their neighbourhood's mean over a square
# of this radius: a textured ground's and a dim frame's pixel-to-pixel
# variation (a pixel's level 40-80% off its neighbours') put the lit pixels'
# dark tail on the shaded side and the reverse, and the ratio came out
# 20-35% too dark.
CLASSIFY_RADIUS_PX = 1
# Frames' measurements are smoothed by a running median over this many
# measured neighbours: it keeps a ramp (dusk, an exposure change) and a step
# (a cloud's edge) where they are, and drops a frame or two measured wrong
# (a passer-by in the shadow, a few pixels of shadow on a small frame).
LIGHT_MEDIAN_WINDOW = 5


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
            ys, yd = ((slice(0, h - dy), slice(dy, h)) if dy >= 0
                      else (slice(-dy, h), slice(0, h + dy)))
            xs, xd = ((slice(0, w - dx), slice(dx, w)) if dx >= 0
                      else (slice(-dx, w), slice(0, w + dx)))
            out[yd, xd] |= mask[ys, xs]
    return out


def box_mean(image: np.ndarray, r: int) -> np.ndarray:
    """Mean over the (2r+1) square around each pixel of a 2-D image, the
    border repeated outward (a summed-area table; no OpenCV in the glue)."""
    if r <= 0:
        return np.asarray(image, dtype=np.float64)
    k = 2 * r + 1
    padded = np.pad(np.asarray(image, dtype=np.float64), r, mode="edge")
    table = np.pad(padded, ((1, 0), (1, 0))).cumsum(axis=0).cumsum(axis=1)
    return (table[k:, k:] - table[:-k, k:] - table[k:, :-k] + table[:-k, :-k]) / (k * k)


# sRGB code value -> linear: the table the frames are read through
# (native linear_block_means).
SRGB_TO_LINEAR_TABLE = srgb_to_linear(np.arange(256) / 255.0).astype(np.float32)


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
    shadow_mask: Optional[np.ndarray] = None   # the pixels measured, H x W bool
    lit_mask: Optional[np.ndarray] = None


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
    # Wide shadows first: thin ones (a fence's bars, a pole's) are mostly
    # edge pixels, part lit, at small sizes.
    for m in (3 * margin, 2 * margin, margin):
        core = erode(shadow, m) & erode(ground, margin)
        if core.sum() >= 4 * MIN_PIXELS:
            break
    near = dilate(shadow, band) & ~dilate(shadow, margin + 1) & erode(ground, margin)
    if core.sum() < MIN_PIXELS or near.sum() < MIN_PIXELS:
        return None
    # A Sun a little off, or a shadow the model does not cast, puts lit
    # pixels among the predicted shadow and dark ones beside it: each side
    # keeps only the pixels whose neighbourhood is on its side of the
    # threshold halfway (in log) between the two first medians. The pixels'
    # own levels are what is measured: only the choice is smoothed.
    lum_all = box_mean(rgb_linear.mean(axis=2), CLASSIFY_RADIUS_PX)
    for _ in range(2):
        d, lt = np.median(lum_all[core]), np.median(lum_all[near])
        if not (0 < d < lt):
            break
        t = math.sqrt(d * lt)
        core2, near2 = core & (lum_all < t), near & (lum_all >= t)
        if core2.sum() < MIN_PIXELS or near2.sum() < MIN_PIXELS:
            break
        core, near = core2, near2
    dark = np.median(rgb_linear[core], axis=0)
    lit = np.median(rgb_linear[near], axis=0)
    if np.any(lit <= 1e-6):
        return None
    ratio = np.clip(dark / lit, MIN_RATIO, MAX_RATIO)
    return ShadowBalance(_rgb(ratio), _rgb(lit), int(core.sum()), int(near.sum()), core, near)


def _rgb(v: np.ndarray) -> Tuple[float, float, float]:
    """A per-channel (R, G, B) array as a tuple of three floats."""
    r, g, b = (float(x) for x in v)
    return r, g, b


def sun_and_sky(shadow_ratio: Sequence[float], lit_linear: Sequence[float], zenith_deg: float,
                ground_albedo: float = GROUND_ALBEDO, sky_seen_in_shadow=1.0,
                sky_seen_lit: float = 1.0):
    """(Sun irradiance RGB, sky radiance RGB) that reproduce the footage's
    `shadow_ratio` on horizontal ground and light it as bright as the
    plate's lit ground (for an albedo of `ground_albedo`).

    The real shadows lie beside their casters, which hide part of the sky
    from them (`sky_seen_in_shadow`, cosine-weighted, 0..1, one value or one
    per channel; the lit ground beside them sees `sky_seen_lit`); an insert
    hides the sky from its own shadow the same way when rendered, so that
    share is taken out here:
        ratio = Vs x / (1 + Vl x),  x = pi W / (S cos z)
        S cos z + Vl pi W = pi lit / albedo."""
    cos_z = max(0.05, math.cos(math.radians(zenith_deg)))  # grazing Sun: bounded
    seen = sky_seen_in_shadow if isinstance(sky_seen_in_shadow, (tuple, list, np.ndarray)) \
        else (sky_seen_in_shadow,) * len(shadow_ratio)
    sun, sky = [], []
    for r, lit, vs in zip(shadow_ratio, lit_linear, seen):
        vs = min(1.0, max(0.2, float(vs)))
        vl = min(1.0, max(vs, sky_seen_lit))
        r = min(MAX_RATIO * vs / vl, max(MIN_RATIO, r))
        x = r / max(1e-6, vs - r * vl)
        irradiance = math.pi * lit / ground_albedo
        direct = irradiance / (1.0 + vl * x)           # S cos z
        sun.append(direct / cos_z)
        sky.append(x * direct / math.pi)               # W
    return tuple(sun), tuple(sky)


def sun_response(rendered_ratio: Sequence[float], target_ratio: Sequence[float],
                 zenith_deg: float, sky_seen_in_shadow: float = 1.0,
                 sky_seen_lit: float = 1.0) -> RGB:
    """Per channel, how much more the renderer's ground answers the Sun
    than the formula's Lambertian ground: the Sun-to-sky balance a check
    render's ratio (`rendered_ratio`, lit as light_per_frame set it for
    `target_ratio`) stands for, over the one it was lit with. A rough
    ground's diffuse model brightens under a grazing Sun, a specular one
    adds a highlight, bounced light lightens the shadow: all folded into
    it, as a function of the Sun's height (corrections)."""
    got = sun_to_sky(rendered_ratio, zenith_deg, sky_seen_in_shadow, sky_seen_lit)
    want = sun_to_sky(target_ratio, zenith_deg, sky_seen_in_shadow, sky_seen_lit)
    r, g, b = (min(10.0, max(0.1, x / y)) for x, y in zip(got, want))
    return r, g, b


def sun_to_sky(shadow_ratio: Sequence[float], zenith_deg: float, sky_seen_in_shadow: float = 1.0,
               sky_seen_lit: float = 1.0):
    """The Sun's irradiance over the unoccluded sky's (S / pi W, per
    channel) behind a measured shadow ratio (see sun_and_sky): unlike the
    ratio it does not change with the Sun's height, so frames pool it."""
    cos_z = max(0.05, math.cos(math.radians(zenith_deg)))
    vs = min(1.0, max(0.2, sky_seen_in_shadow))
    vl = min(1.0, max(vs, sky_seen_lit))
    out = []
    for r in shadow_ratio:
        r = min(MAX_RATIO * vs / vl, max(MIN_RATIO, r))
        out.append(max(1e-6, vs - r * vl) / r / cos_z)
    return tuple(out)


def ratio_for(sun_to_sky_rgb: Sequence[float], zenith_deg: float, sky_seen_in_shadow: float = 1.0,
              sky_seen_lit: float = 1.0):
    """The shadow ratio a Sun-to-sky balance gives at `zenith_deg`."""
    cos_z = max(0.05, math.cos(math.radians(zenith_deg)))
    out = []
    for k in sun_to_sky_rgb:
        x = 1.0 / (k * cos_z)
        out.append(sky_seen_in_shadow * x / (1.0 + sky_seen_lit * x))
    return tuple(out)


def cosine_directions(n: int = 64) -> np.ndarray:
    """n unit directions over the upper hemisphere, spread evenly in the
    cosine-weighted measure (a Fibonacci spiral): the fraction not blocked
    is the share of a uniform sky's light a horizontal point gets."""
    k = np.arange(n) + 0.5
    r = np.sqrt(k / n)                      # disc radius, uniform in area
    phi = k * math.pi * (3.0 - math.sqrt(5.0))
    z = np.sqrt(np.maximum(0.0, 1.0 - r * r))
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=1).astype(np.float32)


def sky_seen(origins: np.ndarray, occluded, n: int = 64, max_points: int = 1500,
             seed: int = 0) -> float:
    """Mean cosine-weighted sky visibility of `origins` (M x 3, lifted off
    the ground); `occluded(origins, directions) -> bool array` casts rays."""
    if len(origins) == 0:
        return 1.0
    if len(origins) > max_points:
        pick = np.random.default_rng(seed).choice(len(origins), max_points, replace=False)
        origins = origins[pick]
    dirs = cosine_directions(n)
    o = np.ascontiguousarray(np.repeat(origins.astype(np.float32), n, axis=0))
    d = np.ascontiguousarray(np.tile(dirs, (len(origins), 1)))
    return float(1.0 - np.mean(occluded(o, d)))


def as_strength_and_color(rgb: Sequence[float]):
    """(strength, colour with max channel 1) for a lamp or a background."""
    peak = max(max(rgb), 1e-9)
    return peak, tuple(c / peak for c in rgb)


RGB = Tuple[float, float, float]


def ground_level(rgb_linear: np.ndarray, ground: np.ndarray) -> Optional[RGB]:
    """Median linear RGB of the ground the camera sees (edges left out), the
    light it gets when no shadow can be told apart; None when too little
    ground shows."""
    core = erode(ground, max(1, round(ground.shape[1] / 400)))
    if core.sum() < MIN_PIXELS:
        return None
    return _rgb(np.median(rgb_linear[core], axis=0))


@dataclass
class LightSample:
    """One frame's light as the footage shows it: a shadow balance where
    the Sun shines, the ground's brightness where it does not."""
    frame: int
    zenith_deg: float
    sunlight: Optional[Sunlight]
    balance: Optional[ShadowBalance] = None
    ground_linear: Optional[Tuple[float, float, float]] = None


@dataclass
class FrameLight:
    """The lamp's irradiance and the sky's radiance (linear RGB) for a frame,
    and the shadow ratio they are meant to give (None without a Sun)."""
    frame: int
    sun_rgb: Tuple[float, float, float]
    sky_rgb: Tuple[float, float, float]
    target_ratio: Optional[Tuple[float, float, float]] = None


def response_at(corrections, zenith_deg: float) -> RGB:
    """The renderer's Sun response at `zenith_deg`: the check renders'
    (zenith, RGB) interpolated per channel in log (held beyond the ends),
    1 without any."""
    if not corrections:
        return 1.0, 1.0, 1.0
    pairs = sorted(corrections, key=lambda c: c[0])
    zs = [z for z, _ in pairs]
    r, g, b = (float(np.exp(np.interp(zenith_deg, zs, [math.log(rgb[c]) for _, rgb in pairs])))
               for c in range(3))
    return r, g, b


def _running_median(rows: np.ndarray, window: int) -> np.ndarray:
    """Per column, the median of each row's neighbourhood of `window` rows,
    narrowed at the ends so that a ramp running to the end keeps its end."""
    n, half = len(rows), window // 2
    out = np.empty_like(rows)
    for i in range(n):
        reach = min(half, i, n - 1 - i)
        out[i] = np.median(rows[i - reach:i + reach + 1], axis=0)
    return out


def _sunlit_runs(lit: Sequence[Tuple[LightSample, ShadowBalance]],
                 samples: Sequence[LightSample]) -> List[List[Tuple[LightSample, ShadowBalance]]]:
    """The sunlit measurements (in frame order) split where a frame measured
    without sunlight lies between two of them: the running median stays on
    its side of a cloud or a night. Across one, the frames thinning into the
    cloud took the full Sun's balance of the frames beyond it, and their
    inserts' shadows came out 0.1-0.2 too dark."""
    dark = sorted(s.frame for s in samples if s.sunlight == Sunlight.NO)
    runs: List[List[Tuple[LightSample, ShadowBalance]]] = []
    for sb in lit:
        if runs and not any(runs[-1][-1][0].frame < f < sb[0].frame for f in dark):
            runs[-1].append(sb)
        else:
            runs.append([sb])
    return runs


def light_per_frame(samples: Sequence[LightSample], sky_seen_in_shadow: float,
                    sky_seen_lit: float,
                    corrections: Optional[Sequence[Tuple[float, Sequence[float]]]] = None,
                    ground_albedo: float = GROUND_ALBEDO) -> List[FrameLight]:
    """The Sun and sky per measured frame, so that an insert's shadow is as
    dark, and as tinted, as the footage's on that frame.

    Where the frame has direct sunlight (or may have: a measured shadow is
    evidence of it), the Sun-to-sky balance and the lit ground's brightness
    follow the frames' own, through a running median in frame order (dusk
    dims the Sun against the sky, an exposure ramp brightens the plate)
    that stays on its side of a frame measured without sunlight.
    Where it has none, the lamp is off and the sky alone lights the ground
    as bright as the footage shows it. `corrections`, (zenith deg, the
    renderer's Sun response RGB) pairs from check renders (sun_response),
    interpolated in the Sun's zenith (a ground's response departs from
    Lambert's most under a low Sun), divide the balance the lamp is set
    with, so that the render gives the footage's ratio."""
    lit = sorted(((s, s.balance) for s in samples
                  if s.balance is not None and s.sunlight != Sunlight.NO),
                 key=lambda sb: sb[0].frame)
    out: Dict[int, FrameLight] = {}
    for run in _sunlit_runs(lit, samples):
        window = min(LIGHT_MEDIAN_WINDOW, len(run))
        # log: the median of a ratio is the same whichever way it is taken.
        k = np.exp(_running_median(np.log([
            sun_to_sky(b.shadow_ratio, s.zenith_deg, sky_seen_in_shadow, sky_seen_lit)
            for s, b in run]), window))
        level = np.exp(_running_median(np.log([b.lit_linear for _, b in run]), window))
        for (s, _), k_s, level_s in zip(run, k, level):
            ratio = ratio_for(k_s, s.zenith_deg, sky_seen_in_shadow, sky_seen_lit)
            response = np.asarray(response_at(corrections, s.zenith_deg))
            lamp_ratio = ratio_for(k_s / response, s.zenith_deg, sky_seen_in_shadow,
                                   sky_seen_lit)
            sun, sky = sun_and_sky(lamp_ratio, level_s, s.zenith_deg, ground_albedo,
                                   sky_seen_in_shadow, sky_seen_lit)
            out[s.frame] = FrameLight(s.frame, _rgb(np.asarray(sun)), _rgb(np.asarray(sky)),
                                      ratio)
    vl = min(1.0, max(0.2, sky_seen_lit))
    for s in samples:
        if s.sunlight == Sunlight.NO and s.ground_linear is not None:
            # The sky alone: pi W vl = pi ground / albedo.
            sky = np.asarray(s.ground_linear, dtype=np.float64) / (ground_albedo * vl)
            out[s.frame] = FrameLight(s.frame, (0.0, 0.0, 0.0), _rgb(sky))
    return [out[f] for f in sorted(out)]
