"""Fits the map from the whole-clip estimate's support to a probability
(addon/estimate/calibration.py) on the randomised suite, and says how well
it holds on scenes it was not fitted on.

  python3 bench/suite.py --uncalibrated-confidence [members ...] --out RAW.json
  python3 bench/calibrate.py --suite RAW.json [--suite RAW2.json ...]
                             [--min-block N] [--folds K] [--write]

Every scored frame of every member (not the "/true" twins) is a pair (error
against the truth, support); the map is the share of frames within 2 deg as
a non-decreasing function of support (pool adjacent violators, blocks of at
least --min-block frames, default 40), as knots to interpolate between,
fitted on the frames with some support (support 0 stays 0) of the clips it
applies to. Frames whose support is below calibration.DOUBTED_SUPPORT are
then held below 0.5, and so is every frame of a clip whose Sun was measured
on too few of the frames that could show it, or whose model's shadows do not
fit the footage or the clip refined it (calibration.clip_doubted; the
suite's measured_share, model_misfit and model_refined, from the track's
sun_measured_share, model_misfit and model_refinement).

Printed: the reliability table and expected calibration error (ECE, 10
bins) of the support as it is; the same of the map applied to scenes it was
not fitted on (K folds of whole scenes, every K-th scene held out in turn,
default 2): the figure to trust; the same fitted and judged on all (which
flatters it); the frames more than 5 deg off at confidence >= 0.5 before and
after; and the knots. --write puts the knots fitted on all the scenes into
addon/estimate/calibration.py. Exit 0 whatever the figures (2: bad flags or
files).
"""
import argparse
import json
import os
import re
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "addon"))

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from core import evaluation  # noqa: E402
from estimate import calibration  # noqa: E402
from suite import (CONFIDENT_WITHIN_DEG as WITHIN_DEG,  # noqa: E402
                   CONFIDENT_WRONG_DEG as WRONG_DEG)
TABLE = os.path.join(ROOT, "addon", "estimate", "calibration.py")
TABLE_NAME = "SUPPORT_TO_PROBABILITY"


def fail(message):
    print(f"calibrate: error: {message}", file=sys.stderr)
    sys.exit(2)


def scenes_from(paths):
    """{scene: [(error deg, support)]} over the suite runs' JSON files, and
    {scene: whether calibration.clip_doubted holds it below 0.5}."""
    scenes, doubted, model = {}, {}, {}
    for path in paths:
        try:
            with open(path) as fh:
                figures = json.load(fh)
        except (OSError, ValueError) as e:
            fail(f"cannot read the suite's figures {path}: {e}")
        for smoothing, block in figures.get("smoothings", {}).items():
            for row in block.get("scenes", []):
                if row["scene"].endswith("/true"):
                    continue
                frames = [(p["error_deg"], p["confidence"]) for p in row.get("per_frame", [])
                          if p["error_deg"] is not None and p["confidence"] is not None]
                key = f"{smoothing}:{row['scene']}"
                scenes.setdefault(key, []).extend(frames)
                share = row.get("measured_share")
                refined = bool(row.get("model_refined"))
                doubted[key] = share is not None and calibration.clip_doubted(
                    share, row.get("model_misfit"), refined)
                model[key] = calibration.model_doubted(row.get("model_misfit"), refined)
    if not scenes:
        fail("no scored frames in " + ", ".join(paths))
    return scenes, doubted, model


def fit(frames, min_block):
    """Knots from frames with support: a frame without any keeps 0 (the
    map's rule), and one fitted at 0 would lift every frame of little."""
    return evaluation.isotonic_fit([f for f in frames if f[1] > 0], WITHIN_DEG, min_block)


def mapped(frames, knots, doubted=False, model=False, model_cap=None):
    """The frames' confidences as calibration.probability makes them with
    these knots and (when given) this model-doubted clip's cap."""
    cap = calibration.MODEL_DOUBTED_PROBABILITY if model_cap is None else model_cap
    return [(e, calibration.probability(c, knots, doubted, model_doubted_clip=model,
                                        model_cap=cap)) for e, c in frames]


def model_cap(frames):
    """The share of frames with support within WITHIN_DEG in clips held by
    the model rule, below DOUBTED_MAX_PROBABILITY (None: no such frames)."""
    scored = [e for e, c in frames if c > 0]
    if not scored:
        return None
    within = sum(e <= WITHIN_DEG for e in scored) / len(scored)
    return min(within, calibration.DOUBTED_MAX_PROBABILITY)


def wrong_at_half(frames):
    return sum(e > WRONG_DEG and c >= 0.5 for e, c in frames)


