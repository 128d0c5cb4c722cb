"""Draws random scenes for the scene suite: a seed in, a scene spec out.

bpy-free: the spec is a plain JSON-able dict that examples/generate_scene.py
(`--random KEY`) turns into a render, and that bench/suite.py hashes into its
cache key. KEY is an integer seed, the name of a fixed member (FIXED), or
<prefix><seed> for a kind of member (PREFIXES: twilight, rough models,
overcast runs, urban scenes, multi-day clips, trees, moving cameras), each drawn from its own
random stream so that no kind changes another's scenes.

The Sun comes from a `sun_position(y, m, d, h, mi, s, lat, lon) -> (zenith,
azimuth)` callable (UTC; `_native.sun_position`), so drawing is exactly
reproducible and checks (shadows in view, sunlit floor in view) use the same
ephemeris as the render.

World frame as everywhere in sunlapse (docs/design.md §4): +Z up, +Y is the scene's
"north", azimuth_world = azimuth_geographic + north_offset.
"""

import datetime as dt
import math
import random

# Bump whenever the rendering of a spec changes (materials, lamp, encoding);
# changes to the drawing rules change the specs themselves and so the key.
GENERATOR_VERSION = 1

SENSOR_WIDTH_MM = 36.0
# Scenes are judged at this size (bench/suite.py renders them so).
DEFAULT_FRAMES = 32
DEFAULT_RESOLUTION = (320, 180)
# Longest shadows we ask for: beyond ~80 deg the shadows leave any view.
MAX_ZENITH_DEG = 78.0
# A Sun within a few degrees of the zenith has no meaningful azimuth (the
# pass criterion judges azimuth alone).
MIN_ZENITH_DEG = 8.0
ROOM_EVERY = 5  # seeds with seed % ROOM_EVERY == ROOM_EVERY - 1 are rooms
# Keys "twilight<seed>": outdoor scenes whose clip runs past sunset (or
# starts before sunrise) into twilight, as real clips do: the Sun ends (or
# starts) TWILIGHT_DEPTH_DEG below the horizon, the direct light fades out
# over the last HORIZON_FADE_DEG above it, and the camera's exposure rises
# as the light falls.
TWILIGHT_PREFIX = "twilight"
TWILIGHT_DEPTH_DEG = (3.0, 8.0)
TWILIGHT_DAY_HOURS = (1.5, 4.0)
HORIZON_FADE_DEG = 4.0
# Keys "rough<seed>": the footage is rendered with the true model, the
# user's scene.blend carries the model as a user models by hand: each caster
# moved ROUGH_MOVE_M, scaled by ROUGH_SCALE per axis, turned up to
# ROUGH_TURN_DEG; the camera turned ROUGH_CAMERA_DEG about a random axis and
# its focal length off by ROUGH_LENS. scene_true.blend keeps the true model.
ROUGH_PREFIX = "rough"
ROUGH_MOVE_M = (0.05, 0.30)
ROUGH_SCALE = (0.03, 0.10)
ROUGH_TURN_DEG = 3.0
ROUGH_CAMERA_DEG = 0.3
ROUGH_LENS = 0.02
# Keys "overcast<seed>": a run of OVERCAST_FRAMES frames inside the clip
# under cloud: the Sun lamp off, the sky a flat grey giving
# OVERCAST_SKY_LEVEL of the clear Sun's irradiance, over OVERCAST_RAMP
# frames of transition each side; the camera's exposure ramps up as the
# light falls (auto-exposure making up a share of it) and drifts slowly
# over the whole clip.
OVERCAST_PREFIX = "overcast"
OVERCAST_FRAMES = (6, 12)
OVERCAST_RAMP = (1, 3)
OVERCAST_SKY_LEVEL = (0.15, 0.35)
# Frames whose direct light is at most this share of the clear Sun's are
# "without direct sunlight" (judged on their flag); below OVERCAST_JUDGED
# they are not judged for accuracy either.
NO_SUN_FACTOR = 0.05
OVERCAST_JUDGED = 0.5
# Keys "urban<seed>": buildings URBAN_HEIGHT_M tall with eaves, seen from a
# camera that sees walls and ground; the Sun's shadows fall on walls.
URBAN_PREFIX = "urban"
URBAN_HEIGHT_M = (6.0, 20.0)
# Keys "walls<seed>": the same streets seen from a camera 4-12 m up looking
# across them at the facades: walls fill most of the view and the Sun's
# shadows fall on walls more than on the ground.
WALLS_PREFIX = "walls"
# Keys "multiday<seed>": MULTIDAY_DAYS days with the nights in them, frames
# at a fixed interval (as a webcam), 1.5 times the suite's frames; the times
# are given to the estimator. The night sky dims as twilight's does; the
# camera's exposure makes up at most MULTIDAY_MAX_GAIN_EV.
MULTIDAY_PREFIX = "multiday"
MULTIDAY_DAYS = (2, 3)
MULTIDAY_MAX_GAIN_EV = 3.0
# Keys "trees<seed>": footage-only trees over the ground (not in the model)
# whose leafy crowns cast dappled shadows.
TREES_PREFIX = "trees"
# Keys "moving<seed>": an outdoor scene shot by a motion-control rig: the
# camera slides MOVING_SLIDE_M along a rail (within MOVING_RAIL_TURN_DEG of
# its image's horizontal), pans MOVING_PAN_DEG and, on half the members,
# tilts up to MOVING_TILT_DEG, eased in and out, centred on the drawn view
# (the middle frame). The user's scene.blend carries the camera keyed on
# every frame as Blender's solver delivers it: the true motion plus a
# solve's jitter (MOVING_JITTER_M, MOVING_JITTER_DEG, standard deviations).
MOVING_PREFIX = "moving"
MOVING_SLIDE_M = (0.3, 2.0)
MOVING_RAIL_TURN_DEG = 30.0
MOVING_PAN_DEG = (5.0, 30.0)
MOVING_TILT_DEG = 4.0
MOVING_JITTER_M = 0.003
MOVING_JITTER_DEG = 0.02
# Moving members from MOVING_AWAY_FROM on pan away from the drawn view and
# back instead (by MOVING_AWAY_SHARE of their horizontal field of view, at
# the middle of the clip): the casters and their shadows leave the view for
# a while, as on a shot that sweeps past the scene.
MOVING_AWAY_FROM = 25
MOVING_AWAY_SHARE = 0.9
# Every prefix of a member kind; a key is <prefix><seed> (seeds plain: the
# static members).
PREFIXES = (TWILIGHT_PREFIX, ROUGH_PREFIX, OVERCAST_PREFIX, URBAN_PREFIX, MULTIDAY_PREFIX,
            TREES_PREFIX, WALLS_PREFIX, MOVING_PREFIX)

GROUNDS = ["paving", "asphalt", "grass", "wood", "cobbles"]
CASTER_SHAPES = ["pole", "box", "wall", "kiosk", "lshape", "cylinder"]
CLUTTER_KINDS = ["bin", "bush", "bench", "person", "car"]


# ---------------------------------------------------------------------------
# Small vector helpers (no numpy needed)

def _sub(a, b):
    return [a[i] - b[i] for i in range(3)]


def _dot(a, b):
    return sum(a[i] * b[i] for i in range(3))


def _cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _unit(a):
    n = math.sqrt(_dot(a, a))
    return [x / n for x in a]


def sun_in_world(zenith_deg, azimuth_world_deg):
    z, a = math.radians(zenith_deg), math.radians(azimuth_world_deg)
    return [math.sin(z) * math.sin(a), math.sin(z) * math.cos(a), math.cos(z)]


