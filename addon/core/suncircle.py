"""The Sun's path without place or date: a small circle about the pole.

Over a day the Sun turns about the celestial pole at 15 deg per hour on a
circle of constant declination. Fitted to the measured Suns (world frame),
that circle gives, with no place, date or compass known (in the spirit of
Junejo & Foroosh, ECCV 2008, geo-temporal localisation from shadows):
- the pole's elevation above the horizon: the latitude;
- the pole's azimuth in the scene: where true north is (the north offset);
- the circle's angular radius: the declination, i.e. the date up to the
  two days a year that share it;
- the hour angle at each frame: solar time.
Its values at the frames are a smoothing that knows how the Sun moves.
When the place and date are known this is the ephemeris fit of sunpath.py.

bpy-free, numpy only (a small Levenberg-Marquardt; Blender's Python has no
scipy).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import List, Optional, Sequence

import numpy as np

from . import angles

# The Sun's hour angle advances 15 deg per hour of (mean) solar time.
DEG_PER_HOUR = 15.0
# A fit has settled when a step moves no parameter (radians, or radians per
# time unit) by more than this, and its robust weights change by less than
# SETTLED_WEIGHT when refreshed: the steps left would change its Suns by
# less than 1e-7 deg.
SETTLED_STEP_RAD = 1e-10
SETTLED_WEIGHT = 1e-9


@dataclass
class CircleFit:
    success: bool = False
    message: str = ""
    latitude_deg: Optional[float] = None
    declination_deg: Optional[float] = None
    # World azimuth of true north (the scene's +Y turned by this from north,
    # as the Sun Position add-on's north offset: world = geographic + it).
    north_offset_deg: Optional[float] = None
    # Hour angle (deg, 0 at solar noon, positive in the afternoon) per frame.
    hour_angle_deg: List[Optional[float]] = field(default_factory=list)
    # The fitted Sun per frame (world frame), and the robust residual (deg).
    zenith_deg: List[Optional[float]] = field(default_factory=list)
    azimuth_world_deg: List[Optional[float]] = field(default_factory=list)
    residual_deg: Optional[float] = None
    # Westward hour angle rate (deg per second with times: 15/h; else per
    # frame, fitted).
    rate_deg: Optional[float] = None


def _unit(zenith_deg, azimuth_deg) -> np.ndarray:
    return angles.sun_in_world_from_angles(zenith_deg, azimuth_deg)


def _basis(pole_zenith, pole_azimuth):
    """The pole p and the circle's plane's axes e1, e2. In plain floats: the
    fits call it thousands of times a run, where numpy's per-call cost was
    most of it."""
    sz, cz = math.sin(pole_zenith), math.cos(pole_zenith)
    sa, ca = math.sin(pole_azimuth), math.cos(pole_azimuth)
    p = np.array([sz * sa, sz * ca, cz])
    # e1: the pole's meridian toward the zenith side (hour angle 0 = noon,
    # the Sun's highest point); e2 = p x e1 points east, so the angle from
    # e1 toward e2 is minus the (westward) hour angle. up - (up.p) p is
    # sin(pz) (-cz sa, -cz ca, sz): e1 is that unit vector times the sign of
    # sin(pz), and e2 (ca, -sa, 0) times it.
    if abs(sz) <= 1e-9:
        e1 = np.array([1.0, 0.0, 0.0])
        return p, e1, angles.cross(p, e1)
    sign = 1.0 if sz > 0 else -1.0
    return p, np.array([-sign * cz * sa, -sign * cz * ca, abs(sz)]), \
        np.array([sign * ca, -sign * sa, 0.0])


def _model(params, t, rate, bases=None):
    """The Sun on the circle at times t. `bases`: a dict the pole's bases
    are kept in, by the pole's angles (a fit's Jacobian moves the other
    parameters four times out of six; the basis is most of the cost)."""
    pz, pa, dec, h0 = params[:4]
    r = params[4] if rate is None else rate
    if bases is None:
        p, e1, e2 = _basis(pz, pa)
    else:
        key = (float(pz), float(pa))
        if key not in bases:
            bases[key] = _basis(pz, pa)
        p, e1, e2 = bases[key]
    h = h0 + r * t
    return (math.cos(dec) * (np.cos(h)[:, None] * e1 + np.sin(h)[:, None] * e2)
            + math.sin(dec) * p[None, :])


def _jacobian(params, t, rate, root_w):
    """The model's derivatives by each parameter, weighted (root_w per
    Sun), as the residuals are laid out; None where the pole is at the
    zenith (the basis jumps there: the caller differentiates numerically).
    Analytic: the forward differences cost five evaluations of the model
    an iteration, most of a fit's time."""
    pz, pa, dec, h0 = (float(v) for v in params[:4])
    r = float(params[4]) if rate is None else rate
    sz, cz = math.sin(pz), math.cos(pz)
    if abs(sz) <= 1e-9:
        return None
    sa, ca = math.sin(pa), math.cos(pa)
    sign = 1.0 if sz > 0 else -1.0
    p, e1, e2 = _basis(pz, pa)
    h = h0 + r * t
    ch, sh = np.cos(h)[:, None], np.sin(h)[:, None]
    cd, sd = math.cos(dec), math.sin(dec)
    along = ch * e1 + sh * e2                 # the circle's unit radius toward the Sun
    ahead = cd * (ch * e2 - sh * e1)          # d/dh of the Sun
    # d e1/d pz = sign p, d e2/d pz = 0, d p/d pz = -sign e1;
    # d e1/d pa = sign (-cz ca, cz sa, 0), d e2/d pa = sign (-sa, -ca, 0),
    # d p/d pa = sz (ca, -sa, 0).
    d_pz = cd * sign * ch * p[None, :] - sd * sign * e1[None, :]
    d_pa = (cd * sign * (ch * np.array([-cz * ca, cz * sa, 0.0])
                         + sh * np.array([-sa, -ca, 0.0]))
            + sd * sz * np.array([ca, -sa, 0.0])[None, :])
    columns = [d_pz, d_pa, -sd * along + cd * p[None, :], ahead]
    if rate is None:
        columns.append(ahead * t[:, None])
    return np.stack([(c * root_w[:, None]).ravel() for c in columns], axis=1)


