"""Shadows of casters the artist did not model: found on the anchor frame
against the clip's shadow-free background, recorded in the track file and
turned into a hint (the plaza's footage has a bin its scene.blend lacks)."""
import json
import os

import bpy
import numpy as np

from test_addon import run_estimate


def truth_mask(out, truth, frame):
    img = bpy.data.images.load(os.path.join(out, truth.extra["shadow_masks"][str(frame)]))
    try:
        w, h = img.size
        return np.array(img.pixels[:]).reshape(h, w, -1)[::-1, :, 0] > 0.5
    finally:
        bpy.data.images.remove(img)


def test_run_notes_the_shadow_of_a_caster_missing_from_the_model(long_plaza, tmp_path):
    out, truth = long_plaza
    assert truth.extra["footage_only_objects"] == ["Bin"]
    track_path = str(tmp_path / "t.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), track_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(track_path))
    noted = track["unmodelled_shadows"]
    assert noted["frame"] == track["initial"]["frame"]
    assert noted["regions"], "the bin's shadow was not found"
    gt = truth_mask(out, truth, noted["frame"])
    for r in noted["regions"]:  # each is a real shadow, not a dark patch
        x, y = (int(round(v)) for v in r["centroid_px"])
        assert gt[y, x], r
        assert 0 < r["darkening"] < 0.7 and r["edge_contrast"] > 2.5
    assert "not cast by the model" in track["model_hint"]
    assert any(line.startswith("sunlapse: note:") for line in proc.stdout.splitlines())


def test_a_clip_too_short_for_a_background_gets_no_note(tiny_plaza, tmp_path):
    # Three frames two minutes apart: the shadows stay put, so the median
    # keeps them and cannot tell them from paint; nothing is claimed.
    out, truth = tiny_plaza
    track_path = str(tmp_path / "t.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), track_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(track_path))
    assert "model_hint" not in track
    assert not track["unmodelled_shadows"].get("regions")