class PinholeCamera:
    """Blender's camera (sensor fit AUTO, 36 mm, landscape, no shift) aimed at
    `target` with no roll, as Vector.to_track_quat('-Z', 'Y') aims it."""

    def __init__(self, location, target, lens_mm, width, height):
        self.location = list(location)
        self.width, self.height = width, height
        self.f_px = lens_mm / SENSOR_WIDTH_MM * width
        self.forward = _unit(_sub(target, location))
        self.right = _unit(_cross(self.forward, [0.0, 0.0, 1.0]))
        self.up = _cross(self.right, self.forward)

    def project(self, point_in_world):
        """OpenCV pixel (x right, y down) or None behind the camera."""
        p = _sub(point_in_world, self.location)
        depth = _dot(p, self.forward)
        if depth <= 1e-6:
            return None
        return (self.width / 2.0 + self.f_px * _dot(p, self.right) / depth,
                self.height / 2.0 - self.f_px * _dot(p, self.up) / depth)

    def in_view(self, point_in_world, margin=0.05):
        px = self.project(point_in_world)
        if px is None:
            return False
        mx, my = margin * self.width, margin * self.height
        return mx <= px[0] <= self.width - mx and my <= px[1] <= self.height - my

    def ground_point(self, x_px, y_px, ground_z=0.0):
        """Where the pixel's ray meets the plane z = ground_z (None if above)."""
        d = [self.forward[i] + ((x_px - self.width / 2.0) * self.right[i]
                                - (y_px - self.height / 2.0) * self.up[i]) / self.f_px
             for i in range(3)]
        if d[2] >= -1e-6:
            return None
        t = (ground_z - self.location[2]) / d[2]
        return [self.location[i] + t * d[i] for i in range(3)]


def camera_of(spec):
    c = spec["camera"]
    w, h = spec["render"]["resolution"]
    return PinholeCamera(c["location"], c["target"], c["lens_mm"], w, h)


# ---------------------------------------------------------------------------
# Time and the Sun

def frame_times_local(spec):
    t = spec["time"]
    tz = dt.timezone(dt.timedelta(hours=t["utc_offset_h"]))
    start = dt.datetime.fromisoformat(t["start_local"]).replace(tzinfo=tz)
    step = dt.timedelta(minutes=t["minutes_per_frame"])
    return [start + i * step for i in range(spec["render"]["frames"])]


def _sun(sun_position, when, lat, lon):
    u = when.astimezone(dt.timezone.utc)
    return sun_position(u.year, u.month, u.day, u.hour, u.minute,
                        u.second + u.microsecond * 1e-6, lat, lon)


def suns_of(spec, sun_position):
    """Per frame (zenith, geographic azimuth), degrees."""
    p = spec["place"]
    return [tuple(_sun(sun_position, t, p["latitude_deg"], p["longitude_deg"]))
            for t in frame_times_local(spec)]


def _draw_day(rng, latitudes):
    """A place (latitude in `latitudes`, any longitude), its whole-hour UTC
    offset and zone, and a day of 2025."""
    lat = rng.uniform(*latitudes)
    lon = rng.uniform(-180.0, 180.0)
    utc = max(-12, min(14, round(lon / 15.0)))
    day = dt.date(2025, 1, 1) + dt.timedelta(days=rng.randrange(365))
    return lat, lon, utc, day, dt.timezone(dt.timedelta(hours=utc))


def _crossing(sun_position, lat, lon, t0, t1, zenith_deg):
    """The time between t0 and t1 (either order) when the Sun's zenith
    crosses zenith_deg (it must cross once), to the second."""
    def above(t):
        return _sun(sun_position, t, lat, lon)[0] < zenith_deg
    first = above(t0)
    while abs((t1 - t0).total_seconds()) > 1.0:
        mid = t0 + (t1 - t0) / 2
        if above(mid) == first:
            t0 = mid
        else:
            t1 = mid
    return t0


def _draw_twilight_time(rng, sun_position, frames):
    """A place, a date and a window that starts TWILIGHT_DAY_HOURS before
    sunset and ends with the Sun TWILIGHT_DEPTH_DEG below the horizon (or
    mirrored about sunrise), its Sun within the suite's bounds while up."""
    for _ in range(400):
        lat, lon, utc, day, tz = _draw_day(rng, (-55.0, 60.0))
        noon = dt.datetime(day.year, day.month, day.day, 12, tzinfo=tz) - \
            dt.timedelta(hours=lon / 15.0 - utc)   # about the Sun's transit
        dusk = rng.random() < 0.5
        depth = rng.uniform(*TWILIGHT_DEPTH_DEG)
        hours = rng.uniform(*TWILIGHT_DAY_HOURS)
        if _sun(sun_position, noon, lat, lon)[0] >= MAX_ZENITH_DEG - 10.0:
            continue
        far = noon + dt.timedelta(hours=12 if dusk else -12)
        if _sun(sun_position, far, lat, lon)[0] < 90.0 + depth:
            continue  # no night that deep (high latitudes in summer)
        horizon = _crossing(sun_position, lat, lon, noon, far, 90.0)
        night = _crossing(sun_position, lat, lon, horizon, far, 90.0 + depth)
        day_end = horizon + dt.timedelta(hours=-hours if dusk else hours)
        if (day_end < noon) if dusk else (day_end > noon):
            continue  # the window would pass the Sun's transit
        start, end = (day_end, night) if dusk else (night, day_end)
        step = (end - start) / (frames - 1)
        times = [start + i * step for i in range(frames)]
        suns = [_sun(sun_position, t, lat, lon) for t in times]
        if min(z for z, _ in suns) < MIN_ZENITH_DEG:
            continue
        if sum(z < MAX_ZENITH_DEG for z, _ in suns) < frames // 2:
            continue  # mostly twilight: too few frames with shadows in view
        start = start.replace(microsecond=0)
        result = dict(place={"latitude_deg": round(lat, 4), "longitude_deg": round(lon, 4)},
                      time={"start_local": start.replace(tzinfo=None).isoformat(),
                            "utc_offset_h": utc,
                            "minutes_per_frame": round(step.total_seconds() / 60.0, 3)},
                      twilight={"side": "dusk" if dusk else "dawn",
                                "depth_deg": round(depth, 2)})
        return result, suns
    raise RuntimeError("could not draw a twilight window")


def _draw_multiday_time(rng, sun_position, frames):
    """A place, a date and MULTIDAY_DAYS days from a random time of day,
    frames at a fixed interval (a webcam's): nights in them, every day's
    Sun high enough for shadows in view, never overhead."""
    for _ in range(400):
        lat, lon, utc, day, tz = _draw_day(rng, (-55.0, 60.0))
        days = rng.randint(*MULTIDAY_DAYS)
        step = round(days * 24 * 60 / frames)
        start = dt.datetime(day.year, day.month, day.day, tzinfo=tz) + \
            dt.timedelta(minutes=rng.randrange(0, 24 * 60, 5))
        suns = [_sun(sun_position, start + dt.timedelta(minutes=i * step), lat, lon)
                for i in range(frames)]
        zeniths = [z for z, _ in suns]
        if min(zeniths) < MIN_ZENITH_DEG or min(zeniths) >= MAX_ZENITH_DEG - 10.0:
            continue  # overhead, or too low a Sun for shadows in view
        if max(zeniths) < 96.0 or sum(z > 90.0 for z in zeniths) < frames // 5:
            continue  # no real night (high latitudes in summer)
        if sum(z < MAX_ZENITH_DEG for z in zeniths) < frames // 4:
            continue
        result = dict(place={"latitude_deg": round(lat, 4), "longitude_deg": round(lon, 4)},
                      time={"start_local": start.replace(tzinfo=None).isoformat(),
                            "utc_offset_h": utc, "minutes_per_frame": float(step)},
                      multiday={"days": days, "times_given": True})
        return result, suns
    raise RuntimeError("could not draw a multi-day window")


