"""Physical smoothing: the Sun's true path fitted through the raw angles.

When the user knows roughly where and when the clip was shot (date, start
time, seconds per frame, place), the smoothest possible Sun is the real one.
This fits latitude, a time offset (it also absorbs longitude and clock
errors: 1 deg of longitude = 4 min) and the scene's north offset to the raw
per-frame angles, robustly and weighted by confidence, with weak priors that
keep the user's values where the clip cannot tell (a short clip barely
separates latitude from time). The fitted path then gives every frame's Sun,
with geographic azimuths and the fitted north offset (docs/track-format.md).

bpy- and native-free: the ephemeris comes in as a function, so tests can use
an independent one.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field
from typing import Callable, List, Optional, Sequence, Tuple

import numpy as np

from . import angles

# sun_position(utc_datetime, latitude_deg, longitude_deg) -> (zenith, azimuth)
SunModel = Callable[[dt.datetime, float, float], Tuple[float, float]]


@dataclass
class PathFit:
    success: bool
    message: str = ""
    latitude_deg: float = 0.0
    longitude_deg: float = 0.0
    time_offset_s: float = 0.0
    north_offset_deg: float = 0.0
    rms_deg: float = 0.0           # robust RMS of the angular residuals
    zenith_deg: List[float] = field(default_factory=list)
    azimuth_deg: List[float] = field(default_factory=list)   # geographic


def _wrap(a):
    return angles.wrap_signed_deg(np.asarray(a))


def fit_sun_path(times: Sequence[dt.datetime], zenith: Sequence[Optional[float]],
                 azimuth_world: Sequence[Optional[float]], weights: Sequence[float],
                 sun_position: SunModel, latitude_deg: float, longitude_deg: float,
                 latitude_sigma_deg: float = 3.0, time_sigma_s: float = 900.0,
                 fit_latitude: bool = True) -> PathFit:
    # Degenerate inputs end as a failed fit with a reason (the caller falls
    # back), never as NaNs reaching the solver.
    if not (isinstance(latitude_deg, (int, float)) and math.isfinite(latitude_deg)
            and -90.0 <= latitude_deg <= 90.0):
        return PathFit(False, f"latitude {latitude_deg} is not in [-90, 90]")
    if not (isinstance(longitude_deg, (int, float)) and math.isfinite(longitude_deg)
            and -180.0 <= longitude_deg <= 360.0):
        return PathFit(False, f"longitude {longitude_deg} is not in [-180, 360]")
    if not (len(times) == len(zenith) == len(azimuth_world) == len(weights)):
        return PathFit(False, "times, angles and weights differ in number")
    z_obs = np.array([np.nan if v is None else v for v in zenith], float)
    a_obs = np.array([np.nan if v is None else v for v in azimuth_world], float)
    w_in = np.array([np.nan if v is None else v for v in weights], float)
    w = np.where(np.isfinite(z_obs) & np.isfinite(a_obs) & np.isfinite(w_in) & (w_in > 0),
                 w_in, 0.0)
    use = np.flatnonzero(w > 0)
    if len(use) < 3:
        return PathFit(False, "fewer than 3 frames with an estimate: nothing to fit")
    if len({times[i] for i in use}) < 2:
        return PathFit(False, "every frame has the same time: the Sun's path cannot be "
                              "fitted (check the seconds per frame or the times file)")
    try:
        return _fit(times, z_obs, a_obs, w, use, sun_position, latitude_deg, longitude_deg,
                    latitude_sigma_deg, time_sigma_s, fit_latitude)
    except (np.linalg.LinAlgError, OverflowError, ValueError) as e:
        return PathFit(False, f"the fit did not converge ({e})")


def _fit(times, z_obs, a_obs, w, use, sun_position, latitude_deg, longitude_deg,
         latitude_sigma_deg, time_sigma_s, fit_latitude) -> PathFit:

    def model(lat, dt_s, idx):
        out = np.empty((len(idx), 2))
        for k, i in enumerate(idx):
            out[k] = sun_position(times[i] + dt.timedelta(seconds=dt_s), lat, longitude_deg)
        return out

    def north_for(zm, am, idx):
        d = _wrap(a_obs[idx] - am)
        ww = w[idx] * np.sin(np.radians(zm)) ** 2
        return math.degrees(math.atan2((ww * np.sin(np.radians(d))).sum(),
                                       (ww * np.cos(np.radians(d))).sum()))

    def residuals(p, idx, robust):
        lat, dt_s, north = p
        m = model(lat, dt_s, idx)
        rz = z_obs[idx] - m[:, 0]
        ra = _wrap(a_obs[idx] - m[:, 1] - north) * np.sin(np.radians(m[:, 0]))
        sw = np.sqrt(w[idx] * robust)
        r = np.concatenate([rz * sw, ra * sw])
        prior = [(lat - latitude_deg) / latitude_sigma_deg if fit_latitude else 0.0,
                 dt_s / time_sigma_s]
        return np.concatenate([r, prior]), rz, ra

    # Coarse start: a grid over latitude and time on a subsample of frames,
    # with the north offset solved in closed form at each node.
    sub = use[np.linspace(0, len(use) - 1, min(len(use), 16)).astype(int)]
    lats = np.arange(-12, 12.01, 3.0) + latitude_deg if fit_latitude else [latitude_deg]
    best = None
    for lat in lats:
        if abs(lat) > 89:
            continue
        for dt_s in np.arange(-3600, 3601, 600.0):
            m = model(lat, dt_s, sub)
            north = north_for(m[:, 0], m[:, 1], sub)
            r, _, _ = residuals((lat, dt_s, north), sub, np.ones(len(sub)))
            cost = float(r @ r)
            if best is None or cost < best[0]:
                best = (cost, np.array([lat, dt_s, north]))
    if best is None or not np.isfinite(best[0]):
        return PathFit(False, "no Sun path near the given place and time fits the angles")
    p = best[1]
    # Levenberg-Marquardt on all frames, Huber-reweighted.
    robust = np.ones(len(use))
    lam = 1e-2
    steps = np.array([1e-3, 1.0, 1e-3])
    for outer in range(4):
        for _ in range(30):
            r0, rz, ra = residuals(p, use, robust)
            J = np.empty((len(r0), 3))
            for j in range(3):
                if j == 0 and not fit_latitude:
                    J[:, 0] = 0.0
                    continue
                dp = np.zeros(3)
                dp[j] = steps[j]
                J[:, j] = (residuals(p + dp, use, robust)[0] - r0) / steps[j]
            A = J.T @ J
            g = J.T @ r0
            improved = False
            if not (np.all(np.isfinite(A)) and np.all(np.isfinite(g))):
                break
            for _ in range(8):
                delta = -np.linalg.solve(A + lam * np.diag(np.diag(A) + 1e-9), g)
                cand = p + delta
                if (float(residuals(cand, use, robust)[0] @ residuals(cand, use, robust)[0])
                        < float(r0 @ r0)):
                    p, lam, improved = cand, max(lam / 3, 1e-6), True
                    break
                lam *= 4
            if not improved or np.all(np.abs(delta) < [1e-5, 0.01, 1e-5]):
                break
        _, rz, ra = residuals(p, use, robust)
        e = np.hypot(rz, ra)
        scale = 1.4826 * np.median(e) + 1e-6
        robust = np.where(e <= 2 * scale, 1.0, 2 * scale / np.maximum(e, 1e-12))
    lat, dt_s, north = p
    _, rz, ra = residuals(p, use, np.ones(len(use)))
    e = np.hypot(rz, ra)
    if not np.all(np.isfinite(p)):
        return PathFit(False, "the fit diverged")
    full = model(lat, dt_s, range(len(times)))
    fit = PathFit(True, "", float(lat), float(longitude_deg), float(dt_s),
                  angles.wrap_azimuth_deg(float(north)), float(np.sqrt(np.median(e ** 2))),
                  [float(v) for v in full[:, 0]],
                  [float(angles.wrap_azimuth_deg(v)) for v in full[:, 1]])
    if fit.rms_deg > 2.0:
        fit.message = (f"the raw angles do not follow a Sun path well (median residual "
                       f"{fit.rms_deg:.1f} deg): check date, time and place")
    return fit
