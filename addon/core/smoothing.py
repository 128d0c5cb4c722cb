"""Smoothing of the per-frame Sun angles (thesis §5, "online" and "two-pass").

bpy-free, numpy only. Every function takes frame numbers, raw values (None or
NaN where a frame has no estimate) and weights (confidence), and returns a
value for every frame. Azimuths are unwrapped before fitting and wrapped to
[0, 360) after.
"""

from __future__ import annotations

from typing import List, Optional, Sequence

import numpy as np

from . import angles


# Two-pass local smoothing takes at most this many frames' span on either
# side of a frame (see two_pass_local_directions).
MAX_HALF_WINDOW_FRAMES = 64


def _arrays(frames, values, weights):
    t = np.asarray(frames, dtype=float)
    v = np.array([np.nan if x is None else float(x) for x in values], dtype=float)
    w = np.asarray(weights, dtype=float) if weights is not None else np.ones_like(v)
    if not (len(t) == len(v) == len(w)):
        raise ValueError(f"{len(t)} times, {len(v)} values and {len(w)} weights")
    # A NaN time or weight would reach LAPACK inside polyfit, whose error
    # handler ends the process (Blender included): such samples carry no weight.
    # Angles beyond 1e9 deg are garbage whose squares overflow in the fit.
    ok = np.isfinite(v) & (np.abs(np.nan_to_num(v)) < 1e9) & np.isfinite(t) & np.isfinite(w)
    w = np.where(ok & (w > 0), w, 0.0)
    return t, v, w


def _safe_degree(x_good, degree):
    """The polynomial degree the samples can carry: one less than the number
    of distinct times (`x_good` normalised, spread at most about 1). Samples
    all at one time (a date-only times column) make a Vandermonde matrix of
    zero columns, which polyfit scales by 0/0 and LAPACK then aborts on; a
    constant is all such data can give."""
    distinct = len(np.unique(np.round(x_good, 6)))
    return int(max(0, min(degree, distinct - 1)))


def unwrap_deg(values: Sequence[Optional[float]]) -> np.ndarray:
    """Unwraps angles in degrees across missing entries."""
    v = np.array([np.nan if x is None else float(x) for x in values], dtype=float)
    good = np.isfinite(v)
    if good.any():
        v[good] = np.degrees(np.unwrap(np.radians(v[good])))
    return v


def online(frames, values, weights=None, alpha=0.3, window=15):
    """The thesis's online mode: exponential smoothing of the incoming values,
    then a linear regression over the last `window` smoothed values, evaluated
    at the current frame (it removes the lag of the exponential filter).
    Causal: frame k uses frames <= k only. Frames before the first estimate
    get None."""
    t, v, w = _arrays(frames, values, weights)
    out: List[Optional[float]] = []
    s = None
    hist_t, hist_s = [], []
    for k in range(len(t)):
        if w[k] > 0:
            s = v[k] if s is None else alpha * v[k] + (1 - alpha) * s
            hist_t.append(t[k])
            hist_s.append(s)
            hist_t, hist_s = hist_t[-window:], hist_s[-window:]
        if s is None:
            out.append(None)
            continue
        if len(hist_t) >= 3 and np.ptp(hist_t) > 1e-6 and np.isfinite(t[k]) and \
                np.all(np.isfinite(hist_s)):
            # The line in closed form: polyfit's LAPACK call aborts the
            # process on times only 1e-160 apart.
            ht, hs = np.asarray(hist_t), np.asarray(hist_s)
            d = ht - ht.mean()
            slope = float(d @ (hs - hs.mean()) / (d @ d))
            icpt = float(hs.mean() - slope * ht.mean())
            # Exponential smoothing lags by (1-alpha)/alpha samples on a ramp.
            lag = (1 - alpha) / alpha
            step = (hist_t[-1] - hist_t[0]) / max(1, len(hist_t) - 1)
            out.append(float(slope * (t[k] + lag * step) + icpt))
        else:
            out.append(float(s))
    return out