def print_table(title, frames):
    bins, ece = evaluation.reliability(frames, WITHIN_DEG)
    print(f"\n{title}: {len(frames)} frames, ECE {ece:.3f} (target <= 0.05), "
          f"{wrong_at_half(frames)} frame(s) more than {WRONG_DEG:g} deg off at >= 0.5")
    print(f"  {'confidence':<12}{'frames':>7}{'mean':>7}{'within':>8}")
    for b in bins:
        print(f"  {b.lo:.1f}-{b.hi:.1f}    {b.frames:>7}{b.mean_confidence:>7.2f}"
              f"{b.share_within:>8.2f}")
    return ece


def held_out(scenes, doubted, model, folds, min_block):
    """Every scene's frames mapped by knots (and a model cap) fitted without
    its fold (the knots on the clips the map applies to)."""
    names = sorted(scenes)
    out = []
    for k in range(folds):
        knots = fit([f for i, n in enumerate(names) if i % folds != k and not doubted[n]
                     for f in scenes[n]], min_block)
        cap = model_cap([f for i, n in enumerate(names) if i % folds != k and model[n]
                         for f in scenes[n]])
        for i, n in enumerate(names):
            if i % folds == k:
                out += mapped(scenes[n], knots, doubted[n], model[n], cap)
    return out


def write_knots(knots, cap):
    text = open(TABLE).read()
    body = "".join(f"    ({c:.4f}, {p:.4f}),\n" for c, p in knots)
    new, n = re.subn(rf"{TABLE_NAME}: Tuple\[Tuple\[float, float\], \.\.\.\] = \((?:.|\n)*?\n?\)\n",
                     f"{TABLE_NAME}: Tuple[Tuple[float, float], ...] = (\n{body})\n", text,
                     count=1)
    if n != 1:
        fail(f"no {TABLE_NAME} table in {TABLE}")
    if cap is not None:
        new, n = re.subn(r"\nMODEL_DOUBTED_PROBABILITY = [0-9.]+\n",
                         f"\nMODEL_DOUBTED_PROBABILITY = {cap:.4f}\n", new, count=1)
        if n != 1:
            fail(f"no MODEL_DOUBTED_PROBABILITY in {TABLE}")
    with open(TABLE, "w") as fh:
        fh.write(new)
    print(f"\nwrote {len(knots)} knots"
          f"{'' if cap is None else f' and MODEL_DOUBTED_PROBABILITY {cap:.4f}'} into "
          f"{os.path.relpath(TABLE, ROOT)}")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--suite", action="append", required=True, metavar="FIGURES.json",
                   help="bench/suite.py --uncalibrated-confidence --out's file (repeatable)")
    p.add_argument("--min-block", type=int, default=40,
                   help="frames a knot stands for at least (default 40)")
    p.add_argument("--folds", type=int, default=2,
                   help="folds of whole scenes for the held-out figure (default 2)")
    p.add_argument("--write", action="store_true",
                   help="write the knots fitted on every scene into calibration.py")
    args = p.parse_args(argv)
    if args.min_block < 1:
        p.error(f"--min-block must be at least 1, got {args.min_block}")
    if args.folds < 2:
        p.error(f"--folds must be at least 2, got {args.folds}")
    scenes, doubted, model = scenes_from(args.suite)
    every = [f for n in sorted(scenes) for f in scenes[n]]
    if len(scenes) < args.folds:
        p.error(f"--folds {args.folds} needs as many scenes; the files hold {len(scenes)}")
    held = sorted(n for n in scenes if doubted[n])
    print(f"{len(scenes)} scene runs, {len(every)} scored frames; clips held below 0.5 "
          f"(Sun measured on under {calibration.MEASURED_SHARE_MIN:.0%} of the frames that "
          f"could show it, or a model misfit of {calibration.MODEL_MISFIT_MAX:g} or more): "
          f"{', '.join(held) or 'none'}")
    print_table("support as the estimator computes it", every)
    print_table(f"calibrated, judged on scenes held out ({args.folds} folds)",
                held_out(scenes, doubted, model, args.folds, args.min_block))
    knots = fit([f for n in sorted(scenes) if not doubted[n] for f in scenes[n]],
                args.min_block)
    cap = model_cap([f for n in sorted(scenes) if model[n] for f in scenes[n]])
    print_table("calibrated, fitted and judged on every scene",
                [f for n in sorted(scenes)
                 for f in mapped(scenes[n], knots, doubted[n], model[n], cap)])
    print("\nknots (support, probability within 2 deg):")
    for c, prob in knots:
        print(f"  ({c:.4f}, {prob:.4f}),")
    print("model-doubted clips' cap (their frames' share within 2 deg): "
          + ("none" if cap is None else f"{cap:.4f}"))
    if args.write:
        write_knots(knots, cap)
    return 0


if __name__ == "__main__":
    sys.exit(main())
