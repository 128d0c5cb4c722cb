"""Sidebar panels: Movie Clip Editor › Sun and 3D View › Sun."""

import bpy

from . import native_loader


def draw_sun_panel(layout, context):
    if native_loader._native is None:
        box = layout.box()
        box.alert = True
        box.label(text="Native core not loaded", icon="ERROR")
        import textwrap
        for line in native_loader.DIAGNOSIS:  # why, which file/library/Python
            for part in textwrap.wrap(line, 60):
                box.label(text=part)
        return
    settings = context.scene.sunlapse
    col = layout.column()
    col.prop(settings, "model_collection")
    col.prop(settings, "camera")
    col.prop(settings, "ground_objects")
    col.prop(settings, "method")
    col.prop(settings, "smoothing")
    col.prop(settings, "times_file")
    if settings.smoothing == "physical":
        box = col.box()
        if getattr(context.scene, "sun_pos_properties", None) is not None and not settings.date:
            box.label(text="Place and time: Sun Position add-on", icon="INFO")
        names = ("latitude", "fit_latitude", "longitude", "utc_offset") if settings.times_file \
            else ("latitude", "fit_latitude", "longitude", "date", "start_hour", "utc_offset",
                  "frame_seconds")
        for name in names:
            box.prop(settings, name)
    col.prop(settings, "ignore_top_rows")
    row = col.row(align=True)
    row.prop(settings, "use_frame_range", text="")
    sub = row.row(align=True)
    sub.active = settings.use_frame_range
    sub.prop(settings, "frame_start")
    sub.prop(settings, "frame_end")
    layout.operator("clip.sunlapse_solve_camera", icon="CAMERA_DATA")
    layout.operator("clip.sunlapse_check_scene", icon="CHECKMARK")
    layout.operator("clip.sunlapse_estimate", icon="LIGHT_SUN")
    layout.operator("clip.sunlapse_initial_sun", icon="LIGHT_SUN")
    box = layout.box()
    box.prop(settings, "sun_lamp")
    box.prop(settings, "sync_sky")
    box.prop(settings, "keyframe_strength")
    box.operator("clip.sunlapse_apply_lamp", icon="KEYINGSET")
    box.operator("clip.sunlapse_setup_ar", icon="RENDER_ANIMATION")
    box.operator("clip.sunlapse_export", icon="EXPORT")
    if settings.last_report:
        layout.label(text=settings.last_report[:120])
    draw_track_summary(layout, context)


def draw_track_summary(layout, context):
    """The stored track on the current frame: angles, confidence, or why not."""
    from . import results
    track = results.load_track()
    if track is None:
        return
    est = track.frame(context.scene.frame_current)
    col = layout.column(align=True)
    if est is None:
        col.label(text="Current frame is outside the track")
        return
    if est.has_estimate:
        col.label(text=f"Zenith {est.zenith_deg:.2f}°  Azimuth {est.azimuth_deg:.2f}°")
        col.label(text=f"Confidence {est.confidence:.2f}")
    if est.reason:
        col.label(text=est.reason[:80], icon="INFO")


class CLIP_PT_sunlapse(bpy.types.Panel):
    bl_space_type = "CLIP_EDITOR"
    bl_region_type = "UI"
    bl_category = "Sun"
    bl_label = "sunlapse"

    @classmethod
    def poll(cls, context):
        sd = context.space_data
        return sd is not None and getattr(sd, "mode", "TRACKING") == "TRACKING"

    def draw(self, context):
        draw_sun_panel(self.layout, context)


class VIEW3D_PT_sunlapse(bpy.types.Panel):
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Sun"
    bl_label = "sunlapse"

    def draw(self, context):
        draw_sun_panel(self.layout, context)


classes = (CLIP_PT_sunlapse, VIEW3D_PT_sunlapse)
register, unregister = bpy.utils.register_classes_factory(classes)
