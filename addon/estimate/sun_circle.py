"""The Sun's small circle about the pole (native/include/sunlapse/sky/
sun_circle.h holds the fits and says what they do and why), as the estimate
asks for it: the whole-clip path's prior and the check of each frame's Sun
against its path (whole_clip.py, trimmed), physical smoothing without a
place (finish.py, with latitude, declination and north).

bpy-free; the fits are native (they were numpy code until issue 28, 0.8 s
of a 1,000-frame run).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, List, Optional, Sequence

import numpy as np

from . import native_loader
from ..core import angles


@dataclass
class CircleFit:
    success: bool = False
    message: str = ""
    latitude_deg: Optional[float] = None
    declination_deg: Optional[float] = None
    # World azimuth of true north (world = geographic + it).
    north_offset_deg: Optional[float] = None
    # Hour angle (deg, 0 at solar noon, positive in the afternoon) per time.
    hour_angle_deg: List[float] = field(default_factory=list)
    # The circle's Sun per time (world frame), and the robust residual (deg).
    zenith_deg: List[float] = field(default_factory=list)
    azimuth_world_deg: List[float] = field(default_factory=list)
    residual_deg: Optional[float] = None
    # Westward hour angle rate (deg per second with times: 15/h; else per
    # frame, fitted).
    rate_deg: Optional[float] = None


@dataclass
class TrimmedFit:
    success: bool = False
    message: str = ""
    # Per given time: the circle's Sun (world frame), and how far the given
    # Sun is from it (deg; None where no Sun was given).
    sun_in_world: List[np.ndarray] = field(default_factory=list)
    off_deg: List[Optional[float]] = field(default_factory=list)
    inliers: List[int] = field(default_factory=list)   # indices into the inputs
    residual_deg: Optional[float] = None    # median distance of the inliers


def min_frames() -> int:
    """Suns a trimmed fit needs (TrimmedCircleOptions.min_frames)."""
    return int(native_loader.require().TrimmedCircleOptions().min_frames)


def _suns_array(suns_in_world: Sequence[Any]) -> np.ndarray:
    out = np.full((len(suns_in_world), 3), np.nan)
    for i, s in enumerate(suns_in_world):
        if s is not None:
            out[i] = s
    return out


def fit_circle(times: Sequence[float], zenith_deg: Sequence[Optional[float]],
               azimuth_world_deg: Sequence[Optional[float]],
               weights: Optional[Sequence[float]] = None,
               times_are_seconds: bool = True) -> CircleFit:
    """The Sun's small circle through measured Suns. `times`: seconds (the
    rate is then 15 deg/h) or frame numbers (times_are_seconds False: the
    rate is fitted). Frames without angles are predicted too."""
    native = native_loader.require()
    suns = _suns_array([None if z is None or a is None else
                        angles.sun_in_world_from_angles(float(z), float(a))
                        for z, a in zip(zenith_deg, azimuth_world_deg)])
    fit = native.fit_sun_circle([float(t) for t in times], suns,
                                [] if weights is None else [float(w) for w in weights],
                                times_are_seconds=times_are_seconds)
    if fit.status != native.SunCircleStatus.SUCCESS:
        return CircleFit(message=fit.message)
    zenith, azimuth = angles.angles_from_sun_in_world(fit.sun_in_world)
    return CircleFit(
        success=True, message=fit.message, latitude_deg=fit.latitude_deg,
        declination_deg=fit.declination_deg, north_offset_deg=fit.north_offset_deg,
        hour_angle_deg=[float(h) for h in fit.hour_angle_deg],
        zenith_deg=[float(z) for z in np.atleast_1d(zenith)],
        azimuth_world_deg=[float(a) for a in np.atleast_1d(azimuth)],
        residual_deg=fit.residual_deg, rate_deg=fit.rate_deg)


def fit_trimmed(times: Sequence[float], suns_in_world: Sequence[Optional[Sequence[float]]],
                floor_deg: float, weights: Optional[Sequence[float]] = None,
                times_are_seconds: bool = True) -> TrimmedFit:
    """The circle through the given Suns (world frame; None: no Sun at that
    time), the far ones left out. `floor_deg`: the inlier limit never falls
    below this (deg)."""
    native = native_loader.require()
    fit = native.fit_trimmed_sun_circle(
        [float(t) for t in times], _suns_array(suns_in_world), float(floor_deg),
        [] if weights is None else [float(w) for w in weights],
        circle_options=native.SunCircleOptions(times_are_seconds=times_are_seconds))
    if fit.status != native.SunCircleStatus.SUCCESS:
        return TrimmedFit(message=fit.message)
    return TrimmedFit(
        success=True, message=fit.message, sun_in_world=list(fit.sun_in_world),
        off_deg=[None if np.isnan(d) else float(d) for d in fit.off_deg],
        inliers=list(fit.inliers), residual_deg=fit.residual_deg)
