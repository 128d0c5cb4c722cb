"""The whole-clip estimator (addon/estimate/whole_clip.py) and its per-segment
smoothing (estimate/finish.py) on frames drawn from a small model: a
pole, a box and a wall on a textured ground brighter far from the camera.
No Blender: frames are drawn with the native ray caster."""
import datetime as dt
import math
import os
import sys
import types

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# The add-on's package without its bpy registration (addon/__init__.py): its
# bpy-free modules import each other relatively.
if "sunlapse" not in sys.modules:
    _package = types.ModuleType("sunlapse")
    _package.__path__ = [os.path.join(ROOT, "addon")]
    sys.modules["sunlapse"] = _package
# One copy of the compiled module: the other tests import it as `_native`
# (conftest puts addon/ on the path); loading it again under a second name
# would register its types twice.
native = pytest.importorskip("_native")
sys.modules.setdefault("sunlapse._native", native)
from sunlapse.estimate import calibration, finish, sun_circle  # noqa: E402
from sunlapse.estimate import options as estimate_options  # noqa: E402
from sunlapse.estimate.raw import RawSun  # noqa: E402
from sunlapse.core import angles  # noqa: E402
from sunlapse.estimate import moving_view as moving, untimed, whole_clip  # noqa: E402

W, H = 320, 200


def look_at(eye, target):
    eye, target = np.asarray(eye, float), np.asarray(target, float)
    back = eye - target
    back /= np.linalg.norm(back)
    right = np.cross([0.0, 0.0, 1.0], back)
    right /= np.linalg.norm(right)
    up = np.cross(back, right)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = right, up, back, eye
    return m


def box(lo, hi, base):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    f = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
         (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    return v, [tuple(i + base for i in t) for t in f]


def sun(zenith, azimuth):
    return angles.sun_in_world_from_angles(zenith, azimuth)


def path(k, n):
    """The Sun over the clip: zenith 58 -> 30, azimuth 100 -> 170 deg."""
    t = k / max(1, n - 1)
    return sun(58 - 28 * t, 100 + 70 * t)


def model(rough=None):
    """The ground (0), a post (1), a box (2) and a wall (3); `rough`: {id:
    (dx, dy, z scale)} for a hand-made model's errors."""
    verts = [(-20, -20, 0), (20, -20, 0), (20, 20, 0), (-20, 20, 0)]
    tris = [(0, 1, 2), (0, 2, 3)]
    ids = [0, 0]
    for lo, hi, oid in (((-0.08, -0.08, 0), (0.08, 0.08, 3.2), 1),
                        ((2.0, 1.0, 0), (3.2, 2.2, 2.4), 2),
                        ((-4.0, 3.0, 0), (1.0, 3.25, 2.0), 3)):
        dx, dy, kz = (rough or {}).get(oid, (0.0, 0.0, 1.0))
        v, f = box((lo[0] + dx, lo[1] + dy, lo[2]), (hi[0] + dx, hi[1] + dy, hi[2] * kz),
                   len(verts))
        verts += v
        tris += f
        ids += [oid] * len(f)
    return native.Scene(np.array(verts, np.float32), np.array(tris, np.int32),
                        np.array(ids, np.int32))


@pytest.fixture(scope="module")
def world():
    scene = model()
    camera = native.Camera.from_blender(lens_mm=28, sensor_width_mm=36, sensor_height_mm=24,
                                        width=W, height=H,
                                        matrix_world=look_at((-3, -9, 6.5), (0, 1, 0)))
    ys, xs = np.mgrid[0:H, 0:W]
    pixels = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)
    hits = scene.intersect_pixels(camera, pixels)
    rng = np.random.default_rng(5)
    texture = (0.35 + 0.15 * rng.random((H, W))).astype(np.float32)
    # Non-Lambertian ground: 25% brighter far from the camera (top rows).
    gradient = (1.25 - 0.25 * np.arange(H) / H)[:, None].astype(np.float32)
    return scene, camera, hits, texture * gradient


def draw(world, d, seed=0, direct=0.75):
    """A frame in sunlight: ambient 0.25 and the Sun's `direct` light (a
    hazy Sun's is weaker)."""
    scene, camera, hits, albedo = world
    seen = hits["object_id"] >= 0
    pts = np.nan_to_num(hits["point"]).astype(np.float32)
    normals = np.nan_to_num(hits["normal"]).astype(np.float32)
    origins = pts + 1e-3 * normals
    shadow = scene.occluded(origins, np.repeat(d[None].astype(np.float32), len(pts), axis=0))
    cos = np.clip(normals @ d.astype(np.float32), 0, None)
    light = (0.25 + direct * cos * ~shadow).reshape(H, W)
    img = np.where(seen.reshape(H, W), albedo * light, 0.6)
    noise = np.random.default_rng(seed).normal(0, 0.005, img.shape)
    return np.clip(img + noise, 0, 1).astype(np.float32)


def error_deg(u, truth):
    u = np.asarray(u, float)
    return math.degrees(math.atan2(np.linalg.norm(np.cross(u, truth)), float(u @ truth)))


def run(world, frames_gray, times_s=None, fit_circle=None):
    scene, camera = world[0], world[1]
    numbers = list(range(1, len(frames_gray) + 1))
    return whole_clip.estimate(native, scene, camera, numbers, lambda f: frames_gray[f - 1], [0],
                               times_s=times_s, fit_circle=fit_circle)


def raw_sun(r):
    """The finishing's raw Sun of a whole-clip frame (north = +Y)."""
    if r.sun_in_world is None:
        return RawSun(r.frame, confidence=r.on_circle, reason=r.reason)
    z, a = angles.angles_from_sun_in_world(r.sun_in_world)
    return RawSun(r.frame, z, a, r.on_circle, r.reason)


def smooth(result):
    raws = [raw_sun(r) for r in result.frames]
    opts = estimate_options.EstimateOptions()
    return finish._smooth_segments([r.frame for r in raws], raws, result.segments, "two_pass",
                                   opts, None, paced=result.paced)


