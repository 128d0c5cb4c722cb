"""One frame's raw Sun: what a method measured before smoothing."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional, Tuple

from ..core.trackfile import Sunlight


@dataclass
class RawSun:
    """A frame's raw Sun in the track's terms: zenith and geographic azimuth
    (degrees, clockwise from north as the track's north_offset_deg says), or
    None for both with the reason. tracked: the native TrackedFrame behind
    it (its shadow's ends, sun/ambient contrast and misfit), when the tracker
    refined it. sunlight: direct sunlight on the frame, where the method
    decides it (a frame without it has no raw Sun: finish.py predicts one).
    shadows_in_view: False where a moving camera looks away from where the
    model's shadows fall (the frame could not show the Sun).
    clock_sun: (zenith, geographic azimuth) the ephemeris gives for the
    frame's capture time and place, where both are known and the clock is
    not contradicted by the footage; clock_night: the clock puts the frame
    at night (its predicted Sun is clock_sun, below the horizon).
    circle_checked: whether a circle of the Sun's path checked the Sun (the
    whole-clip estimate's; None where the method has no such check).
    height_spread_deg: how far the tracker's Sun could move in height
    unnoticed (TrackedFrame.elevation_pinned_deg; 90 where its shadows'
    tips are out of view, so any lower Sun fits them alike), None where the
    tracker did not refine it (a path's grid cell pins no height either).
    The smoothing weighs the height by it."""
    frame: int
    zenith_deg: Optional[float] = None
    azimuth_deg: Optional[float] = None
    confidence: float = 0.0
    reason: Optional[str] = None
    tracked: Any = None
    sunlight: Optional[Sunlight] = None
    clock_sun: Optional[Tuple[float, float]] = None
    clock_night: bool = False
    shadows_in_view: bool = True
    circle_checked: Optional[bool] = None
    height_spread_deg: Optional[float] = None

    @property
    def has_sun(self) -> bool:
        return self.zenith_deg is not None and self.azimuth_deg is not None
