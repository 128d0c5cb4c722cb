"""Operators. They call bridge/core and _native; errors go to self.report."""

import time

import bpy

from . import bridge, native_loader


def ground_names(settings):
    return [n.strip() for n in settings.ground_objects.split(",") if n.strip()]


def gather_all(context, settings=None, movieclip=None, collection=None,
               camera_obj=None):
    """Model, camera and clip of the current scene; raises bridge.SceneError."""
    settings = settings or context.scene.sunlapse
    clip = bridge.gather_clip(context, movieclip)
    clip_obj = movieclip or bridge.active_movieclip(context)
    cam = bridge.gather_camera(context, camera_obj or settings.camera, clip, clip_obj)
    model = bridge.gather_model(context, collection or settings.model_collection)
    return model, cam, clip


class CLIP_OT_sunlapse_check_scene(bpy.types.Operator):
    """Gather the model, camera and clip and build the ray-casting scene"""
    bl_idname = "clip.sunlapse_check_scene"
    bl_label = "Check Scene"
    bl_options = {"REGISTER"}

    def execute(self, context):
        settings = context.scene.sunlapse
        try:
            native_loader.require()
            t0 = time.perf_counter()
            model, cam, clip = gather_all(context, settings)
            t1 = time.perf_counter()
            bridge.build_scene(model)
            bridge.build_camera(cam)
            t2 = time.perf_counter()
        except (bridge.SceneError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for w in cam.warnings:
            self.report({"WARNING"}, w)
        ground = ground_names(settings) or bridge.guess_ground(model)
        msg = (f"{model.num_triangles} triangles in {len(model.names)} objects "
               f"(gathered in {t1 - t0:.2f} s, BVH {t2 - t1:.2f} s); camera "
               f"'{cam.name}'; clip '{clip.name}' {clip.width}x{clip.height}, "
               f"frames {clip.frame_start}-{clip.frame_end}; ground: "
               f"{', '.join(ground) or 'none found'}")
        settings.last_report = msg
        self.report({"INFO"}, msg)
        return {"FINISHED"}


classes = (CLIP_OT_sunlapse_check_scene,)
register, unregister = bpy.utils.register_classes_factory(classes)