def two_pass(frames, values, weights=None, degree=1, iterations=6):
    """Fits the whole clip with a polynomial in time (degree 1 is the thesis's
    "linear curves"), robustly (Huber-weighted iterations), weighted by
    confidence. Returns None everywhere when nothing was estimated."""
    t, v, w = _arrays(frames, values, weights)
    good = w > 0
    if good.sum() == 0:
        return [None] * len(t)
    t0, span = t[good].mean(), max(1.0, np.ptp(t[good]))
    x = np.where(np.isfinite(t), (t - t0) / span, 0.0)
    degree = _safe_degree(x[good], degree)
    robust = np.ones_like(w)
    coef = None
    for _ in range(iterations):
        ww = w * robust
        coef = np.polyfit(x[good], v[good], degree, w=np.sqrt(ww[good]))
        r = v - np.polyval(coef, x)
        scale = 1.4826 * np.median(np.abs(r[good])) + 1e-6
        k = 1.5 * scale
        a = np.abs(np.nan_to_num(r))
        robust = np.where(a <= k, 1.0, k / np.maximum(a, 1e-12))
    if coef is None:
        raise ValueError(f"iterations must be at least 1, not {iterations}")
    return [float(y) for y in np.polyval(coef, x)]


def _unit_vectors(zenith_deg: np.ndarray, azimuth_deg: np.ndarray) -> np.ndarray:
    return angles.sun_in_world_from_angles(zenith_deg, azimuth_deg)


def two_pass_directions(frames, zenith, azimuth, weights=None, degree=3, iterations=6):
    """Two-pass smoothing of the Sun's direction rather than of its angles:
    the unit vector's three components are fitted with polynomials in time
    (robustly, Huber weights on the angle between each raw and fitted Sun)
    and the fit is normalised. Returns (zenith list, azimuth list).

    Departs from the thesis, which fits each angle with a line: near the
    zenith the azimuth swings through tens of degrees in an hour (at the
    tropics around noon), which no low polynomial in azimuth follows, while
    the direction's components stay smooth there (sinusoids of the hour
    angle). On the rendered tropic-noon preset this took the largest
    azimuth error (the last frames, Sun 9 deg from the zenith) from 2.14 to
    0.46 deg (bench/accuracy.py, our own initial Sun)."""
    t, z, w = _arrays(frames, zenith, weights)
    _, a, w_a = _arrays(frames, azimuth, weights)
    w = np.where(w_a > 0, w, 0.0)
    good = w > 0
    if good.sum() == 0:
        return [None] * len(t), [None] * len(t)
    t0, span = t[good].mean(), max(1.0, np.ptp(t[good]))
    x = np.where(np.isfinite(t), (t - t0) / span, 0.0)
    degree = _safe_degree(x[good], degree)
    raw = np.zeros((len(t), 3))
    raw[good] = _unit_vectors(z[good], a[good])
    robust = np.ones_like(w)
    fitted = None
    for _ in range(iterations):
        sw = np.sqrt(w * robust)
        coefs = [np.polyfit(x[good], raw[good, k], degree, w=sw[good]) for k in range(3)]
        fitted = np.stack([np.polyval(c, x) for c in coefs], axis=1)
        fitted /= np.maximum(np.linalg.norm(fitted, axis=1, keepdims=True), 1e-12)
        cross = np.linalg.norm(np.cross(raw, fitted), axis=1)
        r = np.degrees(np.arctan2(cross, np.sum(raw * fitted, axis=1)))
        scale = 1.4826 * np.median(r[good]) + 1e-6
        k = 1.5 * scale
        robust = np.where(r <= k, 1.0, k / np.maximum(r, 1e-12))
    if fitted is None:
        raise ValueError(f"iterations must be at least 1, not {iterations}")
    zen, azi = angles.angles_from_sun_in_world(fitted)
    return [float(v) for v in zen], [float(v) for v in azi]


