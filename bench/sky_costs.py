"""The sky's per-frame costs against a rendered scene's true Sun (a debug
view of the whole-clip estimate's evidence, docs/accuracy.md "Why walls1's
path is wrong in height"):

  blender -b SCENE/scene.blend --python bench/sky_costs.py -- SCENE/truth.sun.json [--out COSTS.npz]

Runs the estimate as examples/run_estimate.py does (its track is not
written) and, before the controller lets the sky's table go, prints per
frame: how many of the grid's directions score under the cost's cap, the
best direction's zenith against the true one, its azimuth's and its
direction's distance from the true Sun's, and the cost of the true Sun's
cell (0: as good as the best; 25.5: the cap). --out keeps every frame's
costs and the grid's directions (numpy .npz: costs, directions).
--north-scan also sums, for each north offset in 2 deg steps, the costs of
the truth's Suns (those at least 4 deg up) turned into the scene by it: where
the place and times are known, whether the evidence could tell north.
"""
import argparse
import json
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "examples"))
import run_estimate  # noqa: E402

CAP = 25.5  # SkyEvidence keeps costs x10 in a byte


def main() -> int:
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    ap = argparse.ArgumentParser(prog="sky_costs.py", description=__doc__.split("\n\n")[0])
    ap.add_argument("truth", help="the scene's truth.sun.json (bench/suite.py's cache)")
    ap.add_argument("--out", help="write the costs and directions to this .npz")
    ap.add_argument("--north-scan", action="store_true",
                    help="sum the truth's costs for each north offset (2 deg steps)")
    args = ap.parse_args(argv)
    with open(args.truth) as f:
        truth = json.load(f)
    run_estimate.load_sunlapse()
    from sunlapse.core import angles
    from sunlapse.estimate import whole_clip
    from sunlapse import cli

    seen = {}
    hooked = getattr(whole_clip._WholeClip, "release_sky", None)
    if hooked is None:
        print("sky_costs: this tree's controller has no release_sky to look in", file=sys.stderr)
        return 2

    def release(self):
        sky = self.sky
        seen["costs"] = np.array([sky.cost(k) for k in range(sky.num_frames)])
        seen["directions"] = np.asarray(sky.directions)
        seen["frames"] = list(self.frames)
        return hooked(self)

    whole_clip._WholeClip.release_sky = release
    with open(os.devnull, "w") as quiet:
        old = sys.stdout
        sys.stdout = quiet
        try:
            cli.main(["--out", os.devnull])
        finally:
            sys.stdout = old
    if "costs" not in seen:
        print("sky_costs: the estimate ended before the sky's table was built", file=sys.stderr)
        return 1
    costs, dirs = seen["costs"], seen["directions"]
    zen = np.degrees(np.arccos(np.clip(dirs[:, 2], -1, 1)))
    print("frame  under-cap  best-zenith  true-zenith  best-azimuth-off  best-off  true-cell")
    north = truth["north_offset_deg"]
    for k, frame in enumerate(seen["frames"]):
        if k >= len(truth["frames"]) or k >= len(costs):
            break
        ft = truth["frames"][k]
        true = np.asarray(angles.sun_in_world_from_geographic(ft["zenith_deg"], ft["azimuth_deg"],
                                                              north))
        c = costs[k]
        best = int(np.argmin(c))
        off = np.degrees(np.arccos(np.clip(dirs @ true, -1, 1)))
        az_off = angles.azimuth_difference_deg(angles.angles_from_sun_in_world(dirs[best])[1],
                                               angles.angles_from_sun_in_world(true)[1])
        print(f"{frame:5d}  {int(np.sum(c < CAP)):9d}  {zen[best]:11.1f}  "
              f"{ft['zenith_deg']:11.1f}  {az_off:16.2f}  {off[best]:8.1f}  "
              f"{c[int(np.argmin(off))]:9.1f}")
    if args.north_scan:
        up = [(k, ft) for k, ft in enumerate(truth["frames"][:len(costs)])
              if 90.0 - ft["zenith_deg"] >= 4.0]

        def summed(offset):
            return sum(float(costs[k][int(np.argmax(dirs @ np.asarray(
                angles.sun_in_world_from_geographic(ft["zenith_deg"], ft["azimuth_deg"],
                                                    offset))))]) for k, ft in up)
        scan = sorted((summed(float(o)), o) for o in range(-180, 180, 2))
        given = summed(north)
        print(f"north scan over {len(up)} frames with the Sun >= 4 deg up: the truth's north "
              f"{north:+.1f} sums {given:.1f}; best {scan[0][0]:.1f} at {scan[0][1]:+d}, "
              f"worst {scan[-1][0]:.1f}; {sum(c < given for c, _ in scan)} of {len(scan)} "
              f"offsets sum less")
    if args.out:
        np.savez(args.out, costs=costs, directions=dirs)
    return 0


sys.exit(main())
