"""Marks the Marseille sundial's known points on its clip: the step a user
does by hand in the Clip Editor before "Solve Camera from Marked Points",
made repeatable.

  /usr/bin/python3 examples/real/measure_dial.py CLIP GUESSES.json OUT.marks.json \
      [--every 13] [--plot OUT.png]

A horizontal sundial is its own calibration target. Units: the nodus height
h = 1; origin at the gnomon's foot, +X east, +Y north, +Z up. For latitude
phi (43 deg 18' N, engraved on the dial) the dial's lines are
(../shared/real/marseille-sundial/README.md):
  equinox line  y = tan(phi), straight, east-west;
  hour line H   through the polar point (0, -1/tan(phi)) at angle theta from
                north, tan(theta) = sin(phi) tan(15 deg (H - 12));
  solstice arcs where the nodus's shadow falls at declination -+23.44 deg.
So the crossing of hour line H with the equinox line lies at
(tan(15 deg (H-12)) / cos(phi), tan(phi)), and its crossings with the arcs
are the nodus's shadow at that hour on the solstices.

The lines are located on the clip's "max image" (the 90th percentile of one
frame per capture), in which the moving shadows are gone. GUESSES holds rough
pixel positions (a few pixels off is fine) of the equinox line's two ends and
of each hour line's two ends, with the arcs each end lies on; that is the
user's part. Each line is then fitted to the darkest (or, for lines engraved
white, brightest) point across it, robustly, and each arc locally by a
quadratic; their crossings become the marked points, named as the add-on's
camera solve reads them ("eq10 -0.7933 0.9424").

Found here (see docs/accuracy.md, Real footage): the camera stands north of the dial
looking south (the picture is upright because the camera is rolled 180 deg),
not south of it; the solve says so without being told.
"""
import argparse
import json
import math
import os
import sys

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "addon"))

PHI = math.radians(43.3)
SOLSTICE = math.radians(23.44)


def shadow_tip(hour, decl):
    """Ground point (units of h) of the nodus's shadow at local apparent
    time `hour` (12 = noon) and solar declination `decl` (radians)."""
    H = math.radians(15.0 * (hour - 12))
    east = -math.cos(decl) * math.sin(H)
    north = math.cos(PHI) * math.sin(decl) - math.sin(PHI) * math.cos(decl) * math.cos(H)
    up = math.sin(PHI) * math.sin(decl) + math.cos(PHI) * math.cos(decl) * math.cos(H)
    return (-east / up, -north / up)


def equinox_crossing(hour):
    return (math.tan(math.radians(15.0 * (hour - 12))) / math.cos(PHI), math.tan(PHI))


def max_image(path, every):
    """90th percentile over one frame per capture (the middle of `every`
    repeats), in gray levels; undecodable frames are skipped."""
    import _native
    reader = _native.VideoReader(path)
    frames, i = [], 0
    while True:
        try:
            f = reader.read()
        except StopIteration:
            break
        if f is not None and i % every == every // 2:
            frames.append(f.astype(np.float32).mean(axis=2))
        i += 1
    if len(frames) < 3:
        raise SystemExit(f"measure_dial: only {len(frames)} frames decoded from {path}")
    return np.percentile(np.array(frames), 90, axis=0)


def bilinear(img, x, y):
    x0 = np.clip(np.floor(x).astype(int), 0, img.shape[1] - 2)
    y0 = np.clip(np.floor(y).astype(int), 0, img.shape[0] - 2)
    fx, fy = x - x0, y - y0
    return (img[y0, x0] * (1 - fx) * (1 - fy) + img[y0, x0 + 1] * fx * (1 - fy)
            + img[y0 + 1, x0] * (1 - fx) * fy + img[y0 + 1, x0 + 1] * fx * fy)


def darkest(profile, offsets):
    """Offset of the profile's minimum, refined by a parabola."""
    i = int(np.argmin(profile))
    if 0 < i < len(profile) - 1:
        a, b, c = profile[i - 1], profile[i], profile[i + 1]
        d = a - 2 * b + c
        if d > 0:
            return offsets[i] + 0.5 * (a - c) / d * (offsets[1] - offsets[0])
    return offsets[i]


def robust_keep(residuals, keep):
    sigma = max(1.4826 * float(np.median(np.abs(residuals[keep]))), 0.15)
    return np.abs(residuals) < 2.5 * sigma


def fit_line(img, p0, p1, half=2.5, trim=0.1):
    """Straight dark line near the segment p0-p1: (point, unit direction,
    RMS residual px, points kept). Numerals sitting on a line are outliers."""
    p0, p1 = np.asarray(p0, float), np.asarray(p1, float)
    length = float(np.linalg.norm(p1 - p0))
    d = (p1 - p0) / length
    n = np.array([-d[1], d[0]])
    offsets = np.arange(-half, half + 1e-9, 0.25)
    pts = []
    for t in np.linspace(trim * length, (1 - trim) * length, max(int(length), 5)):
        c = p0 + t * d
        q = c[None, :] + offsets[:, None] * n[None, :]
        pts.append(c + darkest(bilinear(img, q[:, 0], q[:, 1]), offsets) * n)
    pts = np.array(pts)
    keep = np.ones(len(pts), bool)
    for _ in range(5):
        centre = pts[keep].mean(axis=0)
        direction = np.linalg.svd(pts[keep] - centre)[2][0]
        r = (pts - centre) @ np.array([-direction[1], direction[0]])
        keep = robust_keep(r, keep)
    return centre, direction, float(np.sqrt(np.mean(r[keep] ** 2))), int(keep.sum())


