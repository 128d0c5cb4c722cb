"""Operators: thin leaves over the glue library (blender/) and the
estimate; errors go to self.report, never a traceback."""

import datetime as dt
import time

import bpy
from bpy.props import EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from .blender import ar, background, export, gather, job, keys, lamp, model_fix, place, report, \
    store
from .blender.background import RUN, redraw_all, running
from .panels import wrapped
from .estimate import errors, frames as clip_frames, native_loader, thesis
from .estimate import options as estimate_options, run as estimate_run
from .core import angles, clock, trackfile


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
            model, cam, clip = job.gather_all(context, settings)
            t1 = time.perf_counter()
            scene_n, camera_n = gather.build_scene(model), gather.build_camera(cam)
            t2 = time.perf_counter()
            ground = job.ground_names(settings, model) or gather.guess_ground(model, cam)
            unseen = job.view_doubts(model, cam, scene_n, camera_n, ground)
            camera_obj = settings.camera or context.scene.camera
            moved = gather.camera_motion(context, camera_obj,
                                         (clip.frame_start, clip.frame_end))
            solve = gather.camera_solve(context, camera_obj)
        except (gather.SceneError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        for w in cam.warnings:
            self.report({"WARNING"}, w)
        msg = (f"{model.num_triangles} triangles in {len(model.names)} objects "
               f"(gathered in {t1 - t0:.2f} s, BVH {t2 - t1:.2f} s); camera "
               f"'{cam.name}'; clip '{clip.name}' {clip.width}x{clip.height}, "
               f"frames {clip.frame_start}-{clip.frame_end}; ground: "
               f"{', '.join(ground) or 'none found'}")
        level = "INFO"
        doubts = unseen + gather.ground_doubts(model, ground) if ground else [
            "No ground in view: model the surface the shadows fall on (a plane under the "
            "objects) and pick it as Ground"]
        if moved is not None:
            # Estimated: each frame seen from the camera's pose on it.
            msg += f"; the camera moves over the clip ({moved})"
            if settings.method != "default":
                doubts.append("the thesis method needs a camera that stays put: use the "
                              "default method")
        if solve is not None:
            words, doubtful = solve
            if doubtful:
                doubts.append(words)
            else:
                msg += f"; {words}"
        if doubts:
            # A lone object (the default cube) casts its shadow on nothing
            # modelled: its own top was taken for the ground.
            msg += ". " + "; ".join(doubts)
            level = "WARNING"
        settings.last_report = msg
        self.report({level}, msg)
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
            model, cam, clip = job.gather_all(context, settings)
            native_scene = gather.build_scene(model)
            native_camera = gather.build_camera(cam)
            frame = scene.frame_current
            if not clip.frame_start <= frame <= clip.frame_end:
                raise gather.SceneError(f"frame {frame} is outside the clip "
                                        f"({clip.frame_start}-{clip.frame_end})")
            options = estimate_options.EstimateOptions(
                method=settings.method, ignore_top_rows=settings.ignore_top_rows)
            bgr = clip_frames.read_frame(clip.filepath, frame - clip.frame_start)
            init = thesis.estimate_initial(native_scene, native_camera, bgr, options)
        except (gather.SceneError, errors.EstimateError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if init.status != native_loader.require().InitialSunStatus.SUCCESS:
            self.report({"ERROR"}, f"No Sun found on frame {frame}: {init.message}")
            return {"CANCELLED"}
        try:
            sun = lamp.ensure_sun_lamp(context, settings.sun_lamp)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        settings.sun_lamp = sun
        animated = bool(sun.animation_data and sun.animation_data.action)
        # The estimate is in the world frame: the lamp needs nothing more.
        lamp.point_lamp(sun, init.zenith_deg, init.azimuth_deg,
                        frame=frame if animated else None)
        note = init.message
        self.report({"WARNING" if note else "INFO"},
                    f"Sun at zenith {init.zenith_deg:.1f}°, world azimuth "
                    f"{init.azimuth_deg:.1f}° (confidence {init.confidence:.2f})"
                    + (f": {note}" if note else ""))
        return {"FINISHED"}


# The one Estimate Sun run of this Blender session (a second would race the
# first for the stored track): the panels and the status bar read it.
def draw_status_progress(self, context):
    """The status bar while a run goes: a progress bar (Blender 4.0+'s
    progress widget; a text bar before) and a cancel button, like Blender's
    own jobs."""
    if not RUN["running"]:
        return
    RUN["drawn"] += 1  # the UI tests check the bar was drawn during a run
    row = self.layout.row(align=True)
    text = "Cancelling the Sun estimate" if RUN["cancel"] else "Estimating the Sun"
    if hasattr(row, "progress"):
        row.progress(factor=RUN["fraction"], type="BAR",
                     text=f"{text} {100 * RUN['fraction']:.0f}%")
    else:
        filled = int(round(20 * RUN["fraction"]))
        row.label(text=f"{text}  {'█' * filled}{'░' * (20 - filled)}  {100 * RUN['fraction']:.0f}%",
                  icon="LIGHT_SUN")
    row.operator("clip.sunlapse_cancel", text="", icon="CANCEL")


class CLIP_OT_sunlapse_cancel(bpy.types.Operator):
    """Cancel the running Sun estimate (as Esc does); nothing is changed"""
    bl_idname = "clip.sunlapse_cancel"
    bl_label = "Cancel Sun Estimate"

    @classmethod
    def poll(cls, context):
        return RUN["running"]

    def execute(self, context):
        RUN["cancel"] = True
        return {"FINISHED"}


class CLIP_OT_sunlapse_estimate(bpy.types.Operator):
    """Estimate the Sun on every frame of the clip: by default the whole clip
    at once (every frame's shadows scored over the whole sky, one path for
    the Sun, refined by the shadows), then smoothing. Esc cancels"""
    bl_idname = "clip.sunlapse_estimate"
    bl_label = "Estimate Sun"
    bl_options = {"REGISTER", "UNDO"}

    _timer = None

    def _prepare(self, context):
        if running():
            self.report({"ERROR"}, "Estimate Sun is already running: wait for it, or press Esc "
                                   "to cancel it")
            return False
        warnings = []
        try:
            self._job = job.prepare_job(context, warnings=warnings)
        except (gather.SceneError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return False
        for w in warnings:
            self.report({"WARNING"}, w)
        return True

    def execute(self, context):  # synchronous: blender -b, scripts
        if not self._prepare(context):
            return {"CANCELLED"}
        run = self._job
        RUN.update(running=True, fraction=0.0, cancel=False, thread=None)
        try:
            track = estimate_run.run(run.scene, run.camera, run.clip.filepath,
                                     run.clip.frame_start, run.frames, run.options,
                                     frame_cameras=run.frame_cameras)
        except (errors.EstimateError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        finally:
            RUN["running"] = False
        self.report(report.report_level(track),
                    report.finish_run(context, track, run.clip, run.record))
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        if not self._prepare(context):
            return {"CANCELLED"}
        RUN.update(running=True, fraction=0.0, cancel=False, outcome=None, thread=None,
                   tick=time.monotonic())
        run = self._job
        self._worker = background.Worker(
            lambda progress: estimate_run.run(run.scene, run.camera, run.clip.filepath,
                                              run.clip.frame_start, run.frames, run.options,
                                              progress, run.frame_cameras))
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        redraw_all()
        return {"RUNNING_MODAL"}

    def _end(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()
        RUN["running"] = False
        if context.workspace:
            context.workspace.status_text_set(None)
        redraw_all()

    def modal(self, context, event):
        if event.type == "ESC" and event.value == "PRESS":
            RUN["cancel"] = True
        if event.type != "TIMER":
            return {"RUNNING_MODAL"} if event.type == "ESC" else {"PASS_THROUGH"}
        RUN["tick"] = time.monotonic()
        pct = int(100 * RUN["fraction"])
        context.window_manager.progress_update(pct)
        if context.workspace:  # the status bar shows the bar and a cancel button
            context.workspace.status_text_set(draw_status_progress)
        redraw_all()
        if self._worker.alive():
            return {"PASS_THROUGH"}
        self._end(context)
        error = self._worker.error
        stopped = isinstance(error, errors.Cancelled)
        if error is not None and not stopped:
            RUN["outcome"] = f"failed: {type(error).__name__}: {error}"
            self.report({"ERROR"}, f"Estimate failed: {error}")
            context.scene.sunlapse.last_report = f"Estimate failed: {error}"
            return {"CANCELLED"}
        if stopped or RUN["cancel"]:
            # stopped: the worker saw the cancel and gave up; else it had
            # finished already and its result is dropped.
            RUN["outcome"] = "cancelled" if stopped else "cancelled after the run ended"
            self.report({"INFO"}, "Estimate cancelled; nothing was changed")
            return {"CANCELLED"}
        RUN["outcome"] = "finished"
        track = self._worker.result
        self.report(report.report_level(track),
                    report.finish_run(context, track, self._job.clip, self._job.record))
        return {"FINISHED"}

    def cancel(self, context):  # Blender closes the window / file
        background.file_closed()
        self._end(context)


class CLIP_OT_sunlapse_show_text(bpy.types.Operator):
    """Read the whole message"""
    bl_idname = "clip.sunlapse_show_text"
    bl_label = "sunlapse Message"
    bl_options = {"INTERNAL"}

    text: bpy.props.StringProperty()

    def invoke(self, context, event):
        return context.window_manager.invoke_popup(self, width=520)

    def draw(self, context):
        wrapped(self.layout, context, self.text, max_lines=60, width_px=500)

    def execute(self, context):
        print(f"sunlapse: {self.text}")  # from a script: to the console
        return {"FINISHED"}


class CLIP_OT_sunlapse_notice(bpy.types.Operator):
    """Shows a message in the status bar (what happened to a run whose file
    was closed; only operators can report)"""
    bl_idname = "clip.sunlapse_notice"
    bl_label = "sunlapse Notice"
    bl_options = {"INTERNAL"}

    message: bpy.props.StringProperty()

    def execute(self, context):
        self.report({"WARNING"}, self.message)
        return {"FINISHED"}


class CLIP_OT_sunlapse_apply_lamp(bpy.types.Operator):
    """Keyframe the Sun lamp (created if needed) on every estimated frame,
    in its own rotation mode; a second run replaces its own keys only"""
    bl_idname = "clip.sunlapse_apply_lamp"
    bl_label = "Apply to Sun Lamp"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return store.has_track()

    def execute(self, context):
        settings = context.scene.sunlapse
        track = store.load_track()
        if track is None:
            self.report({"ERROR"}, "No Sun track in this file: run Estimate Sun first")
            return {"CANCELLED"}
        try:
            sun = keys.apply_track(context, track, settings.sun_lamp, settings.sync_sky,
                                   settings.keyframe_strength)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        settings.sun_lamp = sun
        keyed = list(sun.get(keys.KEYED_FRAMES_PROP, []))
        sky = keys.sky_node(context.scene) if settings.sync_sky else None
        msg = (f"Keyed '{sun.name}' ({sun.rotation_mode}) on {len(keyed)} frames "
               f"({keyed[0]}-{keyed[-1]})" + (", sky" if sky is not None else "")
               + (", strength" if settings.keyframe_strength else ""))
        dark = track.without_sunlight()
        if dark:
            msg += f"; off on {len(dark)} frame(s) without direct sunlight"
        level = "INFO"
        if settings.sync_sky and sky is None:
            msg += (". Keyframe Sky is on but the world has no Sky Texture node: only the "
                    "lamp was keyed")
            level = "WARNING"
        settings.last_apply = msg
        self.report({level}, msg)
        return {"FINISHED"}


class CLIP_OT_sunlapse_apply_model(bpy.types.Operator):
    """Move, turn and scale the model's objects and turn and zoom the camera
    as the clip refined them (Refine Model); once, undoable"""
    bl_idname = "clip.sunlapse_apply_model"
    bl_label = "Apply Model Corrections"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        track = store.load_track()
        return track is not None and "model_refinement" in track.extra

    def execute(self, context):
        track = store.load_track()
        if track is None:
            self.report({"ERROR"}, "No Sun track in this file: run Estimate Sun first")
            return {"CANCELLED"}
        try:
            said, skipped = model_fix.apply_corrections(context, track)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if skipped:
            self.report({"WARNING"}, f"{said}; left as they are: {'; '.join(skipped)}")
        else:
            self.report({"INFO"}, said)
        return {"FINISHED"}


class CLIP_OT_sunlapse_export(bpy.types.Operator, ExportHelper):
    """Export the Sun track (sunlapse JSON or CSV) or the animated Sun lamp (glTF)"""
    bl_idname = "clip.sunlapse_export"
    bl_label = "Export Sun"
    bl_options = {"REGISTER"}

    filename_ext = ".sun.json"
    filter_glob: StringProperty(default="*.json;*.csv;*.glb", options={"HIDDEN"})
    format: EnumProperty(
        name="Format",
        items=[("JSON", "Track (.sun.json)", "sunlapse track file"),
               ("CSV", "CSV (.csv)", "frame, zenith_deg, azimuth_deg, confidence"),
               ("GLB", "Sun lamp (.glb)", "the animated Sun lamp as glTF binary")],
        default="JSON")

    def check(self, context):
        # Not ExportHelper's: it takes only the last dot's part for the
        # extension, and .sun.json grew with every format switch.
        self.filename_ext = export.EXTENSIONS[self.format]
        fixed = export.file_name(self.filepath, self.format)
        changed = fixed != self.filepath
        self.filepath = fixed
        return changed

    def execute(self, context):
        track = store.load_track()
        if track is None:
            self.report({"ERROR"}, "No Sun track in this file: run Estimate Sun first")
            return {"CANCELLED"}
        path = bpy.path.abspath(self.filepath)
        try:
            if self.format == "JSON":
                trackfile.write_track(path, track)
            elif self.format == "CSV":
                export.export_csv(track, path)
            else:
                export.export_gltf(context, context.scene.sunlapse.sun_lamp, path)
        except (OSError, ValueError, RuntimeError) as e:
            self.report({"ERROR"}, f"Export failed: {e}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Wrote {path}")
        return {"FINISHED"}


class CLIP_OT_sunlapse_setup_ar(bpy.types.Operator):
    """Set up an AR render: Cycles, the model as shadow catcher, transparent
    film, the render composited over the clip (shadows by the Shadow Catcher
    pass), the lamp and sky lit as the footage's shadows show, and the 3D
    Views previewing the composite through the camera"""
    bl_idname = "clip.sunlapse_setup_ar"
    bl_label = "Set Up AR Render"
    bl_options = {"REGISTER", "UNDO"}

    add_sample_object: bpy.props.BoolProperty(
        name="Add Sample Object", default=True,
        description="Drop a sample virtual object on the ground in view")
    match_shadows: bpy.props.BoolProperty(
        name="Match Shadows", default=True,
        description="Render the model's own shadows once, small, and correct the light so "
                    "that they come out as dark as the footage's (a few seconds)")

    def execute(self, context):
        wm = context.window_manager
        workspace = context.workspace

        def progress(fraction, text):
            # It blocks for seconds (the check render): the cursor's counter
            # moves at once; the status bar says the step at its next redraw.
            wm.progress_update(int(100 * fraction))
            if workspace is not None and not bpy.app.background:
                workspace.status_text_set(text)
        warnings, details = [], []
        wm.progress_begin(0, 100)
        try:
            note = ar.setup(context, add_sample_object=self.add_sample_object, warnings=warnings,
                            match_shadows=self.match_shadows, details=details,
                            progress=progress)
        except (gather.SceneError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        finally:
            wm.progress_end()
            if workspace is not None:
                workspace.status_text_set(None)
        self.report({"INFO"}, note)
        for line in details:  # the figures, in the Info log
            self.report({"INFO"}, line)
        for w in warnings:
            self.report({"WARNING"}, w)
        return {"FINISHED"}


class CLIP_OT_sunlapse_to_sun_position(bpy.types.Operator):
    """Write the place, the current frame's date and time and the north
    offset to Blender's Sun Position add-on (its lamp and sky then agree
    with the estimate on this frame)"""
    bl_idname = "clip.sunlapse_to_sun_position"
    bl_label = "Write to Sun Position"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return getattr(context.scene, "sun_pos_properties", None) is not None

    def execute(self, context):
        import math
        scene = context.scene
        sp = getattr(scene, "sun_pos_properties", None)
        if sp is None:
            self.report({"ERROR"}, "The Sun Position add-on is not enabled (Preferences › "
                                   "Add-ons › Lighting: Sun Position)")
            return {"CANCELLED"}
        settings = scene.sunlapse
        track = store.load_track()
        fit = track.extra.get("sun_path_fit") if track is not None else None
        lat = fit["latitude_deg"] if fit else settings.latitude
        lon = fit["longitude_deg"] if fit else settings.longitude
        written = ["place"]
        sp.latitude, sp.longitude = lat, lon
        if track is not None and track.north_known():
            sp.north_offset = math.radians(angles.wrap_signed_deg(track.north_offset_deg))
            written.append("north")
        try:
            when = report.frame_time_utc(settings, track, scene.frame_current)
            tz = place.settings_zone(settings)
        except gather.SceneError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if when is not None:
            if fit and fit.get("time_offset_s"):
                when += dt.timedelta(seconds=fit["time_offset_s"])
            local = when.astimezone(tz)
            sp.use_daylight_savings = False  # the zone's offset already includes it
            sp.UTC_zone = clock.utc_offset_hours(tz, when)
            sp.year, sp.month, sp.day = local.year, local.month, local.day
            sp.time = (local.hour + local.minute / 60
                       + (local.second + local.microsecond * 1e-6) / 3600)
            written.append(f"{local:%Y-%m-%d %H:%M:%S} UTC{sp.UTC_zone:+g}")
        self.report({"INFO"}, f"Sun Position: {', '.join(written)} (lat {lat:.4f}, lon {lon:.4f})"
                    + ("" if when is not None else "; no time known for this frame (Frame "
                                                   "Times, EXIF or Date and Seconds per Frame)"))
        return {"FINISHED"}


class CLIP_OT_sunlapse_solve_camera(bpy.types.Operator):
    """Match the camera to the clip from tracking markers on the current frame
    whose track names give their ground coordinates in metres ("foot 0 0",
    "corner 2.5 1.2"): focal length and pose (OpenCV), reprojection error"""
    bl_idname = "clip.sunlapse_solve_camera"
    bl_label = "Solve Camera from Marked Points"
    bl_options = {"REGISTER", "UNDO"}

    focal_mm: bpy.props.FloatProperty(
        name="Focal Length", default=0.0, min=0.0, unit="CAMERA",
        description="Known focal length (with a 36 mm sensor); 0: estimate it")

    def execute(self, context):
        scene = context.scene
        clip = gather.active_movieclip(context)
        if clip is None:
            self.report({"ERROR"}, "No clip: open the footage in the Movie Clip Editor")
            return {"CANCELLED"}
        frame = scene.frame_current - clip.frame_start + 1
        points, skipped = gather.marked_points(clip, frame)
        w, h = clip.size
        try:
            native = native_loader.require()
            import numpy as np
            world = np.array([p[1] for p in points], dtype=np.float64).reshape(-1, 3)
            pixels = np.array([p[2] for p in points], dtype=np.float64).reshape(-1, 2)
            side = w if w >= h else h  # AUTO sensor fit: the larger side
            focal_px = self.focal_mm * side / 36.0 if self.focal_mm > 0 else 0.0
            r = native.solve_camera(world, pixels, w, h, focal_px)
        except (RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        if r.status != native.CameraSolveStatus.SUCCESS:
            extra = (f" (tracks without coordinates in their names: {', '.join(skipped)})"
                     if skipped else "")
            msg = r.message + extra + (
                ". Name each marker's track after the point's ground coordinates in metres, "
                "x y [z]: 'foot 0 0', 'corner 2.5 1.2 0'")
            scene.sunlapse.last_report = f"Solve Camera failed: {msg}"
            self.report({"ERROR"}, msg)
            return {"CANCELLED"}
        cam_obj = scene.sunlapse.camera or scene.camera
        if cam_obj is None:
            cam_obj = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
            scene.collection.objects.link(cam_obj)
            scene.camera = cam_obj
        cam = cam_obj.data
        cam.type = "PERSP"
        cam.sensor_fit = "AUTO"
        cam.sensor_width = 36.0
        cam.shift_x = cam.shift_y = 0.0
        cam.lens = r.focal_px * 36.0 / (w if w >= h else h)
        from mathutils import Matrix
        cam_obj.matrix_world = Matrix([list(row) for row in r.matrix_world])
        # The clip's own tracking camera too, as Blender's solver fills it.
        tc = clip.tracking.camera
        tc.sensor_width = 36.0
        tc.units = "MILLIMETERS"
        tc.focal_length = cam.lens
        scene.render.resolution_x, scene.render.resolution_y = w, h
        scene.render.resolution_percentage = 100
        scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
        worst = max(zip(r.errors_px, [p[0] for p in points]))
        level = "WARNING" if r.message else "INFO"
        msg = (f"Camera solved from {len(points)} points: lens {cam.lens:.1f} mm, reprojection "
               f"{r.rms_px:.2f} px RMS (worst {worst[0]:.2f} px at '{worst[1]}')"
               + (f": {r.message}" if r.message else ""))
        # Kept in the Scene panel, as Blender's Solve panel keeps its error.
        scene.sunlapse.last_report = msg
        self.report({level}, msg)
        return {"FINISHED"}


classes = (CLIP_OT_sunlapse_solve_camera, CLIP_OT_sunlapse_check_scene,
           CLIP_OT_sunlapse_initial_sun, CLIP_OT_sunlapse_estimate, CLIP_OT_sunlapse_cancel,
           CLIP_OT_sunlapse_apply_lamp, CLIP_OT_sunlapse_apply_model, CLIP_OT_sunlapse_export,
           CLIP_OT_sunlapse_setup_ar,
           CLIP_OT_sunlapse_to_sun_position, CLIP_OT_sunlapse_notice,
           CLIP_OT_sunlapse_show_text)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()
    if background.tell_after_load not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(background.tell_after_load)


def unregister():
    RUN.update(running=False, cancel=True)
    if background.tell_after_load in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(background.tell_after_load)
    _unregister()