def _draw_time(rng, sun_position, frames, hours_range, ok):
    """A place, a date and a window of `hours_range` hours whose Sun stays
    below MAX_ZENITH_DEG and satisfies ok(suns_world_fn)."""
    for _ in range(400):
        lat, lon, utc, day, tz = _draw_day(rng, (-60.0, 65.0))
        midnight = dt.datetime(day.year, day.month, day.day, tzinfo=tz)
        # Daylight with a Sun high enough, sampled every 10 minutes.
        good = [m for m in range(0, 24 * 60, 10)
                if _sun(sun_position, midnight + dt.timedelta(minutes=m), lat, lon)[0]
                < MAX_ZENITH_DEG - 0.5]
        if len(good) < 7:
            continue
        first, last = good[0], good[-1]
        hours = min(rng.uniform(*hours_range), (last - first) / 60.0)
        if hours < hours_range[0]:
            continue
        start_min = rng.uniform(first, last - hours * 60.0)
        start = midnight + dt.timedelta(minutes=round(start_min))
        mpf = round(hours * 60.0 / (frames - 1), 3)
        times = [start + dt.timedelta(minutes=i * mpf) for i in range(frames)]
        suns = [_sun(sun_position, t, lat, lon) for t in times]
        if max(z for z, _ in suns) >= MAX_ZENITH_DEG or min(z for z, _ in suns) < MIN_ZENITH_DEG:
            continue  # a midday dip below the bound (polar days), or overhead
        result = dict(place={"latitude_deg": round(lat, 4), "longitude_deg": round(lon, 4)},
                      time={"start_local": start.replace(tzinfo=None).isoformat(),
                            "utc_offset_h": utc, "minutes_per_frame": mpf})
        if ok(suns):
            return result, suns
    raise RuntimeError("could not draw a time window")


# ---------------------------------------------------------------------------
# Casters and clutter

def _footprint_radius(item):
    s = item["size"]
    if item["shape"] == "lshape":
        return math.hypot(s[0], s[1])
    if item["shape"] in ("cylinder", "bush", "bin", "person", "tree"):
        return s[0]
    return 0.5 * math.hypot(s[0], s[1])


def _draw_caster(rng, shape, thin):
    """Size (metres) of one caster; `thin` is the smallest width that still
    covers ~2.5 pixels at the view's scale."""
    if shape == "pole":
        w = max(thin, rng.uniform(0.12, 0.22))
        return {"size": [w, w, rng.uniform(2.5, 5.0)], "round": rng.random() < 0.4}
    if shape == "box":
        return {"size": [rng.uniform(0.8, 2.5), rng.uniform(0.8, 2.5), rng.uniform(0.8, 2.0)]}
    if shape == "wall":
        return {"size": [rng.uniform(3.0, 7.0), max(thin, rng.uniform(0.2, 0.35)),
                         rng.uniform(1.2, 2.8)]}
    if shape == "kiosk":
        b = rng.uniform(1.5, 2.5)
        return {"size": [b, rng.uniform(1.5, 2.5), rng.uniform(2.2, 2.9)],
                "roof_overhang": rng.uniform(0.2, 0.45)}
    if shape == "lshape":
        return {"size": [rng.uniform(2.0, 4.0), rng.uniform(1.5, 3.5), rng.uniform(1.2, 2.5)],
                "thickness": max(thin, rng.uniform(0.2, 0.3))}
    if shape == "cylinder":
        return {"size": [rng.uniform(0.3, 1.0), 0.0, rng.uniform(1.0, 3.0)]}
    raise ValueError(shape)


def _draw_clutter(rng, kind):
    return {"bin": [0.3, 0.0, 0.9], "bush": [rng.uniform(0.4, 0.8), 0.0, 0.0],
            "bench": [1.8, 0.5, 0.45], "person": [0.22, 0.0, rng.uniform(1.6, 1.85)],
            "car": [4.2, 1.8, 1.4]}[kind]


def _shadow_probe_points(item):
    """Points whose shadows must be in view: the top of the caster (the tip
    of its shadow) and half way up (half way along the shadow)."""
    x, y = item["location"][:2]
    h = item["size"][2]
    return [[x, y, 0.0], [x, y, 0.5 * h]]


def shadow_points(item, sun_world):
    """Ground points of the probes' shadows (z = 0)."""
    out = []
    for p in _shadow_probe_points(item):
        t = p[2] / sun_world[2]
        out.append([p[0] - t * sun_world[0], p[1] - t * sun_world[1], 0.0])
    return out