def test_every_frame_within_a_degree_despite_a_gradient_and_broken_frames(world):
    n = 30
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, truth[k], k) for k in range(n)]
    garbled = np.random.default_rng(9).random((H, W)).astype(np.float32)
    broken = {0: garbled, 1: None, 14: garbled, 15: None}  # the first frames too
    frames = [broken.get(k, frames[k]) for k in range(n)]
    result = run(world, frames)
    assert result.jumps == []
    for k, r in enumerate(result.frames):
        if k in broken and broken[k] is None:
            assert r.sun_in_world is None and r.reason
            continue
        if k in broken:  # garbled: carried by its neighbours, not confident
            assert r.confidence < 0.3, (k, r)
            continue
        assert error_deg(r.sun_in_world, truth[k]) < 1.0, (k, r)
    # The garbled first frame is beyond the measured span: no estimate.
    assert result.frames[0].sun_in_world is None


def test_a_looped_clip_is_split_and_smoothing_keeps_each_side(world):
    n = 16
    truth = [path(k, n) for k in range(n)] * 2
    frames = [draw(world, d, k) for k, d in enumerate(truth)]
    result = run(world, frames)
    assert result.jumps == [n + 1]
    assert [len(s) for s in result.segments] == [n, n]
    zs, azs = smooth(result)
    for k in range(2 * n):
        raw = result.frames[k]
        raw_error = error_deg(raw.sun_in_world, truth[k])
        smooth_error = error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), truth[k])
        assert smooth_error < max(1.0, 2 * raw_error), (k, raw_error, smooth_error)


def test_an_undecodable_tail_has_no_estimate_and_is_not_extrapolated(world):
    n = 20
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, d, k) for k, d in enumerate(truth[:14])] + [None] * 6
    result = run(world, frames)
    zs, azs = smooth(result)
    for k in range(14, n):
        assert result.frames[k].sun_in_world is None and result.frames[k].reason
        assert zs[k] is None and azs[k] is None
    for k in range(14):
        assert error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), truth[k]) < 1.0


def test_capture_times_going_back_start_a_segment(world):
    n = 12
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, d, k) for k, d in enumerate(truth)]
    times = [600.0 * k for k in range(n)]
    times[6:] = [t - 86400.0 * 0 - 3600.0 * 5 for t in times[6:]]  # back five hours
    result = run(world, frames, times)
    assert [s[0] for s in result.segments] == [1, 7]
    assert result.jumps == []  # a known jump, not an unexplained one


def test_a_clean_clip_is_read_once_and_followed_on_every_frame(world):
    """Every frame is decoded once: the pass scores and tracks it; no frame is
    read again when the tracked Suns agree with the path (issue 18)."""
    n = 40
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, truth[k], k) for k in range(n)]
    reads = []

    def read_gray(f):
        reads.append(f)
        return frames[f - 1]
    scene, camera = world[0], world[1]
    result = whole_clip.estimate(native, scene, camera, list(range(1, n + 1)), read_gray, [0])
    assert result.timing["frames_read"] == len(reads)
    # The reference frames (spread over the clip) are read first; on a
    # clip this short they are kept for the pass, which reads the others.
    assert sorted(reads) == list(range(1, n + 1))
    for k, r in enumerate(result.frames):
        assert r.refined, (k, r.reason)
        assert error_deg(r.sun_in_world, truth[k]) < 1.0, k


def test_frames_wider_than_the_working_size_are_estimated_reduced(world, monkeypatch):
    """Frames wider than WORKING_MAX_WIDTH are reduced by a power of two
    before the evidence and the tracker see them (issue 18)."""
    monkeypatch.setattr(whole_clip, "WORKING_MAX_WIDTH", W // 2)
    assert whole_clip.working_factor(W) == 2
    assert whole_clip.working_factor(W // 2) == 1
    assert whole_clip.working_factor(W + 1) == 4
    n = 20
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, truth[k], k) for k in range(n)]
    result = run(world, frames)
    assert result.tracker_pixel_scale == 2.0
    assert all(r.refined for r in result.frames)
    # 160x100 pixels: the pole is half a pixel wide.
    errors = [error_deg(r.sun_in_world, truth[k]) for k, r in enumerate(result.frames)]
    assert np.mean(errors) < 1.0 and max(errors) < 2.0, errors