def online_directions(frames, zenith, azimuth, weights=None, **kw):
    """The online mode run on the Sun's direction: each component of its unit
    vector is smoothed causally (`online`), the result normalised. Near the
    zenith it follows the azimuth's swing where smoothing the azimuth itself
    lags (a synthetic tropical morning: azimuth error max 5.0 -> 1.2 deg).
    Returns (zenith list, azimuth list), None before the first estimate."""
    t, z, w = _arrays(frames, zenith, weights)
    _, a, w_a = _arrays(frames, azimuth, weights)
    w = np.where(w_a > 0, w, 0.0)
    good = w > 0
    raw = np.full((len(t), 3), np.nan)
    raw[good] = _unit_vectors(z[good], a[good])
    comps = [online(t, [None if not good[i] else raw[i, k] for i in range(len(t))], w, **kw)
             for k in range(3)]
    zen: List[Optional[float]] = []
    azi: List[Optional[float]] = []
    for i in range(len(t)):
        if comps[0][i] is None:
            zen.append(None)
            azi.append(None)
            continue
        u = np.array([comps[k][i] for k in range(3)])
        z, a = angles.angles_from_sun_in_world(u / max(float(np.linalg.norm(u)), 1e-12))
        zen.append(float(z))
        azi.append(float(a))
    return zen, azi


def smooth_angles(frames, zenith, azimuth, weights, mode, degree=1, times_s=None,
                  space="angles", **kw):
    """Smooths zenith and azimuth together; returns (zenith list, azimuth list).

    `times_s` (seconds, one per frame), when the capture times are known,
    replaces the frame numbers as the time axis: the fit then follows real
    time through irregular steps and repeated captures, and frames are taken
    in the order they were shot (an out-of-order frame is smoothed where it
    belongs; the online mode is causal in capture time).

    `space` "directions" smooths the Sun's direction (two_pass_directions,
    online_directions) instead of each angle (the thesis's way)."""
    if space not in ("angles", "directions"):
        raise ValueError(f"smoothing space {space!r} is not one of angles, directions")
    n = len(frames)
    if times_s is not None and len(times_s) != n:
        raise ValueError(f"{len(times_s)} times for {n} frames")
    if times_s is not None and (n < 2 or not np.all(np.isfinite(times_s))
                                or np.ptp(np.asarray(times_s, float)) == 0):
        # Every frame at one time (a date-only times column): time cannot
        # order or space them, the frame numbers still can.
        times_s = None
    order = list(range(n)) if times_s is None else \
        sorted(range(n), key=lambda i: (times_s[i], frames[i]))
    x = [frames[i] if times_s is None else times_s[i] for i in order]
    z_in = [zenith[i] for i in order]
    a_in = [azimuth[i] for i in order]
    w_in = None if weights is None else [weights[i] for i in order]
    az = unwrap_deg(a_in)
    if mode == "online" and space == "directions":
        z_s, a_s = online_directions(x, z_in, a_in, w_in, **kw)
    elif mode == "online":
        z_s = online(x, z_in, w_in, **kw)
        a_s = online(x, list(az), w_in, **kw)
    elif mode == "two_pass" and space == "directions":
        z_s, a_s = two_pass_directions(x, z_in, a_in, w_in, degree=degree)
    elif mode == "two_pass":
        z_s = two_pass(x, z_in, w_in, degree=degree)
        a_s = two_pass(x, list(az), w_in, degree=degree)
    else:
        raise ValueError(f"smoothing mode {mode!r} is not one of online, two_pass")
    z_out, a_out = [None] * n, [None] * n
    for k, i in enumerate(order):
        z_out[i] = z_s[k]
        a_out[i] = None if a_s[k] is None else angles.wrap_azimuth_deg(a_s[k])
    return z_out, a_out


# Frames whose local fits are solved at once (_local_fits): their
# neighbourhoods, padded to the widest, cost memory in proportion.
LOCAL_FIT_CHUNK = 1024