def check_frames(n, suns=None):
    """The frames whose shadows must be in view: the first, middle and last
    of those with the Sun below MAX_ZENITH_DEG (all of them without suns)."""
    up = list(range(n)) if suns is None else [i for i in range(n)
                                              if suns[i][0] < MAX_ZENITH_DEG]
    return sorted({up[0], up[len(up) // 2], up[-1]})


def casters_in_view(spec, sun_position):
    """Per caster, whether its base and its shadow's half-way point are in
    view on the first, middle and last frame (outdoor scenes)."""
    cam = camera_of(spec)
    suns = suns_of(spec, sun_position)
    north = spec["north_offset_deg"]
    out = []
    for item in spec["casters"]:
        ok = True
        for i in check_frames(len(suns), suns):
            s = sun_in_world(suns[i][0], suns[i][1] + north)
            ok = ok and all(cam.in_view(p, 0.03) for p in shadow_points(item, s))
        out.append(ok)
    return out


def _place(rng, cam, item, placed, suns_world, tries=300):
    for _ in range(tries):
        px = (rng.uniform(0.12, 0.88) * cam.width, rng.uniform(0.2, 0.9) * cam.height)
        g = cam.ground_point(*px)
        if g is None:
            continue
        item["location"] = [round(g[0], 3), round(g[1], 3), 0.0]
        r = _footprint_radius(item)
        if any(math.hypot(g[0] - q["location"][0], g[1] - q["location"][1])
               < r + _footprint_radius(q) + 0.6 for q in placed):
            continue
        if not cam.in_view(g, 0.06):
            continue
        if all(cam.in_view(p, 0.04) for s in suns_world for p in shadow_points(item, s)):
            return True
    return False


def _draw_outdoor(rng, sun_position, frames, resolution, when="day"):
    """An outdoor scene over a day's window ("day"), into twilight
    ("twilight") or over several days ("multiday")."""
    if when == "twilight":
        t, suns = _draw_twilight_time(rng, sun_position, frames)
    elif when == "multiday":
        t, suns = _draw_multiday_time(rng, sun_position, frames)
    else:
        t, suns = _draw_time(rng, sun_position, frames, (1.0, 8.0), lambda s: True)
    north = round(rng.uniform(-180.0, 180.0), 2)
    width, height = resolution
    for _ in range(500):
        height_m = rng.uniform(2.0, 20.0)
        lens = rng.uniform(18.0, 50.0)
        depression = rng.uniform(25.0, 70.0)
        # The whole frame must see ground (the top edge below the horizon).
        vfov_half = math.degrees(math.atan(SENSOR_WIDTH_MM * height / width / 2.0 / lens))
        if depression - vfov_half < 6.0:
            continue
        dist_h = height_m / math.tan(math.radians(depression))
        slant = math.hypot(height_m, dist_h)
        view_width_m = slant * SENSOR_WIDTH_MM / lens
        if not 7.0 <= view_width_m <= 32.0:
            continue
        far = PinholeCamera([0, -dist_h, height_m], [0, 0, 0], lens, width, height).ground_point(
            width / 2.0, 0.0)
        if far is None or math.hypot(far[0], far[1] + dist_h) > 70.0:
            continue
        break
    else:
        raise RuntimeError("could not draw a camera")
    yaw = rng.uniform(0.0, 360.0)
    loc = [dist_h * math.sin(math.radians(yaw)), dist_h * math.cos(math.radians(yaw)), height_m]
    spec = dict(kind="outdoor", **t, north_offset_deg=north,
                camera={"location": [round(v, 4) for v in loc], "target": [0.0, 0.0, 0.0],
                        "lens_mm": round(lens, 2)},
                render={"frames": frames, "resolution": list(resolution), "samples": 8})
    cam = camera_of(spec)
    thin = 2.5 * view_width_m / width
    suns_world = [sun_in_world(z, a + north)
                  for z, a in (suns[i] for i in check_frames(frames, suns))]
    casters = []
    want = rng.randint(2, 5)
    shapes = [rng.choice(CASTER_SHAPES) for _ in range(want)]
    for k, shape in enumerate(shapes):
        item = dict(shape=shape, name=f"{shape.capitalize()}{k + 1}",
                    rotation_z_deg=round(rng.uniform(0.0, 180.0), 2),
                    **_draw_caster(rng, shape, thin))
        full_height = item["size"][2]
        for scale in (1.0, 0.75, 0.55, 0.4):
            # Too long a shadow for this view: a lower caster.
            item["size"][2] = round(full_height * scale, 3)
            if _place(rng, cam, item, casters, suns_world):
                casters.append(item)
                break
    if len(casters) < 2:
        return None
    clutter = []
    for k in range(rng.randint(1, 4)):
        kind = rng.choice(CLUTTER_KINDS if rng.random() < 0.3 else CLUTTER_KINDS[:4])
        item = dict(shape=kind, name=f"Clutter{k + 1}_{kind}", size=_draw_clutter(rng, kind),
                    rotation_z_deg=round(rng.uniform(0.0, 180.0), 2))
        for _ in range(200):
            g = cam.ground_point(rng.uniform(0.05, 0.95) * width, rng.uniform(0.1, 0.95) * height)
            if g is None:
                continue
            if all(math.hypot(g[0] - q["location"][0], g[1] - q["location"][1])
                   > _footprint_radius(item) + _footprint_radius(q) + 0.4
                   for q in casters + clutter):
                item["location"] = [round(g[0], 3), round(g[1], 3), 0.0]
                clutter.append(item)
                break
    spec.update(casters=casters, clutter=clutter,
                ground={"kind": rng.choice(GROUNDS), "name": "Ground",
                        "roughness": round(rng.uniform(0.55, 1.0), 3),
                        "specular": round(rng.uniform(0.2, 0.5), 3)})
    return spec


# ---------------------------------------------------------------------------
# Rooms

def window_patch_center(spec, sun_world):
    """Where the Sun through the window's centre meets the floor (z = 0)."""
    r = spec["room"]
    c = r["window_center"]
    t = c[2] / sun_world[2]
    return [c[0] - t * sun_world[0], c[1] - t * sun_world[1], 0.0]


def inside_room(spec, p, margin=0.3):
    r = spec["room"]
    a = math.radians(r["facing_world_deg"])
    # Room axes: +v toward the window wall, +u to its right.
    v = p[0] * math.sin(a) + p[1] * math.cos(a)
    u = p[0] * math.cos(a) - p[1] * math.sin(a)
    return abs(u) < r["width"] / 2 - margin and abs(v) < r["depth"] / 2 - margin


def sunlit_floor_in_view(spec, sun_position):
    cam = camera_of(spec)
    suns = suns_of(spec, sun_position)
    north = spec["north_offset_deg"]
    out = []
    for i in check_frames(len(suns)):
        p = window_patch_center(spec, sun_in_world(suns[i][0], suns[i][1] + north))
        out.append(inside_room(spec, p) and cam.in_view(p, 0.05))
    return out


def _room_to_world(facing_deg, u, v, z):
    a = math.radians(facing_deg)
    return [u * math.cos(a) + v * math.sin(a), -u * math.sin(a) + v * math.cos(a), z]


def _draw_room(rng, sun_position, frames, resolution):
    w, d, h = rng.uniform(4.5, 7.0), rng.uniform(4.0, 6.0), rng.uniform(2.6, 3.2)
    win_w = rng.uniform(1.2, min(2.6, w - 1.5))
    sill = rng.uniform(0.4, 0.9)
    top = min(h - 0.3, sill + rng.uniform(1.2, 1.8))
    win_u = rng.uniform(-(w - win_w) / 2 + 0.5, (w - win_w) / 2 - 0.5)
    north = round(rng.uniform(-180.0, 180.0), 2)
    turn = rng.uniform(-25.0, 25.0)
    box = {}

    def ok(suns):
        # The window faces the middle Sun (turned a little); the Sun must come
        # in through it onto the floor inside the room all clip long.
        facing = suns[len(suns) // 2][1] + north + turn
        for z, a in suns:
            if abs((a + north - facing + 180) % 360 - 180) > 60:
                return False
            v_dist = (sill + top) / 2 * math.tan(math.radians(z)) * abs(
                math.cos(math.radians(a + north - facing)))
            if not 0.4 < v_dist < d - 0.6:
                return False
        box["facing"] = facing
        return True

    t, suns = _draw_time(rng, sun_position, frames, (1.0, 3.0), ok)
    facing = round(box["facing"] % 360.0, 3)
    room = {"width": round(w, 3), "depth": round(d, 3), "height": round(h, 3), "wall": 0.2,
            "window": {"u": round(win_u, 3), "width": round(win_w, 3), "sill": round(sill, 3),
                       "top": round(top, 3)},
            "facing_world_deg": facing}
    room["window_center"] = [round(c, 4) for c in
                             _room_to_world(facing, win_u, d / 2, (sill + top) / 2)]
    spec = dict(kind="room", **t, north_offset_deg=north, room=room,
                render={"frames": frames, "resolution": list(resolution), "samples": 24},
                exposure_ev=round(rng.uniform(1.0, 2.0), 2))
    mid_sun = sun_in_world(suns[frames // 2][0], suns[frames // 2][1] + north)
    target = window_patch_center(spec, mid_sun)
    for _ in range(300):
        lens = rng.uniform(18.0, 24.0)
        cu = rng.uniform(-w / 2 + 0.5, w / 2 - 0.5)
        cv = rng.uniform(-d / 2 + 0.4, -d / 2 + 1.5)
        ch = rng.uniform(2.0, min(2.6, h - 0.2))
        spec["camera"] = {"location": [round(c, 4) for c in _room_to_world(facing, cu, cv, ch)],
                          "target": [round(c, 4) for c in target], "lens_mm": round(lens, 2)}
        if all(sunlit_floor_in_view(spec, sun_position)):
            break
    else:
        return None
    furniture = []
    options = [("table", [1.2, 0.8, 0.75]), ("cabinet", [0.5, 1.0, 1.6]),
               ("shelf", [1.0, 0.35, 1.9]), ("stool", [0.4, 0.4, 0.6])]
    for k in range(rng.randint(1, 3)):
        kind, size = options[rng.randrange(len(options))]
        for _ in range(100):
            u, v = rng.uniform(-w / 2 + 0.6, w / 2 - 0.6), rng.uniform(-d / 2 + 0.6, d / 2 - 0.6)
            p = _room_to_world(facing, u, v, 0.0)
            if math.dist(p[:2], spec["camera"]["location"][:2]) < 1.0:
                continue
            if all(math.dist(p[:2], q["location"][:2]) > 1.4 for q in furniture):
                furniture.append(dict(shape="box", name=f"{kind.capitalize()}{k + 1}",
                                      size=list(size), location=[round(c, 3) for c in p],
                                      rotation_z_deg=round(-facing + rng.uniform(-20, 20), 2)))
                break
    clutter = []
    for k, (kind, size) in enumerate([("bin", [0.18, 0.0, 0.5]), ("bush", [0.3, 0.0, 0.0])][
            :rng.randint(1, 2)]):
        u, v = rng.uniform(-w / 2 + 0.5, w / 2 - 0.5), rng.uniform(-d / 2 + 0.5, d / 2 - 0.5)
        clutter.append(dict(shape=kind, name=f"Clutter{k + 1}_{kind}", size=size,
                            location=[round(c, 3) for c in _room_to_world(facing, u, v, 0.0)],
                            rotation_z_deg=0.0))
    spec.update(casters=furniture, clutter=clutter,
                ground={"kind": rng.choice(["wood", "paving"]), "name": "Floor",
                        "roughness": round(rng.uniform(0.5, 0.95), 3),
                        "specular": round(rng.uniform(0.2, 0.5), 3)})
    return spec


# ---------------------------------------------------------------------------
# Urban scenes: buildings with eaves (keys "urban<seed>")

EAVES_THICKNESS_M = 0.3


def building_boxes(item):
    """The oriented boxes of a building caster (its body and the eaves slab
    on top): dicts of center (x, y), half (x, y), z (low, high), rot (deg)."""
    w, d, h = item["size"]
    o = item["eaves"]
    c = item["location"][:2]
    rot = item["rotation_z_deg"]
    return [{"center": c, "half": [w / 2, d / 2], "z": [0.0, h - EAVES_THICKNESS_M], "rot": rot},
            {"center": c, "half": [w / 2 + o, d / 2 + o], "z": [h - EAVES_THICKNESS_M, h],
             "rot": rot}]


def box_hit(origin, direction, box):
    """(t, normal) where the ray origin + t direction enters the oriented
    box (normal in world, outward), or None. t is 0 (normal None) when the
    origin is inside."""
    a = math.radians(box["rot"])
    c, s = math.cos(a), math.sin(a)
    px, py = origin[0] - box["center"][0], origin[1] - box["center"][1]
    lo = [c * px + s * py, -s * px + c * py, origin[2]]
    ld = [c * direction[0] + s * direction[1], -s * direction[0] + c * direction[1],
          direction[2]]
    lim = [(-box["half"][0], box["half"][0]), (-box["half"][1], box["half"][1]), tuple(box["z"])]
    t0, t1, axis, sign = -math.inf, math.inf, None, 0.0
    for k in range(3):
        if abs(ld[k]) < 1e-12:
            if not lim[k][0] <= lo[k] <= lim[k][1]:
                return None
            continue
        ta, tb = (lim[k][0] - lo[k]) / ld[k], (lim[k][1] - lo[k]) / ld[k]
        sgn = -1.0 if ta < tb else 1.0
        if ta > tb:
            ta, tb = tb, ta
        if ta > t0:
            t0, axis, sign = ta, k, sgn
        t1 = min(t1, tb)
    if t0 > t1 or t1 < 1e-6:
        return None
    if t0 < 1e-6:
        return 0.0, None
    n = [0.0, 0.0, 0.0]
    n[axis] = sign
    return t0, [c * n[0] - s * n[1], s * n[0] + c * n[1], n[2]]


def _first_hit(origin, direction, boxes):
    best = None
    for b in boxes:
        h = box_hit(origin, direction, b)
        if h is not None and (best is None or h[0] < best[0]):
            best = h
    return best


def urban_view(spec, sun_position, grid=(32, 18)):
    """What the camera sees over a grid of pixels, and per check frame what
    is in the Sun's shadow: {"ground", "wall", "roof": shares of pixels;
    "frames": per check frame {"wall_shadow": share of pixels on walls that
    face the Sun but lie in a cast shadow, "ground_shadow", "ground_lit"}}."""
    cam = camera_of(spec)
    boxes = [b for item in spec["casters"] for b in building_boxes(item)]
    points = []  # (kind, point, normal)
    gw, gh = grid
    for j in range(gh):
        for i in range(gw):
            x, y = (i + 0.5) / gw * cam.width, (j + 0.5) / gh * cam.height
            d = [cam.forward[k] + ((x - cam.width / 2.0) * cam.right[k]
                                   - (y - cam.height / 2.0) * cam.up[k]) / cam.f_px
                 for k in range(3)]
            hit = _first_hit(cam.location, d, boxes)
            t_ground = -cam.location[2] / d[2] if d[2] < -1e-9 else math.inf
            if hit is not None and hit[0] < t_ground:
                if hit[1] is None:
                    return None  # the camera is inside a building
                p = [cam.location[k] + hit[0] * d[k] for k in range(3)]
                points.append(("roof" if abs(hit[1][2]) > 0.5 else "wall", p, hit[1]))
            elif t_ground < math.inf:
                p = [cam.location[k] + t_ground * d[k] for k in range(3)]
                points.append(("ground", p, [0.0, 0.0, 1.0]))
    n = float(gw * gh)
    out = {k: sum(q[0] == k for q in points) / n for k in ("ground", "wall", "roof")}
    suns = suns_of(spec, sun_position)
    out["frames"] = []
    for f in check_frames(len(suns), suns):
        s = sun_in_world(suns[f][0], suns[f][1] + spec["north_offset_deg"])
        counts = {"wall_shadow": 0, "wall_lit": 0, "ground_shadow": 0, "ground_lit": 0}
        for kind, p, normal in points:
            if kind == "roof" or _dot(normal, s) <= 0.0:
                continue
            q = [p[k] + 0.02 * normal[k] for k in range(3)]
            shadowed = _first_hit(q, s, boxes) is not None
            if kind == "wall":
                counts["wall_" + ("shadow" if shadowed else "lit")] += 1
            else:
                counts["ground_" + ("shadow" if shadowed else "lit")] += 1
        out["frames"].append({k: v / n for k, v in counts.items()})
    return out


def _urban_view_ok(view):
    return (view is not None and view["ground"] >= 0.2 and view["wall"] >= 0.12 and
            all(f["wall_shadow"] >= 0.015 and f["ground_shadow"] >= 0.04 and
                f["ground_lit"] >= 0.08 for f in view["frames"]))


def _walls_view_ok(view):
    return (view is not None and view["ground"] >= 0.08 and view["wall"] >= 0.45 and
            all(f["wall_shadow"] >= 0.06 and f["wall_lit"] >= 0.06 and
                f["wall_shadow"] >= f["ground_shadow"] for f in view["frames"]))


# How the camera sees the streets: urban (from above: walls and ground) and
# walls (from low across the street: mostly facades).
URBAN_VIEWS = {
    URBAN_PREFIX: dict(height_m=(12.0, 45.0), lens_mm=(18.0, 35.0), depression_deg=(22.0, 55.0),
                       view_width_m=(25.0, 90.0), ok=_urban_view_ok),
    WALLS_PREFIX: dict(height_m=(4.0, 12.0), lens_mm=(28.0, 50.0), depression_deg=(10.0, 35.0),
                       view_width_m=(12.0, 45.0), ok=_walls_view_ok),
}


def _inside_footprint(p, item, margin):
    a = math.radians(item["rotation_z_deg"])
    px, py = p[0] - item["location"][0], p[1] - item["location"][1]
    u, v = math.cos(a) * px + math.sin(a) * py, -math.sin(a) * px + math.cos(a) * py
    eaves = item.get("eaves", 0.0)
    w, d = item["size"][0] / 2 + eaves, item["size"][1] / 2 + eaves
    return abs(u) < w + margin and abs(v) < d + margin


def _draw_urban(rng, sun_position, frames, resolution, view=URBAN_PREFIX):
    """Two to four buildings URBAN_HEIGHT_M tall with eaves on a street grid.
    view "urban": seen from a camera 12-45 m up that sees walls and ground;
    on the first, middle and last frame some walls that face the Sun lie in
    a building's shadow, and the ground shows shadow and sunlight. view
    "walls": from 4-12 m up across the street, walls fill most of the view,
    some lit and some in a building's shadow, more shadow on walls than on
    the ground (URBAN_VIEWS)."""
    how = URBAN_VIEWS[view]
    t, suns = _draw_time(rng, sun_position, frames, (1.0, 6.0), lambda s: True)
    north = round(rng.uniform(-180.0, 180.0), 2)
    width, height = resolution
    for _ in range(60 if view == URBAN_PREFIX else 300):
        height_m = rng.uniform(*how["height_m"])
        lens = rng.uniform(*how["lens_mm"])
        depression = rng.uniform(*how["depression_deg"])
        vfov_half = math.degrees(math.atan(SENSOR_WIDTH_MM * height / width / 2.0 / lens))
        if depression - vfov_half < 4.0:
            continue
        dist_h = height_m / math.tan(math.radians(depression))
        slant = math.hypot(height_m, dist_h)
        if not how["view_width_m"][0] <= slant * SENSOR_WIDTH_MM / lens <= how["view_width_m"][1]:
            continue
        yaw = rng.uniform(0.0, 360.0)
        loc = [dist_h * math.sin(math.radians(yaw)), dist_h * math.cos(math.radians(yaw)),
               height_m]
        spec = dict(kind="outdoor", **t, north_offset_deg=north,
                    camera={"location": [round(v, 4) for v in loc], "target": [0.0, 0.0, 0.0],
                            "lens_mm": round(lens, 2)},
                    render={"frames": frames, "resolution": list(resolution), "samples": 8},
                    urban={"buildings": 0} if view == URBAN_PREFIX else
                    {"buildings": 0, "view": view})
        cam = camera_of(spec)
        corners = [cam.ground_point(x, 0.0) for x in (0.0, float(width))]
        if any(c is None or math.hypot(c[0], c[1]) > 150.0 for c in corners):
            continue
        base = rng.uniform(0.0, 90.0)
        casters = []
        for k in range(rng.randint(2, 4)):
            w, d = rng.uniform(6.0, 14.0), rng.uniform(6.0, 14.0)
            item = dict(shape="building", name=f"Building{k + 1}",
                        size=[round(w, 3), round(d, 3), round(rng.uniform(*URBAN_HEIGHT_M), 3)],
                        eaves=round(rng.uniform(0.4, 1.0), 3),
                        rotation_z_deg=round(base + rng.choice((0.0, 90.0)), 2))
            for _ in range(100):
                g = cam.ground_point(rng.uniform(0.1, 0.9) * width, rng.uniform(0.3, 0.9) * height)
                if g is None:
                    continue
                item["location"] = [round(g[0], 3), round(g[1], 3), 0.0]
                # A street (at least 4 m) between buildings; the camera outside.
                if any(_overlap(item, q, 4.0) for q in casters) or \
                        _inside_footprint(loc, item, 3.0):
                    continue
                casters.append(item)
                break
        if len(casters) < 2:
            continue
        spec.update(casters=casters)
        spec["urban"]["buildings"] = len(casters)
        if how["ok"](urban_view(spec, sun_position)):
            break
    else:
        return None
    clutter = []
    for k in range(rng.randint(2, 5)):
        kind = rng.choice(["car", "person", "bin", "bench"])
        item = dict(shape=kind, name=f"Clutter{k + 1}_{kind}", size=_draw_clutter(rng, kind),
                    rotation_z_deg=round(base + rng.choice((0.0, 90.0)), 2))
        for _ in range(200):
            g = cam.ground_point(rng.uniform(0.05, 0.95) * width, rng.uniform(0.1, 0.95) * height)
            if g is None or any(_inside_footprint(g, q, 2.0) for q in casters):
                continue
            if all(math.hypot(g[0] - q["location"][0], g[1] - q["location"][1])
                   > _footprint_radius(item) + _footprint_radius(q) + 0.4 for q in clutter):
                item["location"] = [round(g[0], 3), round(g[1], 3), 0.0]
                clutter.append(item)
                break
    spec.update(clutter=clutter,
                ground={"kind": rng.choice(["paving", "asphalt", "cobbles"]), "name": "Ground",
                        "roughness": round(rng.uniform(0.55, 1.0), 3),
                        "specular": round(rng.uniform(0.2, 0.5), 3)})
    return spec


def _overlap(a, b, gap):
    """Whether two buildings on the same street grid (rotations differing by
    a multiple of 90 deg) come closer than `gap` metres."""
    base = math.radians(a["rotation_z_deg"])
    c, s = math.cos(base), math.sin(base)

    def half(item):
        turned = round((item["rotation_z_deg"] - a["rotation_z_deg"]) / 90.0) % 2
        w, d = item["size"][0] / 2 + item["eaves"], item["size"][1] / 2 + item["eaves"]
        return (d, w) if turned else (w, d)
    dx, dy = b["location"][0] - a["location"][0], b["location"][1] - a["location"][1]
    u, v = c * dx + s * dy, -s * dx + c * dy
    (aw, ad), (bw, bd) = half(a), half(b)
    return abs(u) < aw + bw + gap and abs(v) < ad + bd + gap


# ---------------------------------------------------------------------------
# Rough models (keys "rough<seed>")

def _draw_rough(rng, spec):
    """How the user's hand-made model differs from the true one."""
    casters = []
    for c in spec["casters"]:
        r, a = rng.uniform(*ROUGH_MOVE_M), rng.uniform(0.0, 2 * math.pi)
        casters.append({"name": c["name"],
                        "move_m": [round(r * math.cos(a), 4), round(r * math.sin(a), 4)],
                        "scale": [round(1.0 + rng.choice((-1.0, 1.0)) * rng.uniform(*ROUGH_SCALE),
                                        4) for _ in range(3)],
                        "turn_deg": round(rng.uniform(-ROUGH_TURN_DEG, ROUGH_TURN_DEG), 3)})
    axis = _unit([rng.gauss(0.0, 1.0) for _ in range(3)])
    return {"casters": casters,
            "camera": {"axis": [round(v, 5) for v in axis], "angle_deg": ROUGH_CAMERA_DEG,
                       "lens_factor": round(1.0 + rng.choice((-1.0, 1.0)) * ROUGH_LENS, 4)}}


def rough_item(item, rough):
    """The caster as the user modelled it (spec["rough_model"])."""
    r = next(c for c in rough["casters"] if c["name"] == item["name"])
    out = dict(item)
    out["location"] = [item["location"][0] + r["move_m"][0],
                       item["location"][1] + r["move_m"][1], item["location"][2]]
    out["size"] = [v * k for v, k in zip(item["size"], r["scale"])]
    out["rotation_z_deg"] = item["rotation_z_deg"] + r["turn_deg"]
    return out


# ---------------------------------------------------------------------------
# Overcast stretches and exposure ramps (keys "overcast<seed>")

def _draw_overcast(rng, frames):
    ramp = rng.randint(*OVERCAST_RAMP)
    margin = min(5 + ramp, max(0, (frames - 1) // 3))
    n = max(1, min(rng.randint(*OVERCAST_FRAMES), frames - 2 * margin))
    first = rng.randint(margin + 1, max(margin + 1, frames - margin - n + 1))
    return {"first": first, "last": min(frames, first + n - 1), "ramp_frames": ramp,
            "sky_level": round(rng.uniform(*OVERCAST_SKY_LEVEL), 3),
            "exposure_gain": round(rng.uniform(0.4, 0.8), 3),
            "exposure_ramp_ev": round(rng.choice((-1.0, 1.0)) * rng.uniform(0.3, 1.0), 3)}


def overcast_factor(spec, frame_index):
    """The share of the clear Sun's direct light that the cloud lets
    through on a frame (0-based): 0 in the overcast run, 1 outside it, a
    smooth ramp between (1 in scenes without an overcast run)."""
    o = spec.get("overcast")
    if not o:
        return 1.0
    f = frame_index + 1
    if o["first"] <= f <= o["last"]:
        return 0.0
    d = o["first"] - f if f < o["first"] else f - o["last"]
    return _smoothstep(0.0, 1.0, d / (o["ramp_frames"] + 1.0))


def no_direct_sun(spec, frame_index, zenith_deg):
    """Whether a frame has no direct sunlight in the footage, by
    construction: the Sun below the horizon, or an overcast frame."""
    return zenith_deg > 90.0 or overcast_factor(spec, frame_index) <= NO_SUN_FACTOR


def judged(spec, frame_index, zenith_deg, judged_max_zenith_deg):
    """Whether a frame is judged on its Sun's accuracy: the Sun high enough
    and the cloud letting most of it through."""
    return zenith_deg <= judged_max_zenith_deg and \
        overcast_factor(spec, frame_index) >= OVERCAST_JUDGED


# ---------------------------------------------------------------------------
# Trees over the ground (keys "trees<seed>"), footage only

def _draw_trees(rng, spec, sun_position):
    """One to three trees whose crowns' shadows fall in view on the first,
    middle and last frame; clear of the casters."""
    cam = camera_of(spec)
    suns = suns_of(spec, sun_position)
    north = spec["north_offset_deg"]
    suns_world = [sun_in_world(suns[i][0], suns[i][1] + north)
                  for i in check_frames(len(suns), suns)]
    trees = []
    for k in range(rng.randint(1, 3)):
        r = rng.uniform(1.2, 2.4)
        item = dict(shape="tree", name=f"Tree{k + 1}", size=[round(r, 3), 0.0, 0.0],
                    trunk_radius=round(rng.uniform(0.1, 0.2), 3),
                    trunk_height=round(rng.uniform(1.8, 3.2), 3),
                    leaf_seed=rng.randrange(1000), rotation_z_deg=0.0)
        crown_z = item["trunk_height"] + 0.8 * r
        for _ in range(200):
            g = cam.ground_point(rng.uniform(0.1, 0.9) * cam.width,
                                 rng.uniform(0.25, 0.9) * cam.height)
            if g is None or not cam.in_view(g, 0.06):
                continue
            if any(math.hypot(g[0] - q["location"][0], g[1] - q["location"][1])
                   < r + _footprint_radius(q) + 0.3 for q in spec["casters"] + trees):
                continue
            shadows = [[g[0] - crown_z / s[2] * s[0], g[1] - crown_z / s[2] * s[1], 0.0]
                       for s in suns_world]
            if all(cam.in_view(p, 0.05) for p in shadows):
                item["location"] = [round(g[0], 3), round(g[1], 3), 0.0]
                trees.append(item)
                break
    return trees


# ---------------------------------------------------------------------------
# Footage degradations

def _draw_degradations(rng, frames):
    clouds = []
    if rng.random() < 0.35:
        for _ in range(rng.randint(1, 2)):
            clouds.append({"frame": rng.randint(2, frames - 1), "width_frames": rng.randint(2, 5),
                           "depth": round(rng.uniform(0.3, 0.75), 3)})
    drift = None
    if rng.random() < 0.5:
        drift = {"amplitude_ev": round(rng.uniform(0.1, 0.5), 3),
                 "period_frames": round(rng.uniform(frames * 0.5, frames * 2.0), 2),
                 "phase": round(rng.uniform(0.0, 2 * math.pi), 3)}
    shake = round(rng.uniform(0.02, 0.1), 4) if rng.random() < 0.4 else 0.0
    return {"noise": rng.randint(0, 12), "crf": rng.randint(18, 30), "clouds": clouds,
            "exposure_drift": drift, "shake_deg": shake}


def _smoothstep(lo, hi, x):
    u = min(1.0, max(0.0, (x - lo) / (hi - lo)))
    return u * u * (3.0 - 2.0 * u)


def horizon_factor(zenith_deg):
    """Direct sunlight through the air near the horizon: none below it,
    fading in over HORIZON_FADE_DEG of altitude."""
    return _smoothstep(0.0, HORIZON_FADE_DEG, 90.0 - zenith_deg)


def twilight_light(spec, zenith_deg):
    """(sky strength factor, camera exposure offset in EV) at a Sun's
    zenith: the sky dims by half an EV a degree below the horizon and an
    auto-exposing camera makes up three quarters of it (at most
    MULTIDAY_MAX_GAIN_EV over a whole night); 1 and 0 in scenes without
    twilight or nights and while the Sun is up."""
    if "twilight" not in spec and "multiday" not in spec:
        return 1.0, 0.0
    below_ev = 0.5 * max(0.0, zenith_deg - 90.0)
    gain = 0.75 * below_ev
    if "multiday" in spec:
        gain = min(gain, MULTIDAY_MAX_GAIN_EV)
    return 2.0 ** -below_ev, gain


def keyed_sky(spec):
    """Whether the sky's strength changes over the clip (twilight, nights)."""
    return "twilight" in spec or "multiday" in spec


def overcast_sky(spec, frame_index):
    """How much of the sky is the overcast's flat grey (0 clear, 1 overcast)."""
    return 1.0 - overcast_factor(spec, frame_index)


def overcast_exposure_ev(spec, frame_index):
    """The overcast members' exposure: the camera makes up a share of the
    light the cloud takes, and the exposure ramps linearly over the clip."""
    o = spec.get("overcast")
    if not o:
        return 0.0
    n = spec["render"]["frames"]
    gain = o["exposure_gain"] * math.log2(1.0 / o["sky_level"]) * overcast_sky(spec, frame_index)
    return gain + o["exposure_ramp_ev"] * (frame_index / max(1, n - 1) - 0.5)


def sun_strength_factor(spec, frame_index, zenith_deg=None):
    """Clouds: the Sun's strength dips smoothly (1 = clear), and is off
    through an overcast run (overcast_factor); and fades at the horizon
    (horizon_factor) when the Sun's zenith is given."""
    f = 1.0 if zenith_deg is None else horizon_factor(zenith_deg)
    if spec.get("overcast"):
        f *= overcast_factor(spec, frame_index)
    for c in spec["degradations"]["clouds"]:
        x = (frame_index + 1 - c["frame"]) / max(c["width_frames"] / 2.0, 0.5)
        f *= 1.0 - c["depth"] * math.exp(-x * x)
    return f


def exposure_offset(spec, frame_index):
    d = spec["degradations"]["exposure_drift"]
    if not d:
        return 0.0
    return d["amplitude_ev"] * math.sin(2 * math.pi * frame_index / d["period_frames"] + d["phase"])


def _draw_motion(rng, spec, away=False):
    """A motion-control move through the drawn view (keys "moving<seed>"),
    or `away` from it and back."""
    right = camera_of(spec).right
    turn = math.radians(rng.uniform(-MOVING_RAIL_TURN_DEG, MOVING_RAIL_TURN_DEG))
    rail = _unit([right[0] * math.cos(turn) - right[1] * math.sin(turn),
                  right[0] * math.sin(turn) + right[1] * math.cos(turn), 0.0])
    tilt = rng.choice((-1.0, 1.0)) * rng.uniform(1.0, MOVING_TILT_DEG) \
        if rng.random() < 0.5 else 0.0
    motion = {"slide_m": round(rng.uniform(*MOVING_SLIDE_M), 3),
              "rail": [round(v, 5) for v in rail],
              "pan_deg": round(rng.choice((-1.0, 1.0)) * rng.uniform(*MOVING_PAN_DEG), 2),
              "tilt_deg": round(tilt, 2)}
    if away:
        fov = 2.0 * math.degrees(math.atan(SENSOR_WIDTH_MM / 2.0 / spec["camera"]["lens_mm"]))
        motion.update(away=True, pan_deg=round(math.copysign(MOVING_AWAY_SHARE * fov,
                                                             motion["pan_deg"]), 2))
    return motion


def camera_move(spec, frame_index):
    """Where a moving member's camera is on frame `frame_index` (0-based)
    against the drawn view: (location offset [x, y, z] m, pan about the
    world's Z deg, tilt about the camera's own x axis deg). Eased
    (smoothstep), zero on the middle frame (an `away` member's pan: zero at
    either end, full in the middle); None for a still camera."""
    m = spec.get("camera_motion")
    if m is None:
        return None
    n = spec["render"]["frames"]
    t = frame_index / max(1, n - 1)
    s = t * t * (3.0 - 2.0 * t) - 0.5
    # Away and back: the drawn view at either end, the full pan mid-clip.
    turn = math.sin(math.pi * t) if m.get("away") else s
    return ([m["slide_m"] * s * v for v in m["rail"]], m["pan_deg"] * turn, m["tilt_deg"] * s)


def solve_jitter(spec, frame_index):
    """A camera solve's error on frame `frame_index`: (location offset
    [x, y, z] m, rotation offsets about x, y, z deg), drawn per member and
    frame."""
    rng = random.Random(f"solve-{spec['key']}-{frame_index}")
    return ([rng.gauss(0.0, MOVING_JITTER_M) for _ in range(3)],
            [rng.gauss(0.0, MOVING_JITTER_DEG) for _ in range(3)])


def shake_offsets_deg(spec):
    """Per frame (x, y, z) rotation offsets of the camera, degrees."""
    s = spec["degradations"]["shake_deg"]
    rng = random.Random(f"shake-{spec['key']}")
    return [[round(rng.gauss(0.0, s), 5) if s else 0.0 for _ in range(3)]
            for _ in range(spec["render"]["frames"])]


# ---------------------------------------------------------------------------
# Fixed members

def _plaza14(key, yaw_deg, north, sun_position, frames, resolution):
    """The plaza of issue 14: a 3.2 m pole, a kiosk, a 5 m long 2 m high wall,
    tiled paving (roughness 0.9: brighter far away), a few small unmodelled
    objects; camera 9 m away, 6.5 m up, 28 mm; the Sun from the east at about
    50 deg zenith rising to about 16 deg at noon over 6.5 hours."""
    yaw = math.radians(yaw_deg)
    spec = dict(kind="outdoor", key=key,
                place={"latitude_deg": 39.47, "longitude_deg": -0.38},
                time={"start_local": "2025-06-21T10:15:00", "utc_offset_h": 2,
                      "minutes_per_frame": round(6.5 * 60 / (frames - 1), 3)},
                north_offset_deg=north,
                camera={"location": [9.0 * math.sin(yaw), 9.0 * math.cos(yaw), 6.5],
                        "target": [0.0, 0.0, 0.0], "lens_mm": 28.0},
                render={"frames": frames, "resolution": list(resolution), "samples": 8},
                ground={"kind": "paving", "name": "Ground", "roughness": 0.9, "specular": 0.2},
                casters=[
                    {"shape": "pole", "name": "Lamp", "size": [0.14, 0.14, 3.2], "round": True,
                     "location": [1.5, -0.8, 0.0], "rotation_z_deg": 0.0},
                    {"shape": "kiosk", "name": "Kiosk", "size": [2.0, 1.6, 2.5],
                     "roof_overhang": 0.3, "location": [-2.2, 1.0, 0.0], "rotation_z_deg": 15.0},
                    {"shape": "wall", "name": "Wall", "size": [5.0, 0.3, 2.0],
                     "location": [0.8, 3.2, 0.0], "rotation_z_deg": 8.0}],
                clutter=[
                    {"shape": "bin", "name": "Clutter1_bin", "size": [0.3, 0.0, 0.9],
                     "location": [-0.5, -2.0, 0.0], "rotation_z_deg": 0.0},
                    {"shape": "bench", "name": "Clutter2_bench", "size": [1.8, 0.5, 0.45],
                     "location": [2.8, 1.0, 0.0], "rotation_z_deg": 70.0},
                    {"shape": "bush", "name": "Clutter3_bush", "size": [0.45, 0.0, 0.0],
                     "location": [-3.5, -1.5, 0.0], "rotation_z_deg": 0.0}],
                degradations={"noise": 4, "crf": 23, "clouds": [], "exposure_drift": None,
                              "shake_deg": 0.0})
    return spec


FIXED = {
    # As issue 14 describes it: the camera looks north-west, the Sun rises in
    # the east behind it on the right.
    "plaza14": dict(yaw_deg=200.0, north=0.0),
    # The same plaza seen from the west with the compass turned.
    "plaza14_west": dict(yaw_deg=250.0, north=40.0),
}


def split_key(key):
    """(prefix, rest) of a member's key: prefix one of PREFIXES, or "" for
    the static members (seeds and FIXED)."""
    for prefix in PREFIXES:
        if key.startswith(prefix):
            return prefix, key[len(prefix):]
    return "", key


def draw(key, sun_position, frames=DEFAULT_FRAMES, resolution=DEFAULT_RESOLUTION):
    """The scene spec for `key`: an integer seed, <prefix><seed> for a
    prefix in PREFIXES, or a name in FIXED. Multi-day members have 1.5 times
    `frames`."""
    key = str(key)
    prefix, rest = split_key(key)
    if key in FIXED:
        spec = _plaza14(key, sun_position=sun_position, frames=frames,
                        resolution=resolution, **FIXED[key])
    else:
        try:
            seed = int(rest)
        except ValueError:
            raise ValueError(f"scene key must be an integer seed, <kind><seed> for a kind in "
                             f"{', '.join(PREFIXES)}, or one of {', '.join(sorted(FIXED))}, "
                             f"got '{key}'") from None
        # Members of a kind draw from their own stream (not seed N's scene).
        rng = random.Random(f"{prefix}-{seed}" if prefix else seed)
        room = not prefix and seed % ROOM_EVERY == ROOM_EVERY - 1
        if prefix == MULTIDAY_PREFIX:
            frames = frames * 3 // 2
        when = {TWILIGHT_PREFIX: "twilight", MULTIDAY_PREFIX: "multiday"}.get(prefix, "day")
        spec = None
        for _ in range(20):  # an unlucky draw (no caster fits) draws again
            if room:
                spec = _draw_room(rng, sun_position, frames, tuple(resolution))
            elif prefix in URBAN_VIEWS:
                spec = _draw_urban(rng, sun_position, frames, tuple(resolution), prefix)
            else:
                spec = _draw_outdoor(rng, sun_position, frames, tuple(resolution), when)
            if spec is not None and prefix == TREES_PREFIX:
                spec["trees"] = _draw_trees(rng, spec, sun_position)
                if not spec["trees"]:
                    spec = None  # no tree's shadow fits in this view
            if spec is not None:
                break
        if spec is None:
            raise RuntimeError(f"seed {seed}: no scene could be drawn")
        spec["key"] = key
        spec["degradations"] = _draw_degradations(rng, frames)
        spec["render"]["seed"] = seed
        if prefix == ROUGH_PREFIX:
            spec["rough_model"] = _draw_rough(rng, spec)
        elif prefix == OVERCAST_PREFIX:
            spec["overcast"] = _draw_overcast(rng, frames)
            # The run is the cloud and the ramp the exposure's change.
            spec["degradations"].update(clouds=[], exposure_drift=None)
        elif prefix == MOVING_PREFIX:
            spec["camera_motion"] = _draw_motion(rng, spec, seed >= MOVING_AWAY_FROM)
            spec["degradations"]["shake_deg"] = 0.0  # the solve's jitter instead
    spec["generator_version"] = GENERATOR_VERSION
    return spec


def describe(spec):
    """One short line: what the scene is."""
    p, t = spec["place"], spec["time"]
    hours = t["minutes_per_frame"] * (spec["render"]["frames"] - 1) / 60.0
    cam = spec["camera"]
    shapes = ",".join(c["shape"] for c in spec["casters"])
    deg = spec["degradations"]
    flags = [f for f, on in (("clouds", deg["clouds"]), ("drift", deg["exposure_drift"]),
                             ("shake", deg["shake_deg"])) if on]
    if "twilight" in spec:
        flags.insert(0, spec["twilight"]["side"])
    if "rough_model" in spec:
        flags.insert(0, "rough")
    if spec.get("overcast"):
        o = spec["overcast"]
        flags.insert(0, f"overcast {o['first']}-{o['last']}")
    if "multiday" in spec:
        flags.insert(0, f"{spec['multiday']['days']} days")
    if "camera_motion" in spec:
        m = spec["camera_motion"]
        flags.insert(0, f"slide {m['slide_m']:.1f}m pan {m['pan_deg']:+.0f}"
                        f"{' away and back' if m.get('away') else ''} "
                        f"tilt {m['tilt_deg']:+.0f}")
    if spec.get("trees"):
        flags.insert(0, f"{len(spec['trees'])} trees")
    return (f"{spec['kind']} lat {p['latitude_deg']:.1f} lon {p['longitude_deg']:.1f} "
            f"{t['start_local'][:16]} {hours:.1f}h N{spec['north_offset_deg']:+.0f} "
            f"cam {cam['location'][2]:.1f}m {cam['lens_mm']:.0f}mm {spec['ground']['kind']} "
            f"[{shapes}] {' '.join(flags)}").strip()
