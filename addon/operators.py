"""Operators. They call bridge/core and _native; errors go to self.report."""

import time

import bpy

from . import bridge, lamp, native_loader, pipeline


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


class CLIP_OT_sunlapse_initial_sun(bpy.types.Operator):
    """Estimate the Sun on the current frame of the clip from the model and
    camera (thesis chapter 3) and point the Sun lamp at it"""
    bl_idname = "clip.sunlapse_initial_sun"
    bl_label = "Sun from Current Frame"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        scene = context.scene
        settings = scene.sunlapse
        try:
            native_loader.require()
            model, cam, clip = gather_all(context, settings)
            native_scene = bridge.build_scene(model)
            native_camera = bridge.build_camera(cam)
            frame = scene.frame_current
            if not clip.frame_start <= frame <= clip.frame_end:
                raise bridge.SceneError(f"frame {frame} is outside the clip "
                                        f"({clip.frame_start}-{clip.frame_end})")
            options = pipeline.RunOptions(method=settings.method,
                                          ignore_top_rows=settings.ignore_top_rows)
            bgr = pipeline.read_frame(clip.filepath, frame - clip.frame_start)
            init = pipeline.estimate_initial(native_scene, native_camera, bgr, options)
        except (bridge.SceneError, pipeline.PipelineError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if not init["success"]:
            self.report({"ERROR"}, f"No Sun found on frame {frame}: {init['message']}")
            return {"CANCELLED"}
        try:
            sun = lamp.ensure_sun_lamp(context, settings.sun_lamp)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        settings.sun_lamp = sun
        animated = bool(sun.animation_data and sun.animation_data.action)
        # The estimate is in the world frame: the lamp needs nothing more.
        lamp.point_lamp(sun, init["zenith_deg"], init["azimuth_deg"],
                        frame=frame if animated else None)
        note = init["message"]
        self.report({"WARNING" if note else "INFO"},
                    f"Sun at zenith {init['zenith_deg']:.1f}°, world azimuth "
                    f"{init['azimuth_deg']:.1f}° (confidence {init['confidence']:.2f})"
                    + (f": {note}" if note else ""))
        return {"FINISHED"}


classes = (CLIP_OT_sunlapse_check_scene, CLIP_OT_sunlapse_initial_sun)
register, unregister = bpy.utils.register_classes_factory(classes)
