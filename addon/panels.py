"""Sidebar panels: Movie Clip Editor › Sun and 3D View › Sun.

A parent panel with the current frame's Sun and sub-panels in the order of
the work (Scene, Estimate, Smoothing / Place and Time, Lamp and Render,
Export), laid out like Blender's Sun Position add-on: property labels in a
column of their own (use_property_split), short enough for the default
sidebar width.
"""

import bpy

from .blender import background, compat, gather, store
from .blender.text import wrapped
from .core import angles, trackfile
from .estimate import native_loader


def _split(layout):
    layout.use_property_split = True
    layout.use_property_decorate = False
    return layout


def _running():
    return background.RUN


def angles_text(track, est):
    """(elevation line, azimuth line) as the Sun Position add-on shows them:
    elevation above the horizon, azimuth clockwise from north (geographic)
    when north is known, else from the scene's +Y."""
    elevation = 90.0 - est.zenith_deg
    if track.north_known():
        az = f"Azimuth {angles.wrap_azimuth_deg(est.azimuth_deg):.1f}° from north"
    else:
        world = angles.azimuth_world_from_geographic(est.azimuth_deg, track.north_offset_deg)
        az = f"Azimuth {world:.1f}° from +Y"
    return f"Elevation {elevation:.1f}°", az


# How the panel names where north came from.
NORTH_SOURCE = {trackfile.NorthSource.EPHEMERIS: "fitted",
                trackfile.NorthSource.SUN_CIRCLE: "fitted to the Sun's circle",
                trackfile.NorthSource.GIVEN: "given"}


def draw_sun_summary(layout, context):
    """The stored track on the current frame: elevation, azimuth, north
    offset, confidence, or why the frame has none."""
    track = store.load_track()
    if track is None:
        layout.label(text="No estimate yet", icon="INFO")
        return
    frame = context.scene.frame_current
    est = track.frame(frame)
    col = layout.column(align=True)
    if est is None:
        col.label(text=f"Frame {frame} is outside the track", icon="INFO")
        return
    north = NORTH_SOURCE.get(track.north_source())
    if est.has_estimate:
        el, az = angles_text(track, est)
        col.label(text=el, icon="LIGHT_SUN")
        col.label(text=az, icon="ORIENTATION_GLOBAL" if north else "ORIENTATION_LOCAL")
        n = angles.wrap_signed_deg(track.north_offset_deg)
        col.label(text=f"North offset {n:.1f}° ({north})" if north else
                  "North unknown (offset 0°)", icon="BLANK1")
        # A calibrated track's confidence is a chance the user can act on.
        chance = trackfile.ConfidenceKind.of(track) == trackfile.ConfidenceKind.PROBABILITY \
            and not est.predicted and est.raw_zenith_deg is not None
        note = (" (predicted: no direct sunlight)" if est.predicted and
                est.sunlight == trackfile.Sunlight.NO else " (predicted)" if est.predicted else
                "" if est.raw_zenith_deg is not None else " (smoothed)")
        col.label(text=f"Confidence {est.confidence:.0%} (within 2°)" if chance else
                  f"Confidence {est.confidence:.2f}{note}", icon="BLANK1")
    if est.reason:
        wrapped(col, context, est.reason, icon="INFO", max_lines=3)


def draw_progress(layout):
    """Blender 4.0+'s progress widget, else a label, and a cancel button."""
    run = _running()
    row = layout.row(align=True)
    text = "Cancelling" if run["cancel"] else f"Estimating {100 * run['fraction']:.0f}%"
    if hasattr(row, "progress"):
        row.progress(factor=run["fraction"], type="BAR", text=text)
    else:
        row.label(text=text, icon="TIME")
    row.operator("clip.sunlapse_cancel", text="", icon="CANCEL")


class _Panel:
    bl_region_type = "UI"
    bl_category = "Sun"

    @classmethod
    def poll(cls, context):
        sd = context.space_data  # the clip editor's mask mode is not ours
        return sd is not None and getattr(sd, "mode", "TRACKING") == "TRACKING"


class _Sub(_Panel):
    @classmethod
    def poll(cls, context):
        return _Panel.poll.__func__(cls, context) and native_loader._native is not None


