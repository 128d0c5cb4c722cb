"""A hand-made model refined by the clip (issue 25 item 5, --refine-model):
the run reports what it did in the track and a note, never changes the
file it opened, and applies the corrections to the .blend only when asked
(Apply Model Corrections, --apply-model-corrections): exactly the stored
transforms, once, and not to objects something else drives."""
import hashlib
import json
import math
import os
import shutil

import bpy
import numpy as np
from mathutils import Matrix

from test_addon import error_lines, run_estimate

from sunlapse.blender import model_fix, store  # noqa: E402 (conftest loads the add-on)
from sunlapse.core import trackfile  # noqa: E402


def digest(path):
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def test_a_refined_run_reports_and_leaves_the_opened_file_alone(long_plaza, tmp_path):
    out, _ = long_plaza
    blend = str(tmp_path / "scene.blend")
    for name in ("scene.blend", "clip.mp4"):  # the clip is beside the .blend
        shutil.copy(os.path.join(out, name), str(tmp_path / name))
    before = digest(blend)
    track_path = str(tmp_path / "refined.sun.json")
    # Refined by default: the run's account is in the track either way.
    proc = run_estimate(blend, track_path, "--apply-model-corrections")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(track_path))
    refinement = track["model_refinement"]
    assert refinement["status"] in ("refined", "unchanged", "no_edges")
    assert refinement["objects"], refinement["message"]
    for o in refinement["objects"]:
        assert 0 <= o["object_id"] < len(track["method"]["options"]["model_objects"])
        assert len(o["transform"]) == 4 and len(o["scale"]) == 3
    # A hint and the confidence held below 0.5 only where the corrections
    # were used; a note says what --apply-model-corrections did either way.
    used = refinement["used"]
    assert used == any(p["stage"] == "model_refinement" for p in track["problems"])
    assert not used or all(f["confidence"] < 0.5 for f in track["frames"])
    assert any(line.startswith("sunlapse: note:") and "model" in line and "clip" in line
               for line in proc.stdout.splitlines()), proc.stdout
    assert digest(blend) == before  # nothing saved without --save
    # Asked not to, the run leaves the model alone and says nothing of it.
    proc = run_estimate(blend, track_path, "--no-refine-model")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "model_refinement" not in json.load(open(track_path))


def test_applying_corrections_needs_the_refinement(long_plaza, tmp_path):
    out, _ = long_plaza
    for off in (["--no-refine-model"], ["--method", "thesis"]):
        proc = run_estimate(os.path.join(out, "scene.blend"), str(tmp_path / "t.sun.json"),
                            "--apply-model-corrections", *off)
        assert proc.returncode == 2
        assert any("--apply-model-corrections needs the model refined" in line
                   for line in error_lines(proc)), proc.stderr
    proc = run_estimate(os.path.join(out, "scene.blend"), str(tmp_path / "t.sun.json"),
                        "--refine-model", "--no-refine-model")
    assert proc.returncode == 2, proc.stderr
    # The thesis baseline runs on the model as it is: asking to refine it
    # is a usage error, not a flag silently ignored.
    proc = run_estimate(os.path.join(out, "scene.blend"), str(tmp_path / "t.sun.json"),
                        "--refine-model", "--method", "thesis")
    assert proc.returncode == 2
    assert any("--refine-model" in line and "thesis" in line
               for line in error_lines(proc)), proc.stderr
    assert not os.path.exists(str(tmp_path / "t.sun.json"))


def _scene_with_a_box_and_a_camera(scene):
    mesh = bpy.data.meshes.new("box")
    mesh.from_pydata([(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)], [], [(0, 1, 2, 3)])
    box = bpy.data.objects.new("Box", mesh)
    post = bpy.data.objects.new("Post", mesh)
    driven = bpy.data.objects.new("Driven", mesh)
    for o in (box, post, driven):
        scene.collection.objects.link(o)
    box.location = (2.0, 1.0, 0.0)
    post.location = (-1.0, 3.0, 0.0)
    driven.keyframe_insert("location", frame=1)
    cam = bpy.data.objects.new("Cam", bpy.data.cameras.new("Cam"))
    scene.collection.objects.link(cam)
    cam.location = (0.0, -10.0, 5.0)
    cam.rotation_euler = (math.radians(70), 0.0, 0.0)
    scene.camera = cam
    bpy.context.view_layer.update()
    return box, post, driven, cam


