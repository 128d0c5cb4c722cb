"""Scores our ground-shadow detection against the rendered ground-truth masks.

  blender -b SCENE.blend --python bench/score_shadows.py -- TRACK.json TRUTH.json

Two detections per frame with a ground-truth mask, each scored by shadow
pixels (precision, recall) and shadow edges (within 1 px):
  "model": the model's cast shadows on the ground under that frame's
           estimated Sun (what the tracker matches to the image);
  "model+image": those plus the hard shadows the model does not explain,
           found in the frame against the clip's shadow-free background
           (estimate/notes.detect_unmodelled_shadows, as a run does on its anchor
           frame): casters that are in the footage but not in the model.
Prints one line "SHADOWS {json}".
"""
import json
import os
import sys

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "examples"))
import run_estimate  # noqa: E402

run_estimate.load_sunlapse()
from sunlapse.blender import gather  # noqa: E402
from sunlapse.estimate import frames as estimate_frames, notes  # noqa: E402
from sunlapse.estimate import options as estimate_options  # noqa: E402
from sunlapse.core import angles, trackfile  # noqa: E402


def edges(mask):
    e = np.zeros_like(mask)
    e[:, 1:] |= mask[:, 1:] != mask[:, :-1]
    e[1:, :] |= mask[1:, :] != mask[:-1, :]
    return e


def dilate(mask, r=1):
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def pr(pred, truth):
    tp = float((pred & truth).sum())
    return (tp / max(1.0, pred.sum()), tp / max(1.0, truth.sum()))


def scores(pred, gt, on_ground):
    p_pix, r_pix = pr(pred, gt)
    pe, ge = edges(pred) & on_ground, edges(gt)
    return {"pixel_precision": p_pix, "pixel_recall": r_pix,
            "edge_precision": float((pe & dilate(ge)).sum()) / max(1.0, pe.sum()),
            "edge_recall": float((ge & dilate(pe)).sum()) / max(1.0, ge.sum())}


def clip_frames(clip, frames):
    """uint8 BGR of the given scene frames (None where unreadable)."""
    out = {}
    reader = estimate_frames.open_clip(clip.filepath, 0)
    for f in frames:
        try:
            bgr = reader.read() if reader.seek(f - clip.frame_start) else None
        except StopIteration:
            bgr = None
        out[f] = bgr
    return out


def main(track_path, truth_path):
    ctx = bpy.context
    track, truth = trackfile.read_track(track_path), trackfile.read_track(truth_path)
    clip = gather.gather_clip(ctx)
    cam = gather.build_camera(gather.gather_camera(ctx, None, clip, gather.active_movieclip(ctx)))
    model = gather.gather_model(ctx)
    scene = gather.build_scene(model)
    ground_ids = model.ids_of(truth.extra.get("ground_objects", ["Ground"]))
    masks = sorted(truth.extra.get("shadow_masks", {}).items(), key=lambda kv: int(kv[0]))
    samples = notes.spread([f.frame for f in truth.frames])
    bgr = clip_frames(clip, sorted(set(samples) | {int(f) for f, _ in masks}))
    rows = []
    for frame, rel in masks:
        est = track.frame(int(frame))
        if est is None or not est.has_estimate:
            continue
        d = tuple(angles.sun_in_world_from_geographic(est.zenith_deg, est.azimuth_deg,
                                                      track.north_offset_deg))
        f = bgr.get(int(frame))
        found = None if f is None else notes.detect_unmodelled_shadows(
            scene, cam, ground_ids, f, d, [bgr[s] for s in samples],
            estimate_options.gamma("default"))
        if found is None:
            ground, shadow = notes.ground_and_model_shadow(scene, cam, ground_ids, d)
        else:
            ground, shadow = found.ground, found.model_shadow
        on_ground = ground > 0
        pred = shadow > 0
        img = bpy.data.images.load(os.path.join(os.path.dirname(truth_path), rel))
        gt = np.array(img.pixels[:]).reshape(img.size[1], img.size[0], -1)[::-1, :, 0] > 0.5
        bpy.data.images.remove(img)
        row = {"frame": int(frame), "model": scores(pred, gt, on_ground)}
        if found is not None:
            row["unmodelled_regions"] = len(found.regions)
            row["model+image"] = scores(pred | (found.mask > 0), gt, on_ground)
        rows.append(row)
    mean = {}
    for kind in ("model", "model+image"):
        have = [r[kind] for r in rows if kind in r]
        if have:
            mean[kind] = {key: float(np.mean([h[key] for h in have])) for key in have[0]}
    print("SHADOWS " + json.dumps({"frames": rows, "mean": mean}))


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:]
    main(*argv[:2])
