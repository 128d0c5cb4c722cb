"""Scores track files against truth files and prints the Table 5.1 layout.

  python3 bench/evaluate.py NAME=TRACK.json:TRUTH.json [...] [--plots DIR]

A missing track file is reported as such, never scored.
"""
import argparse
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "addon"))

from core import evaluation, trackfile  # noqa: E402


def score(name, track_path, truth_path):
    truth = trackfile.read_track(truth_path)
    if not os.path.exists(track_path):
        return evaluation.evaluate(name, None, truth, message="no track was produced")
    return evaluation.evaluate(name, trackfile.read_track(track_path), truth)


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("pairs", nargs="+", metavar="NAME=TRACK:TRUTH")
    p.add_argument("--plots", help="folder for one PNG plot per scene")
    args = p.parse_args(argv)
    reports = []
    for pair in args.pairs:
        name, _, paths = pair.partition("=")
        track, _, truth = paths.partition(":")
        if not truth:
            p.error(f"expected NAME=TRACK:TRUTH, got {pair}")
        reports.append(score(name, track, truth))
    print(evaluation.format_table(reports))
    if args.plots:
        os.makedirs(args.plots, exist_ok=True)
        for r in reports:
            out = evaluation.plot(r, os.path.join(args.plots, f"{r.name}.png"))
            if out:
                print(f"plot: {out}")
    return reports


if __name__ == "__main__":
    main()