def sun_on_its_circle(k):
    """The Sun at 40 deg N, declination 12 deg, frame k 6 minutes after
    frame k-1 from 08:00 (4 h before noon): 1.5 deg of hour angle a frame."""
    lat, dec = math.radians(40.0), math.radians(12.0)
    pole = np.array([0.0, math.cos(lat), math.sin(lat)])  # north is +Y
    e1 = np.cross(pole, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(pole, e1)
    h = math.radians(-60.0 + 1.5 * k)
    return math.cos(dec) * (math.cos(h) * e1 + math.sin(h) * e2) + math.sin(dec) * pole


def frame_times(n):
    import datetime as dt
    t0 = dt.datetime(2025, 6, 1, 8, 0, tzinfo=dt.timezone.utc)
    return [t0 + dt.timedelta(minutes=6 * k) for k in range(n)]


def doubted(raws, times):
    """Whole-clip frames for (frame, zenith, azimuth, confidence) after the
    segment's circle doubted them; the finishing's raw Suns and the circle
    ({index: (zenith, azimuth)}) as whole_clip.run hands them on."""
    seg = [whole_clip.RawFrame(f, angles.sun_in_world_from_angles(z, a), c)
           for f, z, a, c in raws]
    seconds = [(t - times[0]).total_seconds() for t in times]
    whole_clip.doubt_off_circle(seg, seconds, True, sun_circle.fit_trimmed)
    circle = {k: tuple(float(v) for v in angles.angles_from_sun_in_world(r.circle_in_world))
              for k, r in enumerate(seg) if r.circle_in_world is not None}
    return seg, [raw_sun(r) for r in seg], circle


def test_suns_off_their_circle_lose_confidence():
    """The Sun's path over a segment is a small circle about the pole: raw
    Suns far off the circle fitted to the segment lose their confidence, the
    further the more (whole_clip.doubt_off_circle); the others keep it."""
    frames = list(range(1, 41))
    times = frame_times(40)
    off = {7: 8.0, 20: 6.0, 33: 10.0}
    raws = []
    for k, f in enumerate(frames):
        z, a = angles.angles_from_sun_in_world(sun_on_its_circle(k))
        z = float(z) + off.get(f, 0.0)
        raws.append((f, z, float(a) % 360.0, 0.95))
    seg, _, _ = doubted(raws, times)
    conf = {r.frame: r.on_circle for r in seg}
    for f in frames:
        if f in off:
            assert conf[f] < 0.4, f
        else:
            assert conf[f] == 0.95, f
    assert conf[20] > conf[7] > conf[33]  # 6, 8 and 10 deg off


class _Pinned:
    """What doubt_off_circle reads of a native TrackedFrame."""

    def __init__(self, within_deg):
        self.elevation_pinned_deg = within_deg


def test_suns_whose_height_the_shadows_do_not_pin_take_the_pinned_frames_circle():
    """A camera that sees only the casters' feet (moving12's first frames)
    pins the Sun's azimuth, not its height: any lower Sun lengthens the
    shadows out of view alike, and the tracker settles anywhere down there.
    Such frames, too far off the circle of the frames that pin it for
    their shadows to be taken for the Sun's, take that circle's Sun,
    doubted; one whose shadows point another way keeps its Sun and loses
    confidence as any Sun off its circle does."""
    n = 30
    times = frame_times(n)  # 40 N, 1 June, every 6 minutes from 08:00 UTC
    unpinned = set(range(1, 13))  # frames 1-12
    raws, truth = [], []
    for t in times:
        z, a = native.sun_position(t.year, t.month, t.day, t.hour, t.minute, 0.0, 40.0, 0.0)
        truth.append(sun(z, a))
        k = len(raws)
        low = 12.0 + k if k + 1 in unpinned else 0.0  # 12-23 deg too low
        turned = 10.0 if k + 1 == 12 else 0.0  # and frame 12 turned
        raws.append((k + 1, z + low, (a + turned) % 360.0, 0.95))
    seg = [whole_clip.RawFrame(f, angles.sun_in_world_from_angles(z, a), c, on_circle=c,
                               refined=True, tracked=_Pinned(99.0 if f in unpinned else 0.5))
           for f, z, a, c in raws]
    seconds = [(t - times[0]).total_seconds() for t in times]
    whole_clip.doubt_off_circle(seg, seconds, True, sun_circle.fit_trimmed)
    for k, r in enumerate(seg):
        if r.frame in unpinned and r.frame != 12:
            assert error_deg(r.sun_in_world, truth[k]) < 0.5, r
            assert r.on_circle < calibration.DOUBTED_SUPPORT, r
        elif r.frame == 12:
            assert error_deg(r.sun_in_world, truth[k]) > 10.0, r  # its own
            assert r.on_circle < 0.95 * (whole_clip.CIRCLE_DOUBT_DEG / 10.0) ** 2, r
        else:
            assert r.on_circle == 0.95 and error_deg(r.sun_in_world, truth[k]) < 1e-6, r
    # Too few frames pin it for a circle of their own: all of them set it,
    # and the frames keep their Suns.
    few = [whole_clip.RawFrame(r.frame, angles.sun_in_world_from_angles(z, a), 0.95,
                               on_circle=0.95, refined=True,
                               tracked=_Pinned(0.5 if r.frame > n - 4 else 99.0))
           for r, (_, z, a, _) in zip(seg, raws)]
    whole_clip.doubt_off_circle(few, seconds, True, sun_circle.fit_trimmed)
    assert all(r.confidence == 0.95 for r in few)


def test_frames_past_the_confident_span_follow_the_circle_not_the_fit():
    """Frames past a segment's last confident one (shadows fading at
    sunset, followed without evidence: confidence near 0) are not where a
    fit extrapolates: they take the span's end Sun turned as the Sun's
    circle turns; with no circle, their raw Sun within the Sun's motion."""
    n, confident = 40, 30
    frames = list(range(1, n + 1))
    times = frame_times(n)
    raws = []
    for k, f in enumerate(frames):
        z, a = angles.angles_from_sun_in_world(sun_on_its_circle(k))
        if k < confident:
            raws.append((f, float(z), float(a) % 360.0, 0.95))
        else:  # the tracker wanders off as the shadows fade
            raws.append((f, float(z) + 1.5 * (k - confident + 1), float(a) - 4.0 * (k - confident),
                         0.01))
    _, raws, circle = doubted(raws, times)
    opts = estimate_options.EstimateOptions()
    for along, worst in ((circle, 0.3), (None, None)):
        zs, azs = finish._smooth_segments(frames, raws, [frames], "two_pass", opts, times,
                                          along)
        end = angles.sun_in_world_from_angles(zs[confident - 1], azs[confident - 1])
        for k in range(confident, n):
            got = angles.sun_in_world_from_angles(zs[k], azs[k])
            if worst is not None:
                assert error_deg(got, sun_on_its_circle(k)) < worst, k
            # Never further from the span's end than the Sun moves (15.5
            # deg an hour, 6 minutes a frame), whatever the raw Suns do.
            assert angles.angle_between_deg(got, end) <= 1.55 * (k - confident + 1) + 1e-6, k


def test_a_doubted_run_is_carried_by_the_circle_and_the_confident_frames():
    """A segment's first ten frames doubted by the evidence (confidence
    0.05-0.41) and drifting from a 6 deg too low Sun back to the path:
    two-pass smoothing fits the raw Suns' offsets from the segment's circle
    with a window that widens over them, so the confident frames carry
    them; without the circle it follows them."""
    n = 32
    frames = list(range(1, n + 1))
    times = frame_times(n)
    rng = np.random.default_rng(5)
    raws = []
    for k, f in enumerate(frames):
        z, a = angles.angles_from_sun_in_world(sun_on_its_circle(k))
        z, a = float(z) + rng.normal(0, 0.3), float(a) + rng.normal(0, 0.3)
        if k < 10:
            raws.append((f, z + 6.0 - 0.5 * k, a % 360.0, 0.05 + 0.04 * k))
        else:
            raws.append((f, z, a % 360.0, 0.85))
    _, raws, circle = doubted(raws, times)
    assert circle
    opts = estimate_options.EstimateOptions()
    for along, worst in ((circle, 0.6), (None, None)):
        zs, azs = finish._smooth_segments(frames, raws, [frames], "two_pass", opts, times,
                                          along)
        errors = [error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), sun_on_its_circle(k))
                  for k in range(n)]
        if worst is not None:
            assert max(errors) < worst, max(errors)
        else:
            assert max(errors) > 2.0, max(errors)


