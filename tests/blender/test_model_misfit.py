"""A hand-made model the footage does not fit (issue 25, rough models): the
run measures how far its shadows miss the footage's, caps the clip's
confidence and says what to check. The plaza's footage against its own
model, then against the same model with its casters moved and resized as a
hand-made one might be."""
import json
import os

import bpy

from conftest import sunlapse
from test_addon import run_estimate

from sunlapse.estimate import calibration  # noqa: E402 (conftest loads the add-on)


def roughened(blend, out):
    """The scene with every caster of its model 0.5 m off along x and 15%
    taller, saved as `out` (the original is left as it is)."""
    if not hasattr(bpy.types.Scene, "sunlapse"):
        sunlapse.register()
    bpy.ops.wm.open_mainfile(filepath=blend)
    scene = bpy.context.scene
    settings = scene.sunlapse
    ground = settings.ground_object
    model = settings.model_collection
    objects = model.all_objects if model is not None else scene.objects
    moved = []
    for obj in objects:
        if obj.type != "MESH" or obj == ground or obj.dimensions.z < 0.05:
            continue  # the ground and flat things cast nothing
        obj.location.x += 0.5
        obj.scale.z *= 1.15
        moved.append(obj.name)
    assert moved, "no caster in the plaza's model"
    bpy.ops.wm.save_as_mainfile(filepath=out, copy=True)
    return moved


def test_a_model_whose_casters_are_off_is_told_and_its_confidence_capped(long_plaza, tmp_path):
    out, _ = long_plaza
    blend = os.path.join(out, "scene.blend")
    true_path, rough_path = str(tmp_path / "true.sun.json"), str(tmp_path / "rough.sun.json")
    proc = run_estimate(blend, true_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    true_track = json.load(open(true_path))
    rough_blend = str(tmp_path / "rough.blend")
    roughened(blend, rough_blend)
    proc = run_estimate(rough_blend, rough_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rough_track = json.load(open(rough_path))
    print("model misfit: true", true_track.get("model_misfit"),
          "rough", rough_track.get("model_misfit"))

    limit = calibration.MODEL_MISFIT_MAX
    assert true_track["model_misfit"] < limit
    assert not any(p["stage"] == "model" and "miss the footage" in p["message"]
                   for p in true_track["problems"])
    # Not held by the model rule (its 5 frames are too few for the Sun's
    # path to check them, which holds them just under 0.5 too: the cap's
    # value cannot tell the two apart, the run's account does).

    def held_by_model(track):
        return any(p["stage"] == "confidence" and "the model" in p["message"]
                   for p in track["problems"])
    assert not held_by_model(true_track), true_track["problems"]

    assert rough_track["model_misfit"] >= limit
    assert all(f.get("shadow_misfit") is not None for f in rough_track["frames"]
               if f.get("raw_zenith_deg") is not None)
    assert max(f["confidence"] for f in rough_track["frames"]) <= \
        calibration.MODEL_DOUBTED_PROBABILITY + 1e-9
    assert held_by_model(rough_track), rough_track["problems"]
    assert any(line.startswith("sunlapse: note: the model's shadows miss the footage's")
               for line in proc.stdout.splitlines()), proc.stdout
