"""Properties of sunlapse, kept apart from the UI."""

import bpy
from bpy.props import PointerProperty, StringProperty


def _is_camera(self, obj):
    return obj.type == "CAMERA"


class SunlapseSettings(bpy.types.PropertyGroup):
    model_collection: PointerProperty(
        name="Model", type=bpy.types.Collection,
        description="Collection holding the coarse 3D model of the scene; "
                    "empty: every visible mesh")
    camera: PointerProperty(
        name="Camera", type=bpy.types.Object, poll=_is_camera,
        description="Camera matched to the footage; empty: the scene camera")
    ground_objects: StringProperty(
        name="Ground",
        description="Comma-separated names of the ground object(s) the shadows "
                    "fall on; empty: detected automatically")
    last_report: StringProperty(name="Last check", default="")


classes = (SunlapseSettings,)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Scene.sunlapse = PointerProperty(type=SunlapseSettings)


def unregister():
    del bpy.types.Scene.sunlapse
    _unregister()