def _local_fits(t, order, lo, hi, windows, weights, values, max_degree=2):
    """Each frame's local polynomial fit (two_pass_local_directions) of
    `values` ((n, 3)) over its neighbours order[lo[i]:hi[i]] (sorted by
    time), weighted by the tricube kernel over windows[i] and `weights`, at
    the frame itself: (n, 3), NaN rows where no neighbour has weight. A
    quadratic where the frame has at least 6 weighted neighbours and 3 on
    each side; at a segment's ends it would swing on the last few values,
    so a line there (at least 3); never more terms than distinct times, nor
    than max_degree allows.
    Solved from the kernel-weighted moments, all frames at once (a least
    squares call per frame was most of the smoothing's time)."""
    n = len(t)
    out = np.full((n, 3), np.nan)
    for first in range(0, n, LOCAL_FIT_CHUNK):
        rows = np.arange(first, min(n, first + LOCAL_FIT_CHUNK))
        width = int(np.max(hi[rows] - lo[rows]))
        if width <= 0:
            continue
        slot = lo[rows][:, None] + np.arange(width)[None, :]
        inside = slot < hi[rows][:, None]
        near = order[np.where(inside, slot, 0)]
        d = (t[near] - t[rows][:, None]) / windows[rows][:, None]
        kern = np.where(inside, _tricube(np.where(inside, d, 0.0)) * weights[near], 0.0)
        sel = kern > 0
        m = sel.sum(axis=1)
        # Distinct times among the weighted neighbours: sorted by time, a
        # new one where the time differs from the last weighted one's.
        last = np.maximum.accumulate(np.where(sel, d, -np.inf), axis=1)
        before = np.concatenate([np.full((len(rows), 1), -np.inf), last[:, :-1]], axis=1)
        distinct = (sel & (d > before)).sum(axis=1)
        sides = np.minimum((sel & (d < 0)).sum(axis=1), (sel & (d > 0)).sum(axis=1))
        degree = np.minimum(np.where((m >= 6) & (sides >= 3), 2, np.where(m >= 3, 1, 0)),
                            np.minimum(distinct - 1, max_degree))
        dk = np.where(sel, d, 0.0)
        # Only the moments the highest degree asked for needs (most of the
        # fits' time over a long clip).
        powers = [kern * dk ** k for k in range(2 * max_degree + 1)]
        moments = np.stack([p.sum(axis=1) for p in powers], axis=1)
        y = values[near]
        sums = np.stack([np.einsum("ij,ijc->ic", powers[k], y) for k in range(max_degree + 1)],
                        axis=1)
        for deg in range(max_degree + 1):
            pick = np.flatnonzero((degree == deg) & (m > 0))
            if len(pick):
                terms = deg + 1
                a = np.stack([moments[pick, i:i + terms] for i in range(terms)], axis=1)
                b = sums[pick, :terms, :]
                try:
                    out[rows[pick]] = np.linalg.solve(a, b)[:, 0, :]
                except np.linalg.LinAlgError:  # times a rounding apart: least squares
                    out[rows[pick]] = [np.linalg.lstsq(ai, bi, rcond=None)[0][0]
                                       for ai, bi in zip(a, b)]
    return out


# The finest height spread a frame's Sun can have (deg; the tracker's
# elevation_pinned_deg steps): a frame's weight in the height's correction
# is (this / its spread) squared, an inverse variance.
FINEST_HEIGHT_SPREAD_DEG = 0.5
# The spread of a height no shadow in view pins (the tracker's steps stop at
# 8 deg; the track's sun_height_pinned_deg writes this too).
UNPINNED_HEIGHT_SPREAD_DEG = 90.0
# The pinned Suns' own scatter in height (deg): the best-pinned raw Suns are
# within 2 deg of the truth 97% of the time on the static suite. The
# height's correction c is shrunk to c * c^2 / (c^2 + this^2): one pinned
# frame 1.65 deg off moved five well-fitted frames of walls23 by 1.5 deg
# unshrunk, where urban15's unpinned frames were 4-10 deg too low.
HEIGHT_SCATTER_DEG = 2.0