def draw_dusk(world, level, seed=0):
    """A frame without direct sunlight: the sky's light only, dimmer near
    the objects as ambient occlusion makes it (the darkening a Sun near the
    zenith would put there: the trap a dark frame sets), at `level` of the
    lit frames' ambient."""
    scene, camera, hits, albedo = world
    seen = hits["object_id"] >= 0
    pts = np.nan_to_num(hits["point"]).astype(np.float32)
    normals = np.nan_to_num(hits["normal"]).astype(np.float32)
    origins = pts + 1e-3 * normals
    sky = np.zeros(len(pts), np.float32)
    tilts = [(0.0, 0.0), (25.0, 0.0), (25.0, 120.0), (25.0, 240.0), (50.0, 60.0),
             (50.0, 180.0), (50.0, 300.0)]
    for z, a in tilts:  # a few sky directions stand for the sky's dome
        d = sun(z, a).astype(np.float32)
        sky += ~scene.occluded(origins, np.repeat(d[None], len(pts), axis=0))
    light = (level * sky / len(tilts)).reshape(H, W)
    img = np.where(seen.reshape(H, W), albedo * light, 0.6 * level)
    noise = np.random.default_rng(seed).normal(0, 0.005, img.shape)
    return np.clip(img + noise, 0, 1).astype(np.float32)


@pytest.mark.parametrize("times", [False, True])
def test_frames_after_sunset_have_no_sunlight_and_a_predicted_sun(world, times):
    """Dusk: the last frames have no direct sunlight. They start no segment
    of their own, keep no Sun of their own (a dark frame's best direction is
    whatever its ambient shading resembles: overhead, on a real sundial
    webcam) and get their segment's path, at confidence 0 (issue 25)."""
    n, lit = 30, 22
    # The Sun as it moves (40 N, 1 June, every 10 minutes from 07:40 UTC at
    # longitude 0): the circle carries on as it did.
    when = [dt.datetime(2025, 6, 1, 7, 40) + dt.timedelta(minutes=10 * k) for k in range(n)]
    truth = [sun(*native.sun_position(t.year, t.month, t.day, t.hour, t.minute, 0.0, 40.0, 0.0))
             for t in when]
    frames = [draw(world, truth[k], k) if k < lit else draw_dusk(world, 0.3, k)
              for k in range(n)]
    result = run(world, frames, [600.0 * k for k in range(n)] if times else None,
                 sun_circle.fit_trimmed)
    assert len(result.segments) == 1 and result.jumps == []
    Sunlight = whole_clip.Sunlight
    for k, r in enumerate(result.frames):
        if k < lit:
            assert r.sunlight == Sunlight.YES, (k, r)
            assert error_deg(r.sun_in_world, truth[k]) < 1.0, (k, r)
        else:
            assert r.sunlight == Sunlight.NO, (k, r)
            assert r.sun_in_world is None and r.confidence == 0.0 and r.reason, (k, r)
    raws = [whole_clip._raw_sun(r, 0.0) for r in result.frames]
    # Every Sun of the day was checked by its circle (none held below 0.5).
    assert all(raw.circle_checked for raw in raws if raw.has_sun)
    circle = {k: angles.angles_from_sun_in_world(r.circle_in_world)
              for k, r in enumerate(result.frames) if r.circle_in_world is not None}
    zs, azs = finish._smooth_segments([r.frame for r in raws], raws, result.segments,
                                      "two_pass", estimate_options.EstimateOptions(),
                                      when if times else None, circle)
    for k in range(lit, n):  # the Sun's circle carried on
        assert zs[k] is not None, k
        assert error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), truth[k]) < 1.0, k


def test_a_hazy_suns_faint_shadows_are_sunlight_in_a_clip_that_shows_the_sun(world):
    """A hazy Sun's shadows are faint: the tracker fits them a contrast
    between SUNLIT_HAZY_CONTRAST and SUNLIT_MIN_CONTRAST (1.08-1.15 here, as
    on the Marseille March dial's hazy frames). Among frames that show the
    Sun they are in sunlight and keep their own Sun (issue 25)."""
    n = 24
    truth = [path(k, n) for k in range(n)]
    hazy = range(1, n, 3)
    frames = [draw(world, truth[k], k, direct=0.28 if k in hazy else 0.75) for k in range(n)]
    result = run(world, frames, [600.0 * k for k in range(n)])
    assert len(result.segments) == 1
    for k in hazy:
        r = result.frames[k]
        assert r.sunlight == whole_clip.Sunlight.YES and r.sun_in_world is not None, (k, r)
        assert whole_clip.SUNLIT_HAZY_CONTRAST <= r.tracked.contrast < \
            whole_clip.SUNLIT_MIN_CONTRAST, (k, r.tracked.contrast)
        assert error_deg(r.sun_in_world, truth[k]) < 1.0, (k, r)


def test_dark_segments_join_their_neighbours():
    measured = [False, False, True, True, True, False, False, True, True, False, False]
    starts = [0] * 11
    # A jump into and out of frames without evidence is no jump of the Sun.
    assert whole_clip._without_dark_segments([0, 2, 5, 7, 9, 11], measured, starts) == [0, 7, 11]
    # Between two segments with evidence the jump stays; a caller's start
    # (times going back) always stays.
    starts[9] = 1
    assert whole_clip._without_dark_segments([0, 7, 9, 11], measured, starts) == [0, 7, 9, 11]


def test_a_loop_whose_sun_goes_back_less_than_a_step_is_split(world):
    """Four loops of a clip whose Sun moves half a degree a frame: going
    back 9 deg at each loop is a step the untimed path allows (12 deg), so
    it was one segment, and the smoothing across the loops ran 4.7 deg off
    (issue 25). The Sun going back along its path starts a segment."""
    n = 20
    once = [sun(50 - 0.3 * k, 120 + 0.4 * k) for k in range(n)]
    truth = once * 4
    result = run(world, [draw(world, d, k) for k, d in enumerate(truth)], None,
                 sun_circle.fit_trimmed)
    assert result.jumps == [n + 1, 2 * n + 1, 3 * n + 1]
    assert [len(s) for s in result.segments] == [n] * 4
    zs, azs = smooth(result)
    for k in range(4 * n):
        assert error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), truth[k]) < 1.0, k
    # A clip that only goes forward is not cut, whatever its pace.
    steady = [sun(50 - 0.3 * k, 120 + 0.4 * k) for k in range(2 * n)]
    assert run(world, [draw(world, d, k) for k, d in enumerate(steady)], None,
               sun_circle.fit_trimmed).jumps == []


