"""What a run is asked to do: the method, the smoothing, the place and the
capture times (bpy-free). The choices are declared here once; the panel,
the CLI and the benchmarks list them from here."""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

from . import native_loader
from .errors import EstimateError


@dataclass(frozen=True)
class Choice:
    key: str          # as the track file, the CLI and the .blend store it
    label: str        # as the panel shows it
    description: str  # the panel's tooltip


METHODS = (
    Choice("default", "sunlapse", "The whole clip at once: every frame's evidence over the "
                                  "whole sky, one path for the Sun, refined by the shadows"),
    Choice("thesis", "Thesis", "The thesis's baseline: the Sun on the first frame (8 lights "
                               "+ ambient), then its shadows tracked frame after frame"),
)
SMOOTHINGS = (
    Choice("two_pass", "Two-Pass", "Fit the whole clip (best for renders)"),
    Choice("online", "Online", "Causal smoothing, as if the clip were playing"),
    Choice("physical", "Physical", "Fit the Sun's true path: needs the place, the date, the "
                                   "first frame's time and the frame interval"),
)


def keys(choices: Tuple[Choice, ...]) -> List[str]:
    return [c.key for c in choices]


# Two-pass smoothing: the thesis fits a straight line per angle; ours fits
# local quadratics to the Sun's direction (core.smoothing.
# two_pass_local_directions), which follow a whole day's path.
TWO_PASS_DEGREE = {"thesis": 1}
# Ours smooths the Sun's direction, not each angle (both the two-pass and the
# online mode): near the zenith the azimuth swings too fast for either
# (core.smoothing.two_pass_directions, online_directions).
SMOOTHING_SPACE = {"thesis": "angles", "default": "directions"}


def gamma(method: str) -> float:
    """The gamma a frame's 8-bit values are raised to for linear light: the
    thesis reads the grayscale frame as shading as it is (§3.2); ours undoes
    the display gamma (the native readers' default), since the Lambertian
    model is linear."""
    return 1.0 if method == "thesis" else native_loader.require().FrameStreamOptions().gamma


@dataclass
class EstimateOptions:
    method: str = "default"            # a key of METHODS
    smoothing: str = "two_pass"        # a key of SMOOTHINGS
    ignore_top_rows: int = 0
    north_offset_deg: float = 0.0      # scene +Y from north (Sun Position add-on)
    ground_object_ids: List[int] = field(default_factory=list)
    # Given Sun on the first frame (zenith, azimuth as in the track file):
    # skips the initial estimate, to measure the tracker alone.
    initial_sun: Optional[Tuple[float, float]] = None
    # For smoothing "physical": the first frame's time (aware datetime), the
    # seconds between frames and the place (degrees, east positive).
    first_time: Optional[dt.datetime] = None
    frame_seconds: Optional[float] = None
    latitude_deg: Optional[float] = None
    longitude_deg: Optional[float] = None
    # Capture time of each frame (scene frame number -> aware datetime), from
    # a times file: frames are then visited in the order they were taken and
    # smoothed over real time; physical smoothing needs no first_time or
    # frame_seconds then.
    frame_times: Optional[Dict[int, dt.datetime]] = None
    # Physical smoothing keeps the given latitude (the user typed it, or the
    # frames' GPS gave it); True fits it too, about the given one, loosely:
    # on a roughly modelled urban scene the fit moved a typed 32.2 to 41.0.
    fit_latitude: bool = False
    # The track's confidence as a probability of being within 2 deg
    # (calibration.py); False writes the estimator's support as it is, which
    # is what bench/calibrate.py refits the map from.
    calibrated_confidence: bool = True
    # Refine the hand-made model by the clip before the estimate (native
    # refine_model): each object moved, turned and scaled, the camera turned
    # and zoomed, so that the model's edges fall on the clip's stable edges.
    # The estimate uses the refined model where the gate lets it (a model
    # clearly off); the track reports the corrections. A model that already
    # fits costs the stable edges only (docs/performance.md).
    refine_model: bool = True

    def check(self) -> None:
        """Raises EstimateError naming the first option that cannot be."""
        def bad(what: str, valid: str) -> EstimateError:
            return EstimateError(f"{what}: {valid}")
        if self.method not in keys(METHODS):
            raise bad(f"method {self.method!r}", f"expected one of {', '.join(keys(METHODS))}")
        if self.smoothing not in keys(SMOOTHINGS):
            raise bad(f"smoothing {self.smoothing!r}",
                      f"expected one of {', '.join(keys(SMOOTHINGS))}")
        if self.ignore_top_rows < 0:
            raise bad(f"ignore_top_rows {self.ignore_top_rows}", "expected 0 or more rows")
        if not self.ground_object_ids:
            raise EstimateError("no ground object: name the ground the shadows fall on "
                                "(--ground, or Ground in the panel)")
        if not math.isfinite(self.north_offset_deg):
            raise bad("north_offset_deg", "expected a finite angle")
        for name, value, limit in (("latitude_deg", self.latitude_deg, 90.0),
                                   ("longitude_deg", self.longitude_deg, 180.0)):
            if value is not None and not (math.isfinite(value) and abs(value) <= limit):
                raise bad(f"{name} {value}", f"expected -{limit:g} to {limit:g} degrees")
        if self.frame_seconds is not None and not (math.isfinite(self.frame_seconds)
                                                   and self.frame_seconds > 0):
            raise bad(f"frame_seconds {self.frame_seconds}", "expected a positive interval")
        if self.initial_sun is not None:
            z, a = self.initial_sun
            if not (math.isfinite(z) and math.isfinite(a) and 0 <= z <= 180):
                raise bad(f"initial_sun {self.initial_sun}",
                          "expected a zenith in [0, 180] and a finite azimuth (degrees)")
