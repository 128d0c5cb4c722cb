#!/usr/bin/env python3
"""Times native.solve_sun_path on a long synthetic clip, as the whole-clip
estimate calls it: untimed, untimed with a circle prior, with times, and
with times and a night halfway (one step beyond the grid's neighbour cache).

  /usr/bin/python3 bench/path_solve.py [--frames 1000] [--runs 3] [--out RESULTS.pkl]

The clip is tests/python/test_whole_clip.py's world (a pole, a box and a
wall on a textured ground, drawn with the native ray caster, 320x200), its
40 drawn frames played forward and back to --frames; the sky table has the
default 3,000 directions. Prints the best of --runs per case. --out keeps
each case's result (directions, jumps, margins, measured, cost) so that two
trees' solves can be compared field by field (--compare A.pkl B.pkl).
Figures only: nothing is judged.
"""
import argparse
import os
import pickle
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "tests", "python"))
sys.path.insert(0, os.path.join(ROOT, "addon"))


def compare(a_path, b_path):
    with open(a_path, "rb") as fa, open(b_path, "rb") as fb:
        a, b = pickle.load(fa), pickle.load(fb)
    for case in a:
        differ = [f for f in a[case] if a[case][f] != b.get(case, {}).get(f)]
        print(f"{case}: " + ("identical" if not differ else "differ in " + ", ".join(differ)))
    return 0


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--frames", type=int, default=1000, help="frames of the clip (default 1000)")
    p.add_argument("--runs", type=int, default=3, help="runs per case, best kept (default 3)")
    p.add_argument("--out", help="write each case's result here (pickle)")
    p.add_argument("--compare", nargs=2, metavar=("A", "B"),
                   help="compare two --out files instead of timing")
    args = p.parse_args(argv)
    if args.compare:
        return compare(*args.compare)
    if args.frames < 2 or args.runs < 1:
        p.error("--frames must be >= 2 and --runs >= 1")
    import test_whole_clip as clip   # the tests' world and drawing (needs python3-pytest)
    native = clip.native
    world = clip.world.__wrapped__()
    drawn = 40
    truth = [clip.sun(50 - 0.3 * k, 120 + 0.4 * k) for k in range(drawn)]
    frames = [clip.draw(world, d, k) for k, d in enumerate(truth)]
    sky = native.SkyEvidence(world[0], world[1], native.SkyEvidenceOptions())
    sky.set_reference(frames[::5])
    period = 2 * drawn - 2
    order = [k % period if k % period < drawn else period - k % period
             for k in range(args.frames)]
    for k in order:
        sky.add_frame(frames[k])
    options, starts = native.SunPathOptions(), [0] * args.frames
    cases = {"untimed": ([], starts, options),
             "untimed, circle prior": ([], starts, options, [tuple(truth[k]) for k in order]),
             "timed, 10 min a frame": ([600.0 * k for k in range(args.frames)], starts, options),
             "timed, a night halfway": ([600.0 * k + (43200.0 if 2 * k >= args.frames else 0.0)
                                         for k in range(args.frames)], starts, options)}
    out = {}
    for name, call in cases.items():
        best = float("inf")
        for _ in range(args.runs):
            t0 = time.perf_counter()
            r = native.solve_sun_path(sky, *call)
            best = min(best, time.perf_counter() - t0)
        out[name] = {"direction": list(r.direction), "jump_before": list(r.jump_before),
                     "margin": list(r.margin), "path_margin": list(r.path_margin),
                     "measured": list(r.measured), "cost": r.cost}
        print(f"{name}: {best:.3f} s (best of {args.runs}, {args.frames} frames, "
              f"{len(sky.directions)} directions)")
    if args.out:
        with open(args.out, "wb") as fh:
            pickle.dump(out, fh)
    return 0


if __name__ == "__main__":
    sys.exit(main())
