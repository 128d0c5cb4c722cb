"""Pointing and keyframing the Sun lamp in every rotation mode."""
import math

import bpy
import numpy as np
import pytest

from sunlapse.blender import compat, lamp

MODES = ["QUATERNION", "AXIS_ANGLE", "XYZ", "XZY", "YXZ", "YZX", "ZXY", "ZYX"]
DIRECTIONS = [(10, 0), (45, 90), (60, 200), (85, 359), (30, 271), (0.5, 45)]


def local_z(obj):
    return np.array(obj.matrix_world.col[2][:3])


def angle_deg(u, v):
    cos = float(np.dot(u, v) / np.linalg.norm(u) / np.linalg.norm(v))
    return math.degrees(math.acos(min(1.0, cos)))


@pytest.mark.parametrize("mode", MODES)
def test_point_lamp_in_every_rotation_mode(empty_scene, mode):
    obj = lamp.ensure_sun_lamp(bpy.context)
    obj.rotation_mode = mode
    assert math.degrees(obj.data.angle) == pytest.approx(0.545, abs=1e-4)
    for z, a in DIRECTIONS:
        lamp.point_lamp(obj, z, a)
        bpy.context.view_layer.update()
        assert angle_deg(local_z(obj), np.array(lamp.sun_vector(z, a))) < 1e-3


@pytest.mark.parametrize("mode", MODES)
def test_keyframes_hold_the_angles_in_every_mode(empty_scene, mode):
    scene = empty_scene
    obj = lamp.ensure_sun_lamp(bpy.context)
    obj.rotation_mode = mode
    path = lamp.rotation_path(obj)
    for f, (z, a) in enumerate(DIRECTIONS, start=1):
        lamp.point_lamp(obj, z, a, frame=f)
    fcurves = [fc for fc in compat.fcurves(obj) if fc.data_path == path]
    assert len(fcurves) == {"QUATERNION": 4, "AXIS_ANGLE": 4}.get(mode, 3)
    for f, (z, a) in enumerate(DIRECTIONS, start=1):
        scene.frame_set(f)
        assert angle_deg(local_z(obj), np.array(lamp.sun_vector(z, a))) < 0.01, (mode, f)


def test_parented_lamp_is_pointed_in_world_space(empty_scene):
    parent = bpy.data.objects.new("Rig", None)
    empty_scene.collection.objects.link(parent)
    parent.rotation_euler = (0.3, -0.2, 1.1)
    obj = lamp.ensure_sun_lamp(bpy.context)
    obj.parent = parent
    bpy.context.view_layer.update()
    lamp.point_lamp(obj, 40, 120)
    bpy.context.view_layer.update()
    assert angle_deg(local_z(obj), np.array(lamp.sun_vector(40, 120))) < 1e-3


def test_ensure_sun_lamp_rejects_other_objects(empty_scene):
    point = bpy.data.objects.new("P", bpy.data.lights.new("P", "POINT"))
    with pytest.raises(ValueError, match="not a Sun lamp"):
        lamp.ensure_sun_lamp(bpy.context, point)
