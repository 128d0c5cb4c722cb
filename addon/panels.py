"""Sidebar panels: Movie Clip Editor › Sun and 3D View › Sun."""

import bpy

from . import native_loader


def draw_sun_panel(layout, context):
    if native_loader._native is None:
        box = layout.box()
        box.alert = True
        box.label(text="Native core not built", icon="ERROR")
        for line in ("From the sunlapse source folder run:",
                     "bash tools/install.sh"):
            box.label(text=line)
        return
    settings = context.scene.sunlapse
    col = layout.column()
    col.prop(settings, "model_collection")
    col.prop(settings, "camera")
    col.prop(settings, "ground_objects")
    col.prop(settings, "sun_lamp")
    col.prop(settings, "method")
    col.prop(settings, "ignore_top_rows")
    layout.operator("clip.sunlapse_check_scene", icon="CHECKMARK")
    layout.operator("clip.sunlapse_initial_sun", icon="LIGHT_SUN")
    if settings.last_report:
        layout.label(text=settings.last_report[:120])


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