def _track_with(corrections, names, camera="Cam"):
    track = trackfile.Track(clip="clip.mp4",
                            method={"options": {"model_objects": names, "camera": camera}})
    track.extra.update(corrections)
    return track


def test_corrections_are_applied_exactly_once_and_not_to_driven_objects(empty_scene):
    box, post, driven, cam = _scene_with_a_box_and_a_camera(empty_scene)
    turn = Matrix.Rotation(math.radians(3.0), 4, "Z")
    move = Matrix.Translation((0.2, -0.1, 0.0))
    transform = np.array(move @ turn)
    cam_turn = np.array(Matrix.Rotation(math.radians(0.3), 3, "X"))
    box_before, post_before = np.array(box.matrix_world), np.array(post.matrix_world)
    cam_before, lens_before = np.array(cam.matrix_world), cam.data.lens
    track = _track_with({
        "model_refinement": {
            "used": True, "status": "refined", "message": "",
            "camera": {"turn_deg": 0.3, "focal_factor": 1.02,
                       "turn_in_world": cam_turn.tolist()},
            "objects": [
                {"object_id": 1, "refined": True, "transform": transform.tolist(),
                 "move_in_world_m": [0.2, -0.1], "turn_deg": 3.0, "scale": [1, 1, 1]},
                # Not refined: stays where it is.
                {"object_id": 2, "refined": False, "transform": transform.tolist(),
                 "move_in_world_m": [0, 0], "turn_deg": 0, "scale": [1, 1, 1]},
                {"object_id": 3, "refined": True, "transform": transform.tolist(),
                 "move_in_world_m": [0.2, -0.1], "turn_deg": 3.0, "scale": [1, 1, 1]},
                {"object_id": 4, "refined": True, "transform": transform.tolist(),
                 "move_in_world_m": [0.2, -0.1], "turn_deg": 3.0, "scale": [1, 1, 1]}]}},
        ["Ground", "Box", "Post", "Driven", "Gone/Part"])
    store.store_track(track)
    said, skipped = model_fix.apply_corrections(bpy.context, store.load_track())
    bpy.context.view_layer.update()

    assert np.allclose(np.array(box.matrix_world), transform @ box_before, atol=1e-5)
    assert np.allclose(np.array(post.matrix_world), post_before)
    assert any("'Driven'" in s for s in skipped) and any("'Gone/Part'" in s for s in skipped)
    # The camera turned about its own centre, its lens scaled.
    after = np.array(cam.matrix_world)
    assert np.allclose(after[:3, 3], cam_before[:3, 3], atol=1e-6)
    assert np.allclose(after[:3, :3], cam_turn @ cam_before[:3, :3], atol=1e-6)
    assert math.isclose(cam.data.lens, lens_before * 1.02, rel_tol=1e-6)
    assert "1 object(s)" in said and "camera" in said
    # Stored as applied: a second time is refused, nothing moves again.
    assert store.load_track().extra["model_refinement"]["applied"]
    try:
        model_fix.apply_corrections(bpy.context, store.load_track())
    except ValueError as e:
        assert "applied already" in str(e)
    else:
        raise AssertionError("a second apply was not refused")
    assert np.allclose(np.array(box.matrix_world), transform @ box_before, atol=1e-5)


def test_a_track_without_used_corrections_applies_nothing(empty_scene):
    box, _, _, _ = _scene_with_a_box_and_a_camera(empty_scene)
    before = np.array(box.matrix_world)
    for refinement, why in (({"used": False, "message": "not refined"}, "left the model"),
                            (None, "--refine-model")):
        extra = {} if refinement is None else {"model_refinement": refinement}
        try:
            model_fix.apply_corrections(bpy.context, _track_with(extra, ["Box"]))
        except ValueError as e:
            assert why in str(e)
        else:
            raise AssertionError("corrections applied from a track without them")
    assert np.allclose(np.array(box.matrix_world), before)
