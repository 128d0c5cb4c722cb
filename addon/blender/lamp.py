"""Pointing a Sun lamp at the Sun (bpy side).

A Blender light shines along its local -Z, so the lamp's local +Z must point
toward the Sun (docs/design.md §4). The rotation is written through matrix_world,
so Blender stores it in the lamp's own rotation_mode (quaternion, Euler of any
order, axis-angle), parents included; keyframes go on that mode's property.
"""

import math

import bpy
from mathutils import Matrix, Vector

from ..core import angles

SUN_ANGULAR_DIAMETER_DEG = 0.545
KEYFRAME_GROUP = "sunlapse"


def rotation_path(obj) -> str:
    return {"QUATERNION": "rotation_quaternion",
            "AXIS_ANGLE": "rotation_axis_angle"}.get(obj.rotation_mode, "rotation_euler")


def sun_vector(zenith_deg, azimuth_world_deg) -> Vector:
    return Vector(angles.sun_in_world_from_angles(zenith_deg, azimuth_world_deg).tolist())


def point_lamp(obj, zenith_deg, azimuth_world_deg, frame=None):
    """Turns `obj` so its local +Z points to the Sun; keyframes it on `frame`."""
    target = sun_vector(zenith_deg, azimuth_world_deg)
    loc, _, scale = obj.matrix_world.decompose()
    previous = obj.rotation_quaternion.copy()
    obj.matrix_world = Matrix.LocRotScale(loc, target.to_track_quat("Z", "Y"), scale)
    if obj.rotation_mode == "QUATERNION" and obj.rotation_quaternion.dot(previous) < 0:
        # q and -q are the same rotation: keep the F-curves continuous.
        obj.rotation_quaternion = -obj.rotation_quaternion
    if frame is not None:
        obj.keyframe_insert(rotation_path(obj), frame=frame, group=KEYFRAME_GROUP)


def ensure_sun_lamp(context, obj=None, name="Sun"):
    """The given Sun lamp, or a new one of the Sun's angular size."""
    if obj is not None:
        if obj.type != "LIGHT" or obj.data.type != "SUN":
            raise ValueError(f"'{obj.name}' is not a Sun lamp")
        return obj
    data = bpy.data.lights.new(name, "SUN")
    data.angle = math.radians(SUN_ANGULAR_DIAMETER_DEG)
    data.energy = 4.0
    obj = bpy.data.objects.new(name, data)
    context.scene.collection.objects.link(obj)
    return obj