def _damped_step(jtj: np.ndarray, jtr: np.ndarray, lam: float) -> np.ndarray:
    """The Levenberg-Marquardt step. The damped normal matrix is positive
    definite but for a degenerate fit; solve is a fifth of lstsq's cost,
    which stays for those."""
    damped = jtj + lam * np.diag(np.diag(jtj) + 1e-9)
    try:
        return np.linalg.solve(damped, -jtr)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(damped, -jtr, rcond=None)[0]


def fit_circle(times: Sequence[float], zenith_deg: Sequence[Optional[float]],
               azimuth_world_deg: Sequence[Optional[float]],
               weights: Optional[Sequence[float]] = None, times_are_seconds: bool = True,
               iterations: int = 60) -> CircleFit:
    """Fits the Sun's small circle to measured Suns. `times`: seconds (real
    time, the rate is then 15 deg/h) or frame numbers (times_are_seconds
    False: the rate is fitted). Frames without angles are predicted too."""
    out = CircleFit()
    t_all = np.asarray(times, dtype=float)
    n = len(t_all)
    ok = np.array([z is not None and a is not None for z, a in zip(zenith_deg, azimuth_world_deg)])
    w = np.ones(n) if weights is None else np.asarray(weights, dtype=float)
    ok &= np.isfinite(t_all) & (w > 0)
    if ok.sum() < 4:
        out.message = f"needs at least 4 measured frames (has {int(ok.sum())})"
        return out
    t0 = float(np.median(t_all[ok]))
    scale = 3600.0 if times_are_seconds else 1.0
    t = (t_all - t0) / scale
    if np.ptp(t[ok]) <= 0:
        out.message = "the measured frames all have the same time"
        return out
    s = _unit(np.array([zenith_deg[i] for i in np.flatnonzero(ok)], float),
              np.array([azimuth_world_deg[i] for i in np.flatnonzero(ok)], float))
    tw, ww = t[ok], w[ok]
    # Start: the plane through the measured Suns; its normal is the pole.
    centre = (s * ww[:, None]).sum(0) / ww.sum()
    _, _, vt = np.linalg.svd((s - centre) * np.sqrt(ww)[:, None], full_matrices=False)
    p = vt[2]
    steps = np.cross(s[:-1], s[1:]) @ p
    # The Sun turns westward: clockwise about the north celestial pole.
    order = np.sign(np.sum(steps * np.sign(np.diff(tw))))
    if order > 0:
        p = -p
    # The angle about p from e1 toward e2 (east) falls as the Sun goes west.
    rate = None if not times_are_seconds else -math.radians(DEG_PER_HOUR)
    pz = math.acos(max(-1.0, min(1.0, p[2])))
    pa = math.atan2(p[0], p[1])
    dec = math.asin(max(-1.0, min(1.0, float(centre @ p)
                                  / max(1e-9, float(np.linalg.norm(centre))))))
    _, e1, e2 = _basis(pz, pa)
    hs = np.unwrap(np.arctan2(s @ e2, s @ e1))
    if rate is None:
        slope = np.polyfit(tw, hs, 1)[0] if np.ptp(tw) > 0 else 0.0
        params = np.array([pz, pa, dec, float(np.median(hs - slope * tw)), slope])
    else:
        params = np.array([pz, pa, dec, float(np.median(hs - rate * tw))])
    robust = np.ones(len(tw))
    lam: float = 1e-3
    bases: dict = {}

    def residuals(pr):
        return ((_model(pr, tw, rate, bases) - s) * np.sqrt(ww * robust)[:, None]).ravel()

    def jacobian(pr, r0):
        analytic = _jacobian(pr, tw, rate, np.sqrt(ww * robust))
        if analytic is not None:
            return analytic
        numeric = np.empty((len(r0), len(pr)))
        for k in range(len(pr)):
            d = np.zeros(len(pr))
            d[k] = 1e-6
            numeric[:, k] = (residuals(pr + d) - r0) / 1e-6
        return numeric

    # The residuals and the Jacobian at the current parameters, kept while
    # they hold: an accepted step's residuals are the next iteration's, and
    # a rejected step leaves both as they were (most of a fit's cost).
    r0: Optional[np.ndarray] = None
    jac: Optional[np.ndarray] = None
    # Settled: the last step moved no parameter by SETTLED_STEP_RAD; the
    # steps until the next robust weights would not move them either, so
    # they are skipped, and the fit ends when those weights hold too.
    settled = False
    for it in range(iterations):
        if not settled:
            if r0 is None:
                r0 = residuals(params)
            if jac is None:
                jac = jacobian(params, r0)
            step = _damped_step(jac.T @ jac, jac.T @ r0, lam)
            trial = params + step
            r1 = residuals(trial)
            if float(np.sum(r1 ** 2)) < float(np.sum(r0 ** 2)):
                params, lam = trial, lam * 0.3
                r0, jac = r1, None
            else:
                lam *= 10.0
            settled = float(np.max(np.abs(step))) < SETTLED_STEP_RAD
        if it % 10 == 9:  # robust weights (Huber on the angle), refreshed now and then
            ang = np.degrees(np.linalg.norm(_model(params, tw, rate) - s, axis=1))
            huber = 1.5 * (1.4826 * float(np.median(ang)) + 1e-3)
            weights_now = np.where(ang <= huber, 1.0, huber / np.maximum(ang, 1e-12))
            if settled and float(np.max(np.abs(weights_now - robust))) < SETTLED_WEIGHT:
                break
            robust = weights_now
            r0, jac, settled = None, None, False
    fit_all = _model(params, t, rate)
    ang = np.degrees(np.linalg.norm(_model(params, tw, rate) - s, axis=1))
    p, _, _ = _basis(params[0], params[1])
    out.success = True
    out.latitude_deg = math.degrees(math.asin(max(-1.0, min(1.0, float(p[2])))))
    out.declination_deg = math.degrees(params[2])
    out.north_offset_deg = angles.angles_from_sun_in_world(p)[1]
    hour = -np.degrees(params[3] + (params[4] if rate is None else rate) * t)
    out.hour_angle_deg = [float(angles.wrap_signed_deg(h)) for h in hour]
    zenith, azimuth = angles.angles_from_sun_in_world(np.asarray(fit_all))
    out.zenith_deg = [float(z) for z in zenith]
    out.azimuth_world_deg = [float(a) for a in azimuth]
    out.residual_deg = float(np.median(ang))
    out.rate_deg = -math.degrees(params[4] if rate is None else rate) / scale
    if abs(out.latitude_deg) > 89.0:
        out.message = "the pole is near the zenith: the fit cannot tell latitude from the path"
    return out
