"""One frame's raw Sun: what a method measured before smoothing."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Optional


@dataclass
class RawSun:
    """A frame's raw Sun in the track's terms: zenith and geographic azimuth
    (degrees, clockwise from north as the track's north_offset_deg says), or
    None for both with the reason. tracked: the native TrackedFrame behind
    it (its shadow's ends and sun/ambient contrast), when the tracker
    refined it."""
    frame: int
    zenith_deg: Optional[float] = None
    azimuth_deg: Optional[float] = None
    confidence: float = 0.0
    reason: Optional[str] = None
    tracked: Any = None

    @property
    def has_sun(self) -> bool:
        return self.zenith_deg is not None and self.azimuth_deg is not None