def test_a_clip_played_forward_and_back_is_split_where_it_turns(world):
    """A clip played forward then backward (a boomerang edit) with no times:
    the Sun never turns back along its path, so a segment's circle, fitted
    with the frame as its clock, cannot follow the turn. One segment, its
    frames near the turns were taken for shadows that are not the Sun's and
    predicted 4-14 deg off (the speed benchmark's ping-pong clip). Where the
    Sun turns back over the path it came along, a segment starts."""
    n = 20
    forward = [sun(50 - 0.3 * k, 120 + 0.4 * k) for k in range(n)]
    truth = forward + forward[::-1] + forward
    result = run(world, [draw(world, d, k) for k, d in enumerate(truth)], None,
                 sun_circle.fit_trimmed)
    assert [len(s) for s in result.segments] == [n] * 3, result.segments
    zs, azs = smooth(result)
    for k in range(3 * n):
        assert error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), truth[k]) < 1.0, k
    # A Sun that only slows down and goes on is no turn.
    slowing = [sun(50 - 0.3 * k * (1.0 - k / (4.0 * n)), 120 + 0.4 * k * (1.0 - k / (4.0 * n)))
               for k in range(2 * n)]
    assert run(world, [draw(world, d, k) for k, d in enumerate(slowing)], None,
               sun_circle.fit_trimmed).jumps == []


def test_a_clip_whose_interval_changes_keeps_every_frames_sun(world):
    """A time-lapse whose interval triples halfway (a day-to-night ramp),
    no times: the segment's circle, clocked by frame numbers, was fitted to
    the first part and took the faster part's frames for shadows that are
    not the Sun's; 12 of 40 frames came back without a Sun, the others
    0.1-0.4 deg off. The circle's clock follows the Sun's pace."""
    pace = [k if k < 20 else 20 + 3 * (k - 20) for k in range(40)]
    truth = [sun(60 - 0.5 * p, 100 + 0.8 * p) for p in pace]
    result = run(world, [draw(world, d, k) for k, d in enumerate(truth)], None,
                 sun_circle.fit_trimmed)
    assert all(r.sunlight == whole_clip.Sunlight.YES and r.sun_in_world is not None
               for r in result.frames)
    zs, azs = smooth(result)
    for k in range(40):
        assert error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), truth[k]) < 1.0, k


def test_the_pace_clock_is_the_frame_numbers_while_the_pace_holds():
    """A steady clip's clock stays its frame numbers (its fits as they
    were), scatter and a stray Sun included; a pace that doubles gives a
    clock that runs twice as fast from there."""
    rng = np.random.default_rng(2)
    n = 60

    def on_circle(hours):   # the Sun at 45 N in April, 4 minutes a frame
        pole, e1, e2 = (np.array(v) for v in ([0.0, 0.5 ** 0.5, 0.5 ** 0.5],
                                              [0.0, -(0.5 ** 0.5), 0.5 ** 0.5], [1.0, 0.0, 0.0]))
        dec = math.radians(10.0)
        return [math.cos(dec) * (math.cos(h) * e1 + math.sin(h) * e2) + math.sin(dec) * pole
                for h in (-1.0 - math.radians(15.0) * np.asarray(hours, float))]
    steady = [s + rng.normal(0, 0.002, 3) for s in on_circle([k / 15.0 for k in range(n)])]
    steady[30] = sun(20.0, 200.0)
    numbers = list(range(1, n + 1))
    assert untimed.pace_clock(steady, numbers, [0] * n) is None
    doubled = on_circle([(k if k < 30 else 30 + 2 * (k - 30)) / 15.0 for k in range(n)])
    clock = untimed.pace_clock(doubled, numbers, [0] * n)
    assert clock is not None and clock[0] == 1.0
    steps = np.diff(clock)
    assert np.median(steps[5:20]) == pytest.approx(0.5 * np.median(steps[40:55]), rel=0.05)


def test_the_clock_puts_night_frames_in_the_dark_unless_it_contradicts_the_footage(world):
    """With capture times and a place, a frame the ephemeris puts below the
    horizon has no direct sunlight even when it shows hard shadows (street
    lights: the Mulhouse webcam's night frames); a clock that puts most
    sunlit frames at night is a wrong zone, and is not used (issue 25)."""
    n, night = 12, 6
    frames = [draw(world, path(k, n), k) for k in range(n)]
    frames[night] = draw(world, sun(40.0, 250.0), night)   # a street lamp's shadows
    elevation = [35.0] * n
    elevation[night] = -8.0
    scene, camera = world[0], world[1]
    numbers = list(range(1, n + 1))

    def estimate(elevations):
        return whole_clip.estimate(native, scene, camera, numbers,
                                   lambda f: frames[f - 1], [0],
                                   times_s=[600.0 * k for k in range(n)],
                                   clock_elevation_deg=elevations)
    result = estimate(elevation)
    Sunlight = whole_clip.Sunlight
    assert result.clock_trusted and result.clock_night == [night + 1]
    assert result.frames[night].sunlight == Sunlight.NO
    assert result.frames[night].sun_in_world is None and result.frames[night].confidence == 0.0
    assert all(r.sunlight == Sunlight.YES for k, r in enumerate(result.frames) if k != night)
    # The finishing puts its Sun where the ephemeris does, below the horizon.
    raw = whole_clip._raw_sun(result.frames[night], 0.0, (98.0, 250.0), True)
    assert raw.clock_sun == (98.0, 250.0) and raw.clock_night and not raw.has_sun

    wrong = estimate([-20.0] * n)   # every frame at night: the zone is wrong
    assert wrong.clock_trusted is False and wrong.clock_night == []
    assert len(wrong.clock_contradicted) >= 3
    assert sum(r.sunlight == Sunlight.YES for r in wrong.frames) >= n - 1
    # Nor does a clock the footage contradicts predict any frame's Sun.
    suns = {f: (60.0, 100.0 + f) for f in numbers}
    assert whole_clip._clock_suns(suns, wrong.clock_trusted) == {}
    assert whole_clip._clock_suns(suns, result.clock_trusted) == suns