# Draws of the parent panel per space type (the UI tests wait for it).
DRAWN = {}


def draw_main(self, context):
    DRAWN[self.bl_space_type] = DRAWN.get(self.bl_space_type, 0) + 1
    layout = self.layout
    if native_loader._native is None:
        box = layout.box()
        box.alert = True
        box.label(text="Native core not loaded", icon="ERROR")
        for line in native_loader.DIAGNOSIS:  # why, which file/library/Python
            wrapped(box, context, line, max_lines=12)
        return
    if _running()["running"]:
        draw_progress(layout)
    draw_sun_summary(layout, context)


def draw_scene(self, context):
    layout = _split(self.layout)
    s = context.scene.sunlapse
    col = layout.column()
    col.prop(s, "model_collection")
    col.prop(s, "camera")
    col.prop(s, "ground_object")
    col.prop(s, "ground_objects", text="Others")
    col.prop(s, "ignore_top_rows", text="Top Rows")
    col = layout.column(align=True)
    col.operator("clip.sunlapse_solve_camera", text="Solve Camera", icon="CAMERA_DATA")
    col.operator("clip.sunlapse_check_scene", icon="CHECKMARK")
    if s.last_report:
        wrapped(layout, context, s.last_report)


def draw_estimate(self, context):
    layout = _split(self.layout)
    s = context.scene.sunlapse
    layout.prop(s, "method")
    clip = gather.active_movieclip(context)
    col = layout.column(heading="Frames", align=True)
    col.prop(s, "use_frame_range", text="Only a Range")
    if s.use_frame_range:
        col.prop(s, "frame_start", text="Start")
        col.prop(s, "frame_end", text="End")
    elif clip is not None:
        end = clip.frame_start + clip.frame_duration - 1
        row = layout.row()
        row.alignment = "RIGHT"
        row.label(text=f"Whole clip: {clip.frame_start}-{end} ({clip.frame_duration})")
    layout.prop(s, "times_file", text="Times File")
    if clip is not None and clip.source == "SEQUENCE":
        layout.prop(s, "use_exif_times")
    row = layout.row()
    row.active = s.method == "default"  # the thesis baseline runs on the model as it is
    row.prop(s, "refine_model")
    draw_model_refinement(layout, context)
    col = layout.column(align=True)
    col.use_property_split = False
    run = _running()
    if run["running"]:
        draw_progress(col)
    sub = col.row(align=True)
    sub.enabled = not run["running"]  # one run at a time
    sub.scale_y = 1.4
    sub.operator("clip.sunlapse_estimate", icon="LIGHT_SUN")
    sub = col.row(align=True)
    sub.enabled = not run["running"]
    sub.operator("clip.sunlapse_initial_sun", text="Current Frame Only", icon="LIGHT_SUN")


def draw_model_refinement(layout, context):
    """What the last run's Refine Model found, and the button that applies
    it to the model."""
    track = store.load_track()
    r = track.extra.get("model_refinement") if track is not None else None
    if not isinstance(r, dict):
        return
    problem = track.problem("model_refinement")
    col = layout.column(align=True)
    if problem is not None:
        wrapped(col, context, problem.message, icon="MESH_CUBE", max_lines=4)
    if r.get("used") and not r.get("applied"):
        col.operator("clip.sunlapse_apply_model", icon="CHECKMARK")
    elif r.get("applied"):
        col.label(text="Model corrections applied", icon="CHECKMARK")


def draw_place(self, context):
    layout = _split(self.layout)
    s = context.scene.sunlapse
    layout.prop(s, "smoothing")
    sp = getattr(context.scene, "sun_pos_properties", None)
    physical = s.smoothing == "physical"
    col = layout.column(align=True)
    col.active = physical
    col.prop(s, "latitude")
    col.prop(s, "longitude")
    col.prop(s, "fit_latitude", text="Fit Latitude")
    col = layout.column(align=True)
    col.active = physical
    clip = gather.active_movieclip(context)
    times_known = bool(s.times_file) or (
        s.use_exif_times and clip is not None and clip.source == "SEQUENCE")
    if not s.times_file:
        col.prop(s, "date")
        col.prop(s, "start_hour", text="Start Time")
        col.prop(s, "frame_seconds", text="Interval (s)")
    col.prop(s, "time_zone")
    sub = col.row()
    sub.active = physical and not s.time_zone
    sub.prop(s, "utc_offset")
    if physical and sp is not None and not s.date and not times_known:
        layout.label(text="Place and time: Sun Position add-on", icon="INFO")
    row = layout.row()
    row.enabled = sp is not None
    row.operator("clip.sunlapse_to_sun_position", icon="EXPORT")


