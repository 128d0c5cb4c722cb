"""Scores our ground-shadow detection against the rendered ground-truth masks.

  blender -b SCENE.blend --python bench/score_shadows.py -- TRACK.json TRUTH.json

Our detection on a frame is the model's cast shadows on the ground under
that frame's estimated Sun (what the tracker matches to the image). For each
frame with a ground-truth mask it compares shadow pixels (precision, recall)
and shadow edges (within 1 px). Casters that are in the footage but not in
the model are in the truth and not in our detection: recall shows them.
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
from sunlapse import bridge  # noqa: E402
from sunlapse.core import evaluation, trackfile  # noqa: E402


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


def main(track_path, truth_path):
    ctx = bpy.context
    track, truth = trackfile.read_track(track_path), trackfile.read_track(truth_path)
    clip = bridge.gather_clip(ctx)
    cam = bridge.build_camera(bridge.gather_camera(ctx, None, clip, bridge.active_movieclip(ctx)))
    model = bridge.gather_model(ctx)
    scene = bridge.build_scene(model)
    ground = model.ids_of(truth.extra.get("ground_objects", ["Ground"]))
    w, h = cam.width, cam.height
    ys, xs = np.mgrid[0:h, 0:w]
    pixels = np.ascontiguousarray(np.column_stack([xs.ravel(), ys.ravel()]).astype(np.float64))
    hits = scene.intersect_pixels(cam, pixels)
    on_ground = np.isin(hits["object_id"], ground)
    origins = np.ascontiguousarray((hits["point"] + 2e-3 * hits["normal"]).astype(np.float32))
    rows = []
    for frame, rel in sorted(truth.extra.get("shadow_masks", {}).items(), key=lambda kv: int(kv[0])):
        est = track.frame(int(frame))
        if est is None or not est.has_estimate:
            continue
        d = np.array(evaluation.direction(est.zenith_deg, est.azimuth_deg + track.north_offset_deg),
                     dtype=np.float32)
        occ = scene.occluded(origins, np.ascontiguousarray(np.tile(d, (len(origins), 1))))
        pred = (occ & on_ground).reshape(h, w)
        img = bpy.data.images.load(os.path.join(os.path.dirname(truth_path), rel))
        gt = np.array(img.pixels[:]).reshape(img.size[1], img.size[0], -1)[::-1, :, 0] > 0.5
        bpy.data.images.remove(img)
        p_pix, r_pix = pr(pred, gt)
        pe, ge = edges(pred) & on_ground.reshape(h, w), edges(gt)
        p_edge = float((pe & dilate(ge)).sum()) / max(1.0, pe.sum())
        r_edge = float((ge & dilate(pe)).sum()) / max(1.0, ge.sum())
        rows.append({"frame": int(frame), "pixel_precision": p_pix, "pixel_recall": r_pix,
                     "edge_precision": p_edge, "edge_recall": r_edge})
    mean = {k: float(np.mean([r[k] for r in rows])) for k in rows[0]} if rows else {}
    mean.pop("frame", None)
    print("SHADOWS " + json.dumps({"frames": rows, "mean": mean}))


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:]
    main(*argv[:2])