def _heights_pinned(t, z, w, good, height_spread_deg, zen, windows):
    """two_pass_local_directions' zeniths corrected toward the frames whose
    shadows pin the height best: each frame's correction is the kernel-
    weighted mean, over its neighbours, of raw minus fitted zenith, each
    frame weighted by the inverse square of its height's spread. A mean,
    not a line: one pinned frame among many unpinned ones sets the level,
    and a slope from the unpinned ones' scatter would swing at a segment's
    ends. The direction's fit already follows the Sun's motion (and the
    prior); among frames alike the correction is none, and within the
    pinned Suns' own scatter it is shrunk (HEIGHT_SCATTER_DEG). Not the
    direction's robust weights: where the unpinned Suns are many and low,
    they count the few pinned ones as outliers."""
    spread = np.array([np.nan if v is None else float(v) for v in height_spread_deg])
    spread = np.where(np.isfinite(spread), np.maximum(spread, FINEST_HEIGHT_SPREAD_DEG),
                      UNPINNED_HEIGHT_SPREAD_DEG)
    if np.ptp(spread[good]) == 0:
        return zen
    order, lo, hi, win = windows
    residual = np.zeros((len(t), 3))
    residual[good, 0] = z[good] - zen[good]
    hw = (FINEST_HEIGHT_SPREAD_DEG / spread) ** 2
    correction = np.nan_to_num(_local_fits(t, order, lo, hi, win, w * hw, residual,
                                           max_degree=0)[:, 0])
    correction = correction ** 3 / (correction ** 2 + HEIGHT_SCATTER_DEG ** 2)
    return np.clip(zen + correction, 0.0, 180.0)


def _tricube(d):
    """The local fits' tricube kernel at offsets d, in half windows (the
    callers take only the frames within the window, |d| < 1)."""
    return (1.0 - np.abs(d) ** 3) ** 3


# Where a frame's neighbours carry little confidence, its window widens (by
# WINDOW_GROWTH steps, up to MAX_HALF_WINDOW_FRAMES) until their mean
# confidence, weighted by the kernel as the fit weighs them, is at least
# this share of the segment's median (two_pass_local_directions, with a
# prior path only).
WINDOW_CONFIDENCE = 0.75
WINDOW_GROWTH = 1.25