@pytest.mark.parametrize("independent", [True, False])
def test_reference_frames_are_kept_on_a_long_clip_whose_frames_decode_alone(
        world, monkeypatch, independent):
    """Stills and intra-only video: the pass skips the reference frames at no
    cost, so they are kept whatever the clip's length; a long-GOP video
    decodes them again (issue 28)."""
    monkeypatch.setattr(whole_clip, "SHORT_CLIP_FRAMES", 8)
    n = 30
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, truth[k], k) for k in range(n)]
    reads = []

    class Stream:
        frames_independent = independent

        def __init__(self, fs):
            self.fs = fs

        def __iter__(self):
            for f in self.fs:
                reads.append(f)
                yield f, frames[f - 1]

    def source(fs, size):
        reads.extend(fs)
        index_of = {f: i for i, f in enumerate(fs)}
        return native.FrameList([(i, frames[f - 1]) for i, f in enumerate(fs)]), index_of

    scene, camera = world[0], world[1]
    result = whole_clip.estimate(native, scene, camera, list(range(1, n + 1)), None, [0],
                                 stream=lambda fs, near, size: Stream(fs), source=source)
    reference = {frame for frame in reads[:whole_clip.REFERENCE_FRAMES]}
    read_twice = sorted(f for f in set(reads) if reads.count(f) > 1)
    assert read_twice == ([] if independent else sorted(reference))
    for k, r in enumerate(result.frames):
        assert error_deg(r.sun_in_world, truth[k]) < 1.0, k


# -- a moving camera (issue 26) -------------------------------------------

def moving_view(k, n):
    """A slider and a pan head: 1.5 m along the rail and 12 deg of pan over
    the clip, eased, with a solve's jitter (a few mm)."""
    t = k / max(1, n - 1)
    s = 0.5 - 0.5 * math.cos(math.pi * t)
    jitter = np.random.default_rng(100 + k).normal(0, 0.002, 3)
    eye = np.array([-3.75 + 1.5 * s, -9.0, 6.5]) + jitter
    pan = math.radians(-6 + 12 * s)
    c, si = math.cos(pan), math.sin(pan)
    target = eye + np.array([3.0 * c - 10.0 * si, 3.0 * si + 10.0 * c, -6.5])
    return native.Camera.from_blender(lens_mm=28, sensor_width_mm=36, sensor_height_mm=24,
                                      width=W, height=H, matrix_world=look_at(eye, target))


def draw_from(world, camera, d, seed=0):
    """draw() for any camera: the ground's texture is fixed to the world."""
    scene = world[0]
    ys, xs = np.mgrid[0:H, 0:W]
    pixels = np.stack([xs.ravel(), ys.ravel()], axis=1).astype(np.float64)
    hits = scene.intersect_pixels(camera, pixels)
    seen = hits["object_id"] >= 0
    pts = np.nan_to_num(hits["point"]).astype(np.float32)
    normals = np.nan_to_num(hits["normal"]).astype(np.float32)
    cell = np.floor(pts[:, 0] * 3.0) * 7.0 + np.floor(pts[:, 1] * 3.0) * 13.0
    albedo = 0.35 + 0.15 * (np.sin(cell) * 0.5 + 0.5)
    shadow = scene.occluded(pts + 1e-3 * normals,
                            np.repeat(d[None].astype(np.float32), len(pts), axis=0))
    cos = np.clip(normals @ d.astype(np.float32), 0, None)
    img = np.where(seen, albedo * (0.25 + 0.75 * cos * ~shadow), 0.6).reshape(H, W)
    noise = np.random.default_rng(seed).normal(0, 0.005, img.shape)
    return np.clip(img + noise, 0, 1).astype(np.float32)


def test_a_moving_camera_is_estimated_from_its_pose_on_every_frame(world):
    """A slide and a pan, each frame seen from the camera's reference view
    through the model: every frame within a degree. Read as a fixed camera,
    the same frames come out degrees off (the test can fail)."""
    n = 24
    truth = [path(k, n) for k in range(n)]
    cameras = {k + 1: moving_view(k, n) for k in range(n)}
    frames = [draw_from(world, cameras[k + 1], truth[k], k) for k in range(n)]
    cameras[7] = None  # the solve has no pose on frame 7
    scene = world[0]
    numbers = list(range(1, n + 1))
    result = whole_clip.estimate(native, scene, cameras[12], numbers,
                                 lambda f: frames[f - 1], [0], frame_cameras=cameras,
                                 refine_model=True)
    # Asked to refine the model (the default), a moving camera's is left as
    # it is: its views are solved per frame.
    assert result.model_refinement is None
    assert result.model_refinement_note == "not refined: the camera moves"
    assert "refine_s" not in result.timing
    errors = []
    for k, r in enumerate(result.frames):
        if k + 1 == 7:
            assert "no pose" in (r.reason or ""), r
            assert not r.measured
            continue
        assert r.sun_in_world is not None, (k, r.reason)
        errors.append(error_deg(r.sun_in_world, truth[k]))
    assert np.mean(errors) < 0.5 and max(errors) < 1.0, errors
    # The overlay's shadow on the first and last frames, in their own
    # pixels: its foot is on a caster's footprint in the world.
    footprints = [((-0.08, -0.08), (0.08, 0.08)), ((2.0, 1.0), (3.2, 2.2)),
                  ((-4.0, 3.0), (1.0, 3.25))]
    for k in (0, n - 1):
        shadow = result.frames[k].tracked
        hit = scene.intersect_pixels(cameras[k + 1],
                                     np.array([shadow.shadow_start_px], np.float64))
        x, y = hit["point"][0][:2]
        off = min(math.hypot(max(lo[0] - x, 0, x - hi[0]), max(lo[1] - y, 0, y - hi[1]))
                  for lo, hi in footprints)
        assert off < 0.25, (k, x, y)
    still = whole_clip.estimate(native, scene, cameras[12], numbers,
                                lambda f: frames[f - 1], [0])
    off = [error_deg(r.sun_in_world, truth[k]) for k, r in enumerate(still.frames)
           if r.sun_in_world is not None]
    assert not off or max(off) > 3.0, off
    # The resampling's cost is timed (bench/moving_run.py prints it).
    assert result.timing["warp_s"] > 0 and "warp_s" not in still.timing


