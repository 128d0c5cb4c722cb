"""Matching the camera from tracking markers named after their ground points."""

import bpy
import pytest
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

import scenes


def mark(clip, scene, cam_obj, points, frame=1):
    for name, xyz in points:
        ndc = world_to_camera_view(scene, cam_obj, Vector(xyz))
        track = clip.tracking.tracks.new(name=name, frame=frame)
        track.markers.find_frame(frame).co = (ndc.x, ndc.y)


def ground_points():
    return [(f"p{i} {x} {y}", (x, y, 0.0))
            for i, (x, y) in enumerate((x, y) for x in (-1.5, -0.5, 0.5, 1.5)
                                       for y in (-0.5, 0.5, 1.5))]


def test_solve_camera_recovers_the_camera(empty_scene, tmp_path):
    scene = empty_scene
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    clip = scenes.load_clip(scene, scenes.write_frames(str(tmp_path / "f"), width=320, height=240))
    truth = scenes.add_camera(scene, (0.4, -4.0, 3.0), (0, 0.5, 0), lens=32.0, name="Truth")
    mark(clip, scene, truth, ground_points())
    scene.camera = None
    truth_matrix = truth.matrix_world.copy()
    bpy.data.objects.remove(truth)
    scene.frame_set(1)
    assert bpy.ops.clip.sunlapse_solve_camera() == {"FINISHED"}
    cam = scene.camera
    assert cam is not None and cam.data.lens == pytest.approx(32.0, rel=2e-3)
    assert (cam.matrix_world.translation - truth_matrix.translation).length < 5e-3
    assert (cam.matrix_world.col[2].xyz - truth_matrix.col[2].xyz).length < 1e-3
    # The lens and the error stay in the panel once the report is gone.
    report = scene.sunlapse.last_report
    assert report.startswith("Camera solved from 12 points: lens 32.0 mm") and "px RMS" in report


def test_solve_camera_explains_what_is_missing(empty_scene, tmp_path):
    scene = empty_scene
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    clip = scenes.load_clip(scene, scenes.write_frames(str(tmp_path / "f"), width=320, height=240))
    truth = scenes.add_camera(scene, (0.4, -4.0, 3.0), (0, 0.5, 0), lens=32.0, name="Truth")
    mark(clip, scene, truth, ground_points()[:4] + [("no numbers here", (2, 2, 0))])
    with pytest.raises(RuntimeError, match="at least 6.*no numbers here.*'foot 0 0'"):
        bpy.ops.clip.sunlapse_solve_camera()
    assert "Name each marker's track" in scene.sunlapse.last_report
