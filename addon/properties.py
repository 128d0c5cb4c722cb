"""Properties of sunlapse, kept apart from the UI."""

import bpy
from bpy.props import (BoolProperty, EnumProperty, FloatProperty, IntProperty,
                       PointerProperty, StringProperty)

from .estimate import options as estimate_options


def _is_camera(self, obj):
    return obj.type == "CAMERA"


def _is_mesh(self, obj):
    return obj.type == "MESH"


def _clip_range(context):
    from .blender import gather
    clip = gather.active_movieclip(context)
    if clip is None:
        return None
    return int(clip.frame_start), int(clip.frame_start + clip.frame_duration - 1)


def _use_frame_range_update(self, context):
    """Turning the range on starts it at the clip's real frames."""
    r = _clip_range(context)
    if self.use_frame_range and r is not None and not (
            r[0] <= self.frame_start <= self.frame_end <= r[1]):
        self.frame_start, self.frame_end = r


def _is_sun_lamp(self, obj):
    return obj.type == "LIGHT" and obj.data.type == "SUN"


class SunlapseSettings(bpy.types.PropertyGroup):
    model_collection: PointerProperty(
        name="Model", type=bpy.types.Collection,
        description="Collection holding the coarse 3D model of the scene; "
                    "empty: every visible mesh")
    camera: PointerProperty(
        name="Camera", type=bpy.types.Object, poll=_is_camera,
        description="Camera matched to the footage; empty: the scene camera")
    ground_object: PointerProperty(
        name="Ground", type=bpy.types.Object, poll=_is_mesh,
        description="The ground the shadows fall on; empty: detected automatically")
    ground_objects: StringProperty(
        name="Other Ground",
        description="More ground objects, comma-separated names (any case)")
    sun_lamp: PointerProperty(
        name="Sun Lamp", type=bpy.types.Object, poll=_is_sun_lamp,
        description="Sun lamp to drive; empty: a new one is created")
    method: EnumProperty(
        name="Method",
        items=[(c.key, c.label, c.description) for c in estimate_options.METHODS],
        default="default")
    ignore_top_rows: IntProperty(
        name="Ignore Top Rows", min=0, default=0,
        description="Rows at the top of the frame to ignore: not scene content "
                    "(burned-in time stamps, banners)")
    smoothing: EnumProperty(
        name="Smoothing",
        items=[(c.key, c.label, c.description) for c in estimate_options.SMOOTHINGS],
        default="two_pass")
    latitude: FloatProperty(name="Latitude", min=-90, max=90, default=0.0,
                            description="Degrees, north positive")
    longitude: FloatProperty(name="Longitude", min=-180, max=180, default=0.0,
                             description="Degrees, east positive")
    date: StringProperty(name="Date", default="", description="YYYY-MM-DD of the first frame")
    start_hour: FloatProperty(name="Start Time", min=0, max=24, default=12.0, subtype="TIME",
                              description="Local time of the first frame, hours")
    utc_offset: FloatProperty(name="UTC Offset", min=-14, max=14, default=0.0,
                              description="Hours between local time and UTC (used when "
                                          "Time Zone is empty)")
    time_zone: StringProperty(
        name="Time Zone", default="",
        description="IANA time zone of the local times (Europe/Paris, America/New_York): "
                    "daylight saving is then applied on each frame's date. Empty: the UTC "
                    "offset")
    use_exif_times: BoolProperty(
        name="EXIF Times", default=True,
        description="Image sequences: read each frame's capture time (DateTimeOriginal, "
                    "sub-seconds) and GPS position from its EXIF data when no times file "
                    "is given")
    refine_model: BoolProperty(
        name="Refine Model", default=True,
        description="Before the estimate, move, turn and scale each modelled object and "
                    "turn and zoom the camera so that the model's edges fall on the "
                    "footage's (a fixed camera; used only where the model is clearly off). "
                    "The .blend changes only with Apply Model Corrections")
    fit_latitude: BoolProperty(
        name="Fit Latitude", default=False,
        description="Physical smoothing also fits the latitude near the given one; off: "
                    "the latitude is used as given")
    frame_seconds: FloatProperty(name="Seconds per Frame", min=0, default=0.0,
                                 description="Time between two frames of the time-lapse")
    times_file: StringProperty(
        name="Frame Times", subtype="FILE_PATH", default="",
        description="CSV with each frame's capture time (columns frame, local_time; local "
                    "times use the UTC offset): frames are tracked in the order they were "
                    "taken and smoothed over real time. Empty: evenly spaced frames")
    use_frame_range: BoolProperty(
        name="Frame Range", default=False, update=_use_frame_range_update,
        description="Estimate only these frames (default: the whole clip)")
    frame_start: IntProperty(name="Start", default=1)
    frame_end: IntProperty(name="End", default=250)
    keyframe_strength: BoolProperty(
        name="Keyframe Strength", default=False,
        description="Also keyframe the lamp's strength from the measured sun/ambient "
                    "light (the present strength stands for the clip's median)")
    sync_sky: BoolProperty(
        name="Sync Sky", default=True,
        description="Also keyframe the world's Nishita Sky Texture from the track")
    last_report: StringProperty(name="Last check", default="")
    last_apply: StringProperty(name="Last apply", default="")
    show_plot: BoolProperty(name="Sun Plot", default=True,
                            description="Draw the elevation/azimuth/confidence plot over "
                                        "the clip in the Movie Clip Editor")
    show_shadow: BoolProperty(name="Tracked Shadow", default=True,
                              description="Draw the current frame's tracked shadow and its "
                                          "confidence over the clip")


classes = (SunlapseSettings,)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.Scene.sunlapse = PointerProperty(type=SunlapseSettings)


def unregister():
    del bpy.types.Scene.sunlapse
    _unregister()
