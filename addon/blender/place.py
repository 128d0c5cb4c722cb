"""Place and time for physical smoothing, worked out once for the panel and
the CLI: what the command line gave (PlaceTimeFlags), then the panel (when
its Date is set), then Blender's Sun Position add-on; the frames' own times
(a times file, EXIF) are the clock when there are any, and their GPS fix the
place."""

import datetime as dt
import math
from dataclasses import dataclass
from typing import Optional, Tuple

from .gather import SceneError
from ..core import clock


class PlaceTimeError(ValueError):
    """A flag that physical smoothing cannot use, or one it needs and lacks:
    names the flags."""


@dataclass
class PlaceTimeFlags:
    """What the command line gave (None: not given)."""
    latitude_deg: Optional[float] = None
    longitude_deg: Optional[float] = None
    date: Optional[dt.date] = None
    start_hours: Optional[float] = None
    utc_offset_hours: Optional[float] = None
    frame_seconds: Optional[float] = None
    fit_latitude: Optional[bool] = None   # --fit-latitude / --fixed-latitude


def settings_zone(settings) -> dt.tzinfo:
    """The panel's time zone (IANA name, else the UTC offset) as a tzinfo;
    raises SceneError for an unknown name."""
    try:
        return clock.zone(settings.time_zone, settings.utc_offset)
    except clock.ClockError as e:
        raise SceneError(str(e))


def place_and_time(context, settings, options, gps: Optional[Tuple[float, float]] = None,
                   flags: Optional[PlaceTimeFlags] = None) -> None:
    """Fills `options` (EstimateOptions) with the place and time physical
    smoothing needs. The panel's way leaves what nobody knows unset (the run
    then fits the Sun's circle, or falls back to two-pass, and says so);
    with `flags` (the CLI), whatever the flags' route still lacks raises
    PlaceTimeError naming the flags."""
    _from_panel(context, settings, options)
    if gps is not None:  # the frames' own GPS fix is the place
        options.latitude_deg, options.longitude_deg = gps
    if flags is not None:
        if flags.fit_latitude is not None:
            options.fit_latitude = flags.fit_latitude
        for key, value in _with_flags(context, options, flags).items():
            setattr(options, key, value)


def _from_panel(context, settings, options) -> None:
    """Place and time from the panel, or from Blender's Sun Position add-on
    when the panel's date is empty; left unset when neither knows them."""
    sp = getattr(context.scene, "sun_pos_properties", None)
    lat, lon, hours = settings.latitude, settings.longitude, settings.start_hour
    tz = settings_zone(settings)  # the zone, else the UTC offset
    day = None
    if settings.date:
        try:
            day = dt.date.fromisoformat(settings.date)
        except ValueError:
            raise SceneError(f"Date '{settings.date}' is not YYYY-MM-DD")
    elif sp is not None:
        day = dt.date(sp.year, sp.month, sp.day)
        lat, lon, hours = sp.latitude, sp.longitude, sp.time
        dst = 1.0 if getattr(sp, "use_daylight_savings", False) else 0.0
        tz = clock.zone("", sp.UTC_zone + dst)
    options.fit_latitude = settings.fit_latitude
    if options.frame_times is not None:  # the times file is the clock
        options.latitude_deg, options.longitude_deg = lat, lon
        return
    if day is None or settings.frame_seconds <= 0:
        return
    options.first_time = clock.local_start(day, hours, tz)
    options.frame_seconds = settings.frame_seconds
    options.latitude_deg, options.longitude_deg = lat, lon


def _check(value, flag, low, high, what):
    if value is not None and not (math.isfinite(value) and low <= value <= high):
        raise PlaceTimeError(f"{flag} {value} is not {what}")


def _with_flags(context, options, flags: PlaceTimeFlags) -> dict:
    """The flags first, then what the panel gave (`options`), then the Sun
    Position add-on (its latitude, longitude, date, time and UTC zone). With
    the frames' times known only the place is needed; with no place at all,
    the Sun's circle about the pole is fitted instead."""
    sp = getattr(context.scene, "sun_pos_properties", None)

    def pick(flag, from_options, from_sun_position):
        if flag is not None:
            return flag
        if from_options is not None:
            return from_options
        return getattr(sp, from_sun_position, None)
    lat = pick(flags.latitude_deg, options.latitude_deg, "latitude")
    lon = pick(flags.longitude_deg, options.longitude_deg, "longitude")
    seconds = flags.frame_seconds if flags.frame_seconds is not None else options.frame_seconds
    if lat is None and lon is None:
        # No place anywhere: the Sun's circle about the pole is fitted
        # instead (estimate/sun_circle.py), in real time when the seconds per frame
        # are known, else per frame.
        _check(seconds, "--frame-seconds", 1e-9, math.inf, "a positive number of seconds")
        return {"frame_seconds": seconds}
    if options.frame_times is not None:
        missing = [n for n, v in (("--latitude", lat), ("--longitude", lon)) if v is None]
        if missing:
            raise PlaceTimeError("--smoothing physical needs " + ", ".join(missing))
        _check(lat, "latitude", -90, 90, "a latitude in [-90, 90] degrees")
        _check(lon, "longitude", -180, 360, "a longitude in [-180, 360] degrees")
        return {"latitude_deg": lat, "longitude_deg": lon}
    utc = flags.utc_offset_hours if flags.utc_offset_hours is not None else \
        getattr(sp, "UTC_zone", 0.0)
    first = options.first_time if flags.date is None and flags.start_hours is None else None
    if first is None:
        day = flags.date
        if day is None and sp is not None:
            day = dt.date(sp.year, sp.month, sp.day)
        hours = flags.start_hours if flags.start_hours is not None else getattr(sp, "time", None)
        if day is not None and hours is not None:
            try:
                first = clock.local_start(day, hours, clock.zone("", utc))
            except (ValueError, OverflowError) as e:  # clock.ClockError too
                raise PlaceTimeError(f"bad --date or --start-time: {e}")
    missing = [name for name, v in (("--latitude", lat), ("--longitude", lon),
                                    ("--date and --start-time", first),
                                    ("--frame-seconds", seconds)) if v is None]
    if missing:
        raise PlaceTimeError("--smoothing physical needs " + ", ".join(missing) +
                             " (or --times, or Blender's Sun Position add-on values)")
    _check(lat, "latitude", -90, 90, "a latitude in [-90, 90] degrees")
    _check(lon, "longitude", -180, 360, "a longitude in [-180, 360] degrees")
    _check(seconds, "--frame-seconds", 1e-9, math.inf, "a positive number of seconds")
    return {"first_time": first, "frame_seconds": seconds,
            "latitude_deg": lat, "longitude_deg": lon}