def draw_lamp(self, context):
    layout = _split(self.layout)
    s = context.scene.sunlapse
    layout.prop(s, "sun_lamp")
    col = layout.column(heading="Keyframe", align=True)
    col.prop(s, "sync_sky", text="Sky")
    col.prop(s, "keyframe_strength", text="Strength")
    col = layout.column(align=True)
    col.operator("clip.sunlapse_apply_lamp", icon="KEYINGSET")
    if s.last_apply:
        wrapped(col, context, s.last_apply, icon="CHECKMARK", max_lines=3)
    layout.operator("clip.sunlapse_setup_ar", icon="RENDER_ANIMATION")


def draw_export(self, context):
    self.layout.operator("clip.sunlapse_export", icon="EXPORT")


_SECTIONS = (("scene", "Scene", draw_scene, False),
             ("estimate", "Estimate", draw_estimate, False),
             ("place", "Smoothing / Place and Time", draw_place, False),
             ("lamp", "Lamp and Render", draw_lamp, False),
             ("export", "Export", draw_export, True))


def _make_classes():
    out = []
    for space, prefix in (("CLIP_EDITOR", "CLIP"), ("VIEW_3D", "VIEW3D")):
        parent_id = f"{prefix}_PT_sunlapse"
        out.append(type(parent_id, (_Panel, bpy.types.Panel), {
            "bl_idname": parent_id, "bl_space_type": space, "bl_label": "sunlapse",
            "draw": draw_main}))
        for key, label, draw, closed in _SECTIONS:
            idname = f"{prefix}_PT_sunlapse_{key}"
            attrs = {"bl_idname": idname, "bl_space_type": space, "bl_label": label,
                     "bl_parent_id": parent_id, "draw": draw}
            if closed:
                attrs["bl_options"] = {"DEFAULT_CLOSED"}
            out.append(type(idname, (_Sub, bpy.types.Panel), attrs))
    return tuple(out)


# The operators in the order of the work, as the Movie Clip Editor's Track
# menu shows them (and so F3's menu search finds them), the way Blender's
# own motion-tracking tools sit there.
MENU_OPERATORS = ("clip.sunlapse_solve_camera", "clip.sunlapse_check_scene",
                  "clip.sunlapse_estimate", "clip.sunlapse_initial_sun",
                  "clip.sunlapse_apply_model", "clip.sunlapse_apply_lamp",
                  "clip.sunlapse_setup_ar",
                  "clip.sunlapse_to_sun_position", "clip.sunlapse_export")


class CLIP_MT_sunlapse(bpy.types.Menu):
    bl_idname = "CLIP_MT_sunlapse"
    bl_label = "Sun (sunlapse)"

    def draw(self, context):
        for idname in MENU_OPERATORS:
            self.layout.operator(idname)


def draw_track_menu(self, context):
    self.layout.separator()
    self.layout.menu(CLIP_MT_sunlapse.bl_idname, icon="LIGHT_SUN")


def draw_overlay_options(self, context):
    """The overlay's toggles where the editor's own are: its Overlays
    popover (Blender 4.2+), or the Display popover before."""
    s = getattr(context.scene, "sunlapse", None)
    if s is None:
        return
    layout = self.layout
    layout.separator()
    col = layout.column(heading="Sun", align=True)
    col.prop(s, "show_plot")
    col.prop(s, "show_shadow")


classes = _make_classes() + (CLIP_MT_sunlapse,)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    bpy.types.CLIP_MT_track.append(draw_track_menu)
    compat.clip_overlay_panel().append(draw_overlay_options)


def unregister():
    compat.clip_overlay_panel().remove(draw_overlay_options)
    bpy.types.CLIP_MT_track.remove(draw_track_menu)
    _unregister()