def test_a_camera_that_pans_away_from_the_casters_and_back(world):
    """The model's casters leave the view in the middle of the clip (a pan
    of 70 deg out and back): the reference view is taken where they are
    seen, the frames that see them are within a degree, and the frames
    that do not are not answered with confidence."""
    n = 24
    truth = [path(k, n) for k in range(n)]

    def view(k):
        pan = math.radians(-70.0 * math.sin(math.pi * k / (n - 1)))
        c, si = math.cos(pan), math.sin(pan)
        eye = np.array([-3.0, -9.0, 6.5])
        target = eye + np.array([3.0 * c - 10.0 * si, 3.0 * si + 10.0 * c, -6.5])
        return native.Camera.from_blender(lens_mm=28, sensor_width_mm=36, sensor_height_mm=24,
                                          width=W, height=H, matrix_world=look_at(eye, target))
    cameras = {k + 1: view(k) for k in range(n)}
    frames = [draw_from(world, cameras[k + 1], truth[k], k) for k in range(n)]
    scene = world[0]
    chosen = moving.reference_camera(scene, cameras, list(range(1, n + 1)), [0])
    assert chosen is not cameras[n // 2 + 1]
    result = whole_clip.estimate(native, scene, cameras[1], list(range(1, n + 1)),
                                 lambda f: frames[f - 1], [0], frame_cameras=cameras)
    near_ends = [k for k in range(n) if min(k, n - 1 - k) <= 2]
    for k in near_ends:
        r = result.frames[k]
        assert r.sun_in_world is not None and error_deg(r.sun_in_world, truth[k]) < 1.0, (k, r)
    for k, r in enumerate(result.frames):
        if r.sun_in_world is not None and r.confidence >= 0.5:
            assert error_deg(r.sun_in_world, truth[k]) < 5.0, (k, r)
    # Looking away, the camera cannot tell whether the Sun shines: unknown,
    # with the reason, never "no direct sunlight" (which keys the lamp off).
    away = result.frames[n // 2]
    assert away.sunlight == whole_clip.Sunlight.UNKNOWN, away
    assert away.reason == moving.SHADOWS_OUT_OF_VIEW and not away.shadows_in_view
    assert all(result.frames[k].shadows_in_view for k in near_ends)
    assert not any(r.sunlight == whole_clip.Sunlight.NO for r in result.frames)


@pytest.mark.parametrize("every", [1, 2])
def test_a_moving_camera_reads_key_frames_as_reference_when_all_have_poses(world, every):
    """Reference frames are the clip's key frames near those asked (one
    decode each): a moving camera's key frame is resampled with its own
    pose. When the run skips frames a key frame may have none, so they are
    read exactly (issue 26)."""
    n = 24
    truth = [path(k, n) for k in range(n)]
    cameras = {k + 1: moving_view(k, n) for k in range(n)}
    frames = [draw_from(world, cameras[k + 1], truth[k], k) for k in range(n)]
    numbers = list(range(1, n + 1, every))
    asked_near = []

    class Stream:
        frames_independent = False

        def __init__(self, fs, near):
            self.fs, self.near = fs, near
            asked_near.append(near)

        def __iter__(self):
            # Key frames every 5 frames: the one at or before each asked.
            for f in sorted({1 + 5 * ((f - 1) // 5) for f in self.fs} if self.near else self.fs):
                yield f, frames[f - 1]

    def source(fs, size):
        return (native.FrameList([(i, frames[f - 1]) for i, f in enumerate(fs)]),
                {f: i for i, f in enumerate(fs)})

    result = whole_clip.estimate(native, world[0], cameras[12], numbers, None, [0],
                                 stream=lambda fs, near, size: Stream(fs, near),
                                 source=source, frame_cameras={f: cameras[f] for f in numbers})
    assert asked_near == [every == 1]
    errors = [error_deg(r.sun_in_world, truth[r.frame - 1]) for r in result.frames]
    assert np.mean(errors) < 0.5 and max(errors) < 1.0, errors


def test_a_rough_model_is_refined_by_the_clip_and_a_true_one_left_alone(world):
    n = 20
    truth = [path(k, n) for k in range(n)]
    frames = [draw(world, truth[k], k) for k in range(n)]
    numbers = list(range(1, n + 1))

    def estimate(scene, refine):
        return whole_clip.estimate(native, scene, world[1], numbers, lambda f: frames[f - 1],
                                   [0], refine_model=refine)

    def mean_error(result):
        return float(np.mean([error_deg(r.sun_in_world, truth[k])
                              for k, r in enumerate(result.frames)]))

    kept = estimate(world[0], True)
    assert kept.model_refinement is not None
    assert kept.model_refinement.status != native.ModelRefineStatus.REFINED, \
        kept.model_refinement.message
    assert mean_error(kept) < 0.5

    rough = model({1: (0.3, -0.25, 1.15), 2: (0.25, 0.3, 0.88), 3: (-0.2, 0.2, 1.1)})
    as_made, refined = estimate(rough, False), estimate(rough, True)
    r = refined.model_refinement
    print("rough model: as made", mean_error(as_made), "refined", mean_error(refined), r.message)
    assert r.status == native.ModelRefineStatus.REFINED, r.message
    assert mean_error(refined) < 0.5 * mean_error(as_made)


def test_the_pace_clock_of_a_sun_that_stands_still_is_the_frame_numbers():
    """Frames that repeat one picture (a frozen stretch of video) give no
    pace to divide by: the clock stays the frame numbers, never infinite."""
    n = 200
    frozen = [sun(40.0, 150.0)] * 140 + [sun(40.0 - 0.5 * k, 150.0 + 0.8 * k) for k in range(60)]
    clock = untimed.pace_clock(frozen, list(range(1, n + 1)), [0] * n)
    assert clock is None or all(math.isfinite(c) for c in clock)


def test_a_stretch_whose_shadows_are_not_the_suns_is_not_a_cut(world):
    """Frames in the middle of an untimed clip whose shadows point the other
    way (an unmodelled tree's shade over the casters: fresh member trees9)
    made a segment of their own that the path jumped to and back from, 118-127
    deg off. The segments either side lie on one circle at one pace: the
    clip went on through those frames, and their Suns are not the Sun's."""
    n, lo, hi = 30, 12, 18
    truth = [path(k, n) for k in range(n)]

    def shown(k):
        z, a = angles.angles_from_sun_in_world(truth[k])
        return sun(z, a + 180.0) if lo <= k < hi else truth[k]
    frames = [draw(world, shown(k), k) for k in range(n)]
    result = run(world, frames, None, sun_circle.fit_trimmed)
    assert result.jumps == [] and len(result.segments) == 1, result.segments
    for k, r in enumerate(result.frames):
        if r.sun_in_world is not None:
            assert error_deg(r.sun_in_world, truth[k]) < (10.0 if lo <= k < hi else 1.0), k
    # Without the circle (no fit given) nothing tells the stretch from a cut.
    assert run(world, frames).jumps == [lo + 1, hi + 1]


def test_a_short_leg_after_a_long_one_does_not_make_the_leg_between_an_excursion(world):
    """A clip played forward, back and forward again, no times, its last leg
    short (the speed benchmark's ping-pong clip ends so): the long first leg
    alone made most of the inliers of a circle through the legs either side
    of the middle one, which was then taken for a stretch whose shadows are
    not the Sun's, and its 89 frames had no Sun. Each side must be on it."""
    n, short = 60, 16
    forward = [sun(50 - 0.3 * k, 120 + 0.4 * k) for k in range(n)]
    truth = forward + forward[::-1] + forward[:short]
    result = run(world, [draw(world, d, k) for k, d in enumerate(truth)], None,
                 sun_circle.fit_trimmed)
    assert len(result.segments) == 3, result.segments
    for k, r in enumerate(result.frames):
        assert r.sun_in_world is not None, (k, r.reason)
        assert error_deg(r.sun_in_world, truth[k]) < 1.0, k


def test_a_frame_whose_suns_shadows_miss_the_ground_in_view_is_not_said_to_be_unlit():
    """Suite member walls3: the buildings' shadows fall on the facades, and
    on 15 sunlit frames the tracker, asked at the path's Sun, found no
    shadow of the model on the ground in view. They were said to be
    without direct sunlight and the lamp was keyed off; the ground cannot
    show it either way, so they are UNKNOWN, and do not count as frames
    that could show the Sun. A frame whose ground could show shadows and
    shows none stays NO."""
    up = np.array([0.3, 0.4, 0.866])
    n = 6
    clip = object.__new__(whole_clip._WholeClip)
    clip.frames = list(range(1, n + 1))
    clip.n = n
    clip.starts = [0] * n
    clip.bounds = [0, n]
    clip.usable = [True] * n
    clip.out_of_view = [False] * n
    clip.clock_elevation = None
    clip.clock_trusted = None
    clip.no_shadow_in_view = {2, 3}
    tracked = types.SimpleNamespace(contrast=2.0)
    frames = [whole_clip.RawFrame(f, sun_in_world=up.copy(), confidence=0.9, measured=True,
                                  refined=True, tracked=tracked) for f in clip.frames]
    for k in (2, 3, 4):  # not confirmed; their evidence leads no one Sun
        frames[k] = whole_clip.RawFrame(k + 1, sun_in_world=up.copy(), confidence=0.1)
    clip.result = whole_clip.WholeClipResult(frames=frames, anchor=1)
    clip.path = types.SimpleNamespace(explained=[0.25, 0.26, 0.05, 0.05, 0.05, 0.25],
                                      margin=[25.0, 25.0, -12.0, 0.0, -25.0, 25.0])
    clip.decide_sunlight()
    Sunlight = whole_clip.Sunlight
    got = clip.result.frames
    assert [r.sunlight for r in got] == [Sunlight.YES, Sunlight.YES, Sunlight.UNKNOWN,
                                         Sunlight.UNKNOWN, Sunlight.NO, Sunlight.YES]
    assert [r.shadows_in_view for r in got] == [True, True, False, False, True, True]
    assert got[2].reason == whole_clip.NO_SHADOW_IN_VIEW
    assert got[2].sun_in_world is None and got[2].confidence == 0.0


def test_a_tracked_frame_says_what_became_of_it_as_a_status(world):
    """The tracker's outcome is a status the estimate reads (decide_sunlight
    reads no_shadow_in_view), not its reason's words."""
    scene, camera = world[0], world[1]
    tracker = native.ShadowTracker(scene, camera, [0])
    d = sun(40, 120)
    first = tracker.initialize(draw(world, d), d)
    assert first.ok and first.status == native.TrackedFrameStatus.tracked, first.reason
    black = tracker.track(np.zeros((H, W), np.float32))
    assert not black.ok and black.status == native.TrackedFrameStatus.unusable_frame


def test_a_sun_the_tracker_could_not_refine_says_so():
    """A measured frame whose Sun stays the path's grid cell (the tracker
    could not refine it) is in sunlight with a coarse Sun; its reason said
    "no shadow evidence on this frame", which it has (suite member walls3,
    frame 15, at confidence 0.94)."""
    clip = object.__new__(whole_clip._WholeClip)
    clip.n, clip.checked = 3, 0
    clip.tick = lambda x: None
    clip.directions = np.array([[0.0, 0.5, 0.866]])
    clip.refine_max_deg = 8.0
    clip.path = types.SimpleNamespace(direction=[0, 0, 0], path_margin=[25.0] * 3,
                                      measured=[True] * 3)
    clip.passed_track = lambda k, d, limit, beyond: None
    clip.restart = lambda run, first: False
    raw = whole_clip.RawFrame(2, reason="no shadow evidence on this frame or around it")
    assert not clip.refine(1, raw, (0, 1), 0, False, 1, 1)
    assert raw.sun_in_world is not None and raw.confidence > 0
    assert raw.reason == whole_clip.PATH_CELL_ONLY


def test_the_frames_that_pin_the_height_set_it_for_those_that_do_not():
    """A stretch whose shadows' tips run out of view (the tracker's Suns
    there fit any lower Sun, and came back 5-9 deg too low: height spread
    90) around three frames that pin it within 0.5 deg: the smoothing keeps
    the stretch's azimuths and takes its height from the pinned frames.
    Without the spreads it follows the low Suns."""
    n = 32
    frames = list(range(1, n + 1))
    times = frame_times(n)
    rng = np.random.default_rng(7)
    pinned = {6, 10, 14}

    def raws(spreads: bool):
        out = []
        for k, f in enumerate(frames):
            z, a = angles.angles_from_sun_in_world(sun_on_its_circle(k))
            low = 0.0 if k in pinned else rng.uniform(5.0, 9.0)
            out.append(RawSun(f, float(z) + low + rng.normal(0, 0.2),
                              (float(a) + rng.normal(0, 0.2)) % 360.0, confidence=0.9,
                              height_spread_deg=(0.5 if k in pinned else 90.0) if spreads
                              else None))
        return out

    opts = estimate_options.EstimateOptions()
    near = range(3, 18)
    for spreads in (True, False):
        zs, azs = finish._smooth_segments(frames, raws(spreads), [frames], "two_pass", opts,
                                          times)
        errors = [error_deg(angles.sun_in_world_from_angles(zs[k], azs[k]), sun_on_its_circle(k))
                  for k in near]
        if spreads:
            assert np.mean(errors) < 2.0, errors
        else:
            assert np.mean(errors) > 4.0, errors