def line_polarity(img, p0, p1):
    """Fit as a dark line and as a bright one; keep the tighter fit."""
    return min((fit_line(img, p0, p1), fit_line(-img, p0, p1)), key=lambda f: f[2])


def cross_lines(c1, d1, c2, d2):
    t = np.linalg.solve(np.array([d1, -d2]).T, c2 - c1)
    return c1 + t[0] * d1


def cross_arc(img, centre, direction, guess, span=14, gap=3.5, half=3.0):
    """Where the line meets the dark arc near `guess`: the arc is fitted
    locally as y = quadratic(x) from columns away from the crossing itself."""
    offsets = np.arange(-half, half + 1e-9, 0.25)
    xs = np.array([x for x in np.arange(guess[0] - span, guess[0] + span + 0.01)
                   if abs(x - guess[0]) >= gap])
    ys = np.array([guess[1] + darkest(bilinear(img, np.full_like(offsets, x), guess[1] + offsets),
                                      offsets) for x in xs])
    keep = np.ones(len(xs), bool)
    for _ in range(4):
        poly = np.polyfit(xs[keep], ys[keep], 2)
        r = ys - np.polyval(poly, xs)
        keep = robust_keep(r, keep)
    dpoly = np.polyder(poly)
    t = float((np.asarray(guess) - centre) @ direction)
    for _ in range(30):  # Newton on the line parameter
        x, y = centre + t * direction
        t -= (y - np.polyval(poly, x)) / (direction[1] - np.polyval(dpoly, x) * direction[0])
    return centre + t * direction, float(np.sqrt(np.mean(r[keep] ** 2)))


def measure(img, guesses):
    """Marked points [{name, pixel, ground}] and the fitted lines."""
    eq = line_polarity(img, *guesses["equinox"])
    marks, lines = [], {"equinox": eq}
    for key, (top, bottom, arcs) in guesses["hours"].items():
        hour = int(key)
        c, d, rms, n = line_polarity(img, top, bottom)
        lines[key] = (c, d, rms, n)
        found = [("eq", cross_lines(c, d, eq[0], eq[1]), equinox_crossing(hour))]
        for arc, end, decl in (("winter", top, -SOLSTICE), ("summer", bottom, SOLSTICE)):
            if arc in arcs:
                found.append((arc, cross_arc(img, c, d, end)[0], shadow_tip(hour, decl)))
        for what, pixel, ground in found:
            marks.append({"name": f"{what}{hour} {ground[0]:.4f} {ground[1]:.4f}",
                          "pixel": [round(float(pixel[0]), 3), round(float(pixel[1]), 3)],
                          "ground": [round(ground[0], 6), round(ground[1], 6), 0.0]})
    return marks, lines


def plot(img, marks, lines, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(8, 6), dpi=100)
    ax.imshow(img, cmap="gray", vmin=0, vmax=255)
    for c, d, *_ in lines.values():
        a, b = c - 400 * d, c + 400 * d
        ax.plot([a[0], b[0]], [a[1], b[1]], "-", color="lime", lw=0.6)
    for m in marks:
        ax.plot(*m["pixel"], "o", mfc="none", mec="red", ms=5)
    ax.set_xlim(0, img.shape[1] - 1)
    ax.set_ylim(img.shape[0] - 1, 0)
    ax.set_title("fitted dial lines and marked points")
    fig.tight_layout()
    fig.savefig(path)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("clip")
    p.add_argument("guesses")
    p.add_argument("out")
    p.add_argument("--every", type=int, default=1, help="frames per capture (13 for January)")
    p.add_argument("--plot", help="write the fitted lines over the max image here")
    args = p.parse_args(argv)
    with open(args.guesses) as f:
        guesses = json.load(f)
    img = max_image(args.clip, args.every)
    marks, lines = measure(img, guesses)
    for key, (_, _, rms, n) in lines.items():
        print(f"  line {key:>7}: {n} points, {rms:.2f} px RMS")
    with open(args.out, "w") as f:
        json.dump({"clip": os.path.basename(args.clip), "latitude_deg": math.degrees(PHI),
                   "units": "nodus height h = 1; x east, y north, origin at the gnomon's foot",
                   "marks": marks}, f, indent=1)
    if args.plot:
        plot(img, marks, lines, args.plot)
    print(f"measure_dial: {len(marks)} marks -> {args.out}")


if __name__ == "__main__":
    main()
