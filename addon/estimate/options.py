"""What a run is asked to do: the method, the smoothing, the place and the
capture times (bpy-free)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional, Tuple

# The thesis reads the grayscale frame as shading as it is (§3.2); ours
# undoes the display gamma first, since the Lambertian model is linear.
GAMMA = {"thesis": 1.0, "default": 2.2}
# Two-pass smoothing: the thesis fits a straight line per angle; ours fits
# local quadratics to the Sun's direction (core.smoothing.
# two_pass_local_directions), which follow a whole day's path.
TWO_PASS_DEGREE = {"thesis": 1}
# Ours smooths the Sun's direction, not each angle (both the two-pass and the
# online mode): near the zenith the azimuth swings too fast for either
# (core.smoothing.two_pass_directions, online_directions).
SMOOTHING_SPACE = {"thesis": "angles", "default": "directions"}


class PipelineError(Exception):
    """The run cannot go on (unreadable clip, cancelled, ...): says why."""


@dataclass
class EstimateOptions:
    method: str = "default"           # "thesis" | "default"
    smoothing: str = "two_pass"        # "online" | "two_pass"
    ignore_top_rows: int = 0
    north_offset_deg: float = 0.0      # scene +Y from north (Sun Position add-on)
    ground_object_ids: List[int] = field(default_factory=list)
    # Given Sun on the first frame (zenith, azimuth as in the track file):
    # skips the initial estimate, to measure the tracker alone.
    initial_sun: Optional[Tuple[float, float]] = None
    # For smoothing "physical": the first frame's time (aware datetime), the
    # seconds between frames and the place (degrees, east positive).
    first_time: Optional[object] = None
    frame_seconds: Optional[float] = None
    latitude_deg: Optional[float] = None
    longitude_deg: Optional[float] = None
    # Capture time of each frame (scene frame number -> aware datetime), from
    # a times file: frames are then visited in the order they were taken and
    # smoothed over real time; physical smoothing needs no first_time or
    # frame_seconds then.
    frame_times: Optional[dict] = None
    # Physical smoothing fits the latitude too (about the given one, loosely);
    # False keeps the given latitude exactly (it is known, e.g. engraved).
    fit_latitude: bool = True