def two_pass_local_directions(frames, zenith, azimuth, weights=None, half_window=None,
                              iterations=4, prior_zenith=None, prior_azimuth=None,
                              height_spread_deg=None):
    """Two-pass smoothing of the Sun's direction by local quadratics: at
    every frame, the unit vector's components are fitted over its neighbours
    in time (tricube kernel, the weights, robust bisquare weights on the
    angle between raw and fitted Sun from the previous pass), and the fit's
    value there is normalised. Returns (zenith list, azimuth list).

    Departs from one polynomial over the whole clip (thesis: a line per
    angle; two_pass_directions: a cubic per component): over a long day the
    Sun's path is no low polynomial, so a global fit is off by more than the
    measurements' noise where they are good; a local fit follows any smooth
    path and still averages the noise and rejects outliers. `half_window`
    (in the frames' units) defaults to enough of the clip for six measured
    frames on either side, at least an eighth of the span.

    `prior_zenith`/`prior_azimuth` (one per frame, e.g. the segment's Sun
    circle) give a path whose shape the fit borrows: the local fits run on
    the raw Suns' offsets from it, and where the frames around carry little
    confidence the window widens (WINDOW_CONFIDENCE) so that confident
    frames further away carry the fit. Without a prior the window stays
    fixed: a widened window at a segment's end is one-sided, and the line
    fitted there through a curving path ran 11 deg off (Marseille March,
    azimuth at sunset); offsets from the circle stay nearly constant, so
    the wider fit no longer extrapolates the path's curve. A run of doubted
    frames (suite scene 23: five at confidence 0.07-0.18, 5-7 deg off)
    otherwise steers a fixed window's fit of its own.

    `height_spread_deg` (one per frame): how far each frame's Sun could
    move in height unnoticed (a tracked Sun whose shadows' tips are out of
    view: any lower Sun fits them alike, UNPINNED_HEIGHT_SPREAD_DEG; None:
    not measured, the same). The
    azimuths count as any frame's, and the height is corrected toward the
    frames that pin it best (_heights_pinned).
    """
    t, z, w = _arrays(frames, zenith, weights)
    _, a, w_a = _arrays(frames, azimuth, weights)
    w = np.where(w_a > 0, w, 0.0)
    good = w > 0
    n = len(t)
    if not good.any():
        return [None] * n, [None] * n
    raw = np.zeros((n, 3))
    raw[good] = _unit_vectors(z[good], a[good])
    base = np.zeros((n, 3))  # the prior's Suns: the fits run on raw - base
    adaptive = False
    if prior_zenith is not None and prior_azimuth is not None:
        _, pz, pw = _arrays(frames, prior_zenith, None)
        _, pa, pw_a = _arrays(frames, prior_azimuth, None)
        if np.all(pw > 0) and np.all(pw_a > 0):  # a prior only where it covers every frame
            base = _unit_vectors(pz, pa)
            adaptive = half_window is None
    span = float(np.ptp(t[good]))
    step = span / max(1, int(good.sum()) - 1)
    widest = MAX_HALF_WINDOW_FRAMES * step
    if half_window is None:
        # On long clips an eighth of the span holds thousands of frames: at
        # most MAX_HALF_WINDOW_FRAMES on a side average the noise as well.
        half_window = min(max(span / 8.0, 6.5 * step), widest)
    half_window = max(float(half_window), 1e-9)
    # Each frame's neighbours within its window, by sorted time (only they
    # have kernel weight; the fits cost the window, not the clip).
    order = np.argsort(t, kind="stable")
    ts = t[order]
    windows = np.full(n, half_window)
    if adaptive:
        need = WINDOW_CONFIDENCE * float(np.median(w[good]))
        for i in range(n):
            h = half_window
            while h < widest:
                near = order[np.searchsorted(ts, t[i] - h, side="right"):
                             np.searchsorted(ts, t[i] + h, side="left")]
                kern = _tricube((t[near] - t[i]) / h)
                if float(kern @ w[near]) >= need * float(kern.sum()):
                    break
                h = min(widest, WINDOW_GROWTH * h)
            windows[i] = h
    robust = np.ones(n)
    lo = np.searchsorted(ts, t - windows, side="right")
    hi = np.searchsorted(ts, t + windows, side="left")
    for _ in range(iterations):
        fitted = _local_fits(t, order, lo, hi, windows, w * robust, raw - base)
        # No measured neighbour: the nearest measured frame.
        for i in np.flatnonzero(np.isnan(fitted[:, 0])):
            j = int(np.flatnonzero(good)[np.argmin(np.abs(t[good] - t[i]))])
            fitted[i] = raw[j] - base[j]
        fitted += base
        fitted /= np.maximum(np.linalg.norm(fitted, axis=1, keepdims=True), 1e-12)
        cross = np.linalg.norm(np.cross(raw, fitted), axis=1)
        r = np.degrees(np.arctan2(cross, np.sum(raw * fitted, axis=1)))
        scale = 1.4826 * float(np.median(r[good])) + 1e-3
        c = 4.685 * scale
        robust = np.where(r < c, (1.0 - (r / c) ** 2) ** 2, 0.0)
    zen, azi = angles.angles_from_sun_in_world(fitted)
    if height_spread_deg is not None:
        if len(height_spread_deg) != n:
            raise ValueError(f"{n} frames and {len(height_spread_deg)} height spreads")
        zen = _heights_pinned(t, z, w, good, height_spread_deg, zen,
                              (order, lo, hi, windows))
    return [float(v) for v in zen], [float(v) for v in azi]
