"""Bad input gives clear errors, never a crash."""
import bpy
import numpy as np
import pytest

import scenes
from sunlapse.blender import gather


def tri_arrays():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32)
    t = np.array([[0, 1, 2]], dtype=np.int32)
    ids = np.zeros(1, dtype=np.int32)
    return v, t, ids


def test_wrong_dtype_names_the_argument(native):
    v, t, ids = tri_arrays()
    with pytest.raises(ValueError, match="vertices.*float32"):
        native.Scene(v.astype(np.float64), t, ids)
    with pytest.raises(ValueError, match="triangles.*int32"):
        native.Scene(v, t.astype(np.int64), ids)


def test_non_contiguous_arrays_are_rejected(native):
    v, t, ids = tri_arrays()
    v2 = np.repeat(v, 2, axis=0)[::2]
    assert not v2.flags.c_contiguous
    with pytest.raises(ValueError, match="vertices.*C-contiguous"):
        native.Scene(v2, t, ids)
    with pytest.raises(ValueError, match="vertices"):
        native.Scene(np.asfortranarray(np.repeat(v, 2, axis=0)), t, ids)


def test_wrong_shapes_are_rejected(native):
    v, t, ids = tri_arrays()
    with pytest.raises(ValueError, match="vertices: axis 1"):
        native.Scene(v[:, :2].copy(), t, ids)
    with pytest.raises(ValueError, match="object_ids"):
        native.Scene(v, t, np.zeros(2, dtype=np.int32))
    scene = native.Scene(v, t, ids)
    with pytest.raises(ValueError, match="directions"):
        scene.intersect(v, v[:2].copy())


def test_empty_mesh_and_bad_indices(native):
    v, t, ids = tri_arrays()
    with pytest.raises(ValueError, match="triangles"):
        native.Scene(v, np.zeros((0, 3), np.int32), np.zeros(0, np.int32))
    with pytest.raises(ValueError, match="out of range"):
        native.Scene(v, np.array([[0, 1, 3]], np.int32), ids)
    with pytest.raises(ValueError, match="out of range"):
        native.Scene(v, np.array([[0, -1, 2]], np.int32), ids)
    with pytest.raises(ValueError, match="not finite"):
        native.Scene(np.full((3, 3), np.nan, np.float32), t, ids)


def test_empty_model_in_blender(empty_scene):
    with pytest.raises(gather.SceneError, match="model is empty"):
        gather.gather_model(bpy.context)


def test_no_camera(empty_scene):
    scenes.add_box_on_plane(empty_scene)
    with pytest.raises(gather.SceneError, match="no camera"):
        gather.gather_camera(bpy.context)


def test_bad_camera_values(native):
    with pytest.raises(ValueError, match="lens_mm"):
        native.Camera.from_blender(lens_mm=0, sensor_width_mm=36, sensor_height_mm=24,
                                   width=10, height=10, matrix_world=np.eye(4))
    with pytest.raises(ValueError, match="sensor_fit"):
        native.Camera.from_blender(lens_mm=50, sensor_width_mm=36, sensor_height_mm=24,
                                   sensor_fit="DIAGONAL", width=10, height=10,
                                   matrix_world=np.eye(4))


def test_clip_aspect_mismatch_is_reported(empty_scene, tmp_path):
    scene = empty_scene
    scenes.add_camera(scene, (0, -10, 5), (0, 0, 0))
    scene.render.resolution_x, scene.render.resolution_y = 1920, 1080
    first = scenes.write_frames(str(tmp_path / "frames"), width=64, height=48)
    clip = scenes.load_clip(scene, first)
    info = gather.gather_clip(bpy.context)
    with pytest.raises(gather.SceneError, match="aspect"):
        gather.gather_camera(bpy.context, None, info, clip)
