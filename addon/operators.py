"""Operators. They call bridge/core and _native; errors go to self.report."""

import datetime as dt
import threading
import time

import bpy
from bpy.props import EnumProperty, StringProperty
from bpy_extras.io_utils import ExportHelper

from . import ar, bridge, lamp, results
from .estimate import errors, frames as clip_frames, native_loader, thesis
from .estimate import options as estimate_options, run as estimate_run
from .core import clock, exif, frametimes, trackfile


def ground_names(settings, model=None):
    """The picked Ground object and any more named in Other Ground; with the
    model given, names match its objects whatever their case (raises
    bridge.SceneError naming one that matches none)."""
    names = [settings.ground_object.name] if settings.ground_object is not None else []
    names += [n.strip() for n in settings.ground_objects.split(",") if n.strip()]
    if model is None:
        return names
    by_lower = {n.lower(): n for n in model.names}
    out = []
    for n in names:
        match = n if n in model.names else by_lower.get(n.lower())
        if match is None:
            raise bridge.SceneError(f"Ground: '{n}' is not an object of the model "
                                    f"(model objects: {', '.join(model.names[:8])}"
                                    f"{' ...' if len(model.names) > 8 else ''})")
        if match not in out:
            out.append(match)
    return out


def gather_all(context, settings=None, movieclip=None, collection=None,
               camera_obj=None):
    """Model, camera and clip of the current scene; raises bridge.SceneError.
    AR inserts are never part of the model (with Model empty, every visible
    mesh would otherwise count)."""
    settings = settings or context.scene.sunlapse
    clip = bridge.gather_clip(context, movieclip)
    clip_obj = movieclip or bridge.active_movieclip(context)
    cam = bridge.gather_camera(context, camera_obj or settings.camera, clip, clip_obj)
    model = bridge.gather_model(context, collection or settings.model_collection,
                                exclude=ar.insert_names())
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
        ground = ground_names(settings, model) or bridge.guess_ground(model, cam)
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
            options = estimate_options.EstimateOptions(
                method=settings.method, ignore_top_rows=settings.ignore_top_rows)
            bgr = clip_frames.read_frame(clip.filepath, frame - clip.frame_start)
            init = thesis.estimate_initial(native_scene, native_camera, bgr, options)
        except (bridge.SceneError, errors.EstimateError, RuntimeError, ValueError) as e:
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


def settings_zone(settings):
    """The panel's time zone (IANA name, else the UTC offset) as a tzinfo;
    raises bridge.SceneError for an unknown name."""
    try:
        return clock.zone(settings.time_zone, settings.utc_offset)
    except clock.ClockError as e:
        raise bridge.SceneError(str(e))


def load_frame_times(path, utc_offset_hours, clip, frames, tz=None):
    """{scene frame: aware datetime} for `frames` from a times CSV (its frame
    column counts the clip's frames from 1); raises bridge.SceneError.
    With `tz` (a zone with daylight saving), local times are read in it on
    their own date; times with their own offset or in UTC are kept."""
    try:
        table = frametimes.read_times(path, tz or clock.zone("", utc_offset_hours))
        clip_frames = [f - clip.frame_start + 1 for f in range(frames[0], frames[1] + 1)]
        times = frametimes.times_for(table, clip_frames, path)
    except (frametimes.FrameTimesError, clock.ClockError) as e:
        raise bridge.SceneError(str(e))
    return {f: t for f, t in zip(range(frames[0], frames[1] + 1), times)}


def exif_times(clip, frames, tz):
    """({scene frame: UTC time} or None, (lat, lon) or None) from the EXIF
    data of an image sequence's frames; raises bridge.SceneError for a
    file whose time cannot be read."""
    sequence = native_loader.require().find_image_sequence(clip.filepath)
    if sequence is None:
        return None, None
    paths = [sequence.path(k) for k in range(min(sequence.num_frames, clip.frame_duration))]
    try:
        captures = exif.read_sequence(paths, tz)
    except exif.ExifError as e:
        raise bridge.SceneError(f"EXIF times: {e}")
    table = exif.times_by_frame(captures, clip.frame_start)
    if table is not None and not all(f in table for f in range(frames[0], frames[1] + 1)):
        table = None
    return table, exif.place(captures)


def prepare_run(context, settings=None, collection=None, ground=None, frames=None,
                method=None, smoothing=None, times_file=None, utc_offset=None, warnings=None):
    """Everything a run needs, gathered on the main thread (bpy reads only,
    and the panel's place filled from the frames' GPS).
    Returns (native scene, native camera, clip info, frame numbers, options,
    extra). `times_file` / `utc_offset` override the panel's Frame Times and
    UTC Offset. The camera's warnings go to `warnings` (a list) when given,
    else to stdout."""
    settings = settings or context.scene.sunlapse
    native_loader.require()
    model, cam, clip = gather_all(context, settings, collection=collection)
    names = ground or ground_names(settings, model) or bridge.guess_ground(model, cam)
    missing = [g for g in names if g not in model.names]
    if missing:
        raise bridge.SceneError(f"ground object(s) not in the model: {', '.join(missing)}")
    ids = model.ids_of(names)
    if not ids:
        raise bridge.SceneError("no ground found: pick the object the shadows fall on "
                                "(Ground in the Scene panel)")
    if frames is None:
        frames = (clip.frame_start, clip.frame_end)
        if settings.use_frame_range:
            frames = (max(clip.frame_start, settings.frame_start),
                      min(clip.frame_end, settings.frame_end))
    if frames[0] > frames[1]:
        raise bridge.SceneError(f"empty frame range {frames[0]}-{frames[1]}")
    options = estimate_options.EstimateOptions(
        method=method or settings.method, smoothing=smoothing or settings.smoothing,
        ignore_top_rows=settings.ignore_top_rows,
        north_offset_deg=bridge.scene_north_offset_deg(context), ground_object_ids=ids)
    track_extra = {"ground": names, "model_objects": model.names}
    times_path = times_file if times_file is not None else (
        settings.times_file and bpy.path.abspath(settings.times_file))
    gps = None
    if times_path:
        utc = utc_offset if utc_offset is not None else settings.utc_offset
        tz = settings_zone(settings) if settings.time_zone and utc_offset is None else None
        options.frame_times = load_frame_times(times_path, utc, clip, frames, tz)
        track_extra["times"] = "times file"
    elif clip.source == "SEQUENCE" and settings.use_exif_times:
        table, gps = exif_times(clip, frames, settings_zone(settings))
        if table is not None:
            options.frame_times = table
            track_extra["times"] = "exif"
        if gps is not None:
            settings.latitude, settings.longitude = gps
            track_extra["gps_deg"] = list(gps)
    if options.smoothing == "physical":
        physical_from_settings(context, settings, options)
        if gps is not None:  # the frames' own GPS fix is the place
            options.latitude_deg, options.longitude_deg = gps
    for w in cam.warnings:
        if warnings is None:  # scripted runs: on stdout with the run's other warnings
            print(f"sunlapse: warning: {w}")
        else:
            warnings.append(w)
    scene_n = bridge.build_scene(model)
    camera_n = bridge.build_camera(cam)
    return scene_n, camera_n, clip, list(range(frames[0], frames[1] + 1)), options, track_extra


def physical_from_settings(context, settings, options):
    """Place and time from the panel, or from Blender's Sun Position add-on
    when the panel's date is empty; left unset (the run then falls back to
    two-pass and says so) when neither knows them."""
    sp = getattr(context.scene, "sun_pos_properties", None)
    lat, lon, hours = settings.latitude, settings.longitude, settings.start_hour
    tz = settings_zone(settings)  # the zone, else the UTC offset
    day = None
    if settings.date:
        try:
            day = dt.date.fromisoformat(settings.date)
        except ValueError:
            raise bridge.SceneError(f"Date '{settings.date}' is not YYYY-MM-DD")
    elif sp is not None:
        day = dt.date(sp.year, sp.month, sp.day)
        lat, lon, hours = sp.latitude, sp.longitude, sp.time
        dst = 1.0 if getattr(sp, "use_daylight_savings", False) else 0.0
        tz = clock.zone("", sp.UTC_zone + dst)
    options.fit_latitude = settings.fit_latitude
    if options.frame_times is not None:  # the times file is the clock
        options.latitude_deg, options.longitude_deg = lat, lon
        return
    if day is None or settings.frame_seconds <= 0:
        return
    options.first_time = clock.local_start(day, hours, tz)
    options.frame_seconds = settings.frame_seconds
    options.latitude_deg, options.longitude_deg = lat, lon


def finish_run(context, track, clip, extra):
    """Main thread: keeps the result in the .blend and summarises it."""
    track.clip = clip.filepath
    track.method["options"].update(extra)
    results.store_track(track)
    done = len(track.estimated())
    raw = sum(1 for f in track.frames if f.raw_zenith_deg is not None)
    msg = (f"Sun estimated on {done}/{len(track.frames)} frames "
           f"({raw} measured, the rest from smoothing)")
    # What kept frames from a measurement, in the user's words.
    problems = [p.message for p in track.problems if p.is_warning]
    from collections import Counter
    reasons = Counter(f.reason for f in track.frames if f.raw_zenith_deg is None and f.reason)
    if reasons and track.problem("estimate") is None:
        reason, count = reasons.most_common(1)[0]
        problems.append(f"{count} frame(s): {reason}")
    if problems:
        msg += ": " + "; ".join(problems)
    for hint in (p for p in track.problems if not p.is_warning):  # advisory: not a warning
        msg += ". Note: " + hint.message
    context.scene.sunlapse.last_report = msg
    return msg


def report_level(track):
    """WARNING when frames lack a measurement or a stage had to give up."""
    short = any(f.raw_zenith_deg is None for f in track.frames)
    troubled = any(p.is_warning for p in track.problems)
    return {"WARNING"} if short or troubled else {"INFO"}


# The one Estimate Sun run of this Blender session (a second would race the
# first for the stored track): the panels and the status bar read it.
RUN = {"running": False, "fraction": 0.0, "cancel": False, "outcome": None, "drawn": 0}
# A run whose modal handler has not ticked for this long is taken as ended.
STALE_RUN_S = 10.0


def _redraw_all():
    wm = bpy.context.window_manager
    for win in wm.windows:
        for area in win.screen.areas:
            if area.type in ("CLIP_EDITOR", "VIEW_3D", "STATUSBAR"):
                area.tag_redraw()


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
    """Estimate the Sun on every frame of the clip: initial Sun on the first
    frame, shadow tracking on the rest, then smoothing. Esc cancels"""
    bl_idname = "clip.sunlapse_estimate"
    bl_label = "Estimate Sun"
    bl_options = {"REGISTER", "UNDO"}

    _timer = None

    def _prepare(self, context):
        if RUN["running"] and RUN.get("thread") is not None and \
                time.monotonic() - RUN.get("tick", 0.0) > STALE_RUN_S:
            RUN["running"] = False  # its modal handler is gone (an error): not running
        if RUN["running"]:
            self.report({"ERROR"}, "Estimate Sun is already running: wait for it, or press Esc "
                                   "to cancel it")
            return False
        warnings = []
        try:
            self._job = prepare_run(context, warnings=warnings)
        except (bridge.SceneError, RuntimeError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return False
        for w in warnings:
            self.report({"WARNING"}, w)
        return True

    def execute(self, context):  # synchronous: blender -b, scripts
        if not self._prepare(context):
            return {"CANCELLED"}
        scene_n, camera_n, clip, frames, options, extra = self._job
        RUN.update(running=True, fraction=0.0, cancel=False, thread=None)
        try:
            track = estimate_run.run(scene_n, camera_n, clip.filepath, clip.frame_start, frames,
                                     options)
        except (errors.EstimateError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        finally:
            RUN["running"] = False
        self.report(report_level(track), finish_run(context, track, clip, extra))
        return {"FINISHED"}

    def invoke(self, context, event):
        if bpy.app.background:
            return self.execute(context)
        if not self._prepare(context):
            return {"CANCELLED"}
        RUN.update(running=True, fraction=0.0, cancel=False, outcome=None, thread=None,
                   tick=time.monotonic())
        self._result = None
        self._error = None

        def work():
            scene_n, camera_n, clip, frames, options, _ = self._job

            def progress(fraction):
                RUN["fraction"] = fraction
                return not RUN["cancel"]
            try:
                self._result = estimate_run.run(scene_n, camera_n, clip.filepath,
                                                clip.frame_start, frames, options, progress)
            except Exception as e:  # reported on the main thread
                self._error = e

        self._thread = threading.Thread(target=work, name="sunlapse-estimate", daemon=True)
        self._thread.start()
        RUN["thread"] = self._thread
        wm = context.window_manager
        wm.progress_begin(0, 100)
        self._timer = wm.event_timer_add(0.1, window=context.window)
        wm.modal_handler_add(self)
        _redraw_all()
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
        _redraw_all()

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
        _redraw_all()
        if self._thread.is_alive():
            return {"PASS_THROUGH"}
        self._end(context)
        stopped = isinstance(self._error, errors.Cancelled)
        if self._error is not None and not stopped:
            RUN["outcome"] = f"failed: {type(self._error).__name__}: {self._error}"
            self.report({"ERROR"}, f"Estimate failed: {self._error}")
            context.scene.sunlapse.last_report = f"Estimate failed: {self._error}"
            return {"CANCELLED"}
        if stopped or RUN["cancel"]:
            # stopped: the worker saw the cancel and gave up; else it had
            # finished already and its result is dropped.
            RUN["outcome"] = "cancelled" if stopped else "cancelled after the run ended"
            self.report({"INFO"}, "Estimate cancelled; nothing was changed")
            return {"CANCELLED"}
        _, _, clip, _, _, extra = self._job
        RUN["outcome"] = "finished"
        self.report(report_level(self._result), finish_run(context, self._result, clip, extra))
        return {"FINISHED"}

    def cancel(self, context):  # Blender closes the window / file
        RUN["cancel"] = True
        self._end(context)


class CLIP_OT_sunlapse_apply_lamp(bpy.types.Operator):
    """Keyframe the Sun lamp (created if needed) on every estimated frame,
    in its own rotation mode; a second run replaces its own keys only"""
    bl_idname = "clip.sunlapse_apply_lamp"
    bl_label = "Apply to Sun Lamp"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return results.TEXT_NAME in bpy.data.texts

    def execute(self, context):
        settings = context.scene.sunlapse
        track = results.load_track()
        if track is None:
            self.report({"ERROR"}, "No Sun track in this file: run Estimate Sun first")
            return {"CANCELLED"}
        try:
            sun = results.apply_track(context, track, settings.sun_lamp, settings.sync_sky,
                                      settings.keyframe_strength)
        except ValueError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        settings.sun_lamp = sun
        n = len(track.estimated())
        frames = [f.frame for f in track.estimated()]
        msg = (f"Keyed '{sun.name}' ({sun.rotation_mode}) on {n} frames "
               f"({frames[0]}-{frames[-1]})" + (", sky" if settings.sync_sky and results.sky_node(
                   context.scene) is not None else "") +
               (", strength" if settings.keyframe_strength else ""))
        settings.last_apply = msg
        self.report({"INFO"}, msg)
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
        self.filename_ext = {"JSON": ".sun.json", "CSV": ".csv", "GLB": ".glb"}[self.format]
        return super().check(context)

    def execute(self, context):
        track = results.load_track()
        if track is None:
            self.report({"ERROR"}, "No Sun track in this file: run Estimate Sun first")
            return {"CANCELLED"}
        path = bpy.path.abspath(self.filepath)
        try:
            if self.format == "JSON":
                trackfile.write_track(path, track)
            elif self.format == "CSV":
                results.export_csv(track, path)
            else:
                results.export_gltf(context, context.scene.sunlapse.sun_lamp, path)
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
        try:
            warnings = []
            note = ar.setup(context, add_sample_object=self.add_sample_object, warnings=warnings,
                            match_shadows=self.match_shadows)
        except (bridge.SceneError, ValueError) as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, note)
        for w in warnings:
            self.report({"WARNING"}, w)
        return {"FINISHED"}


def frame_time_utc(settings, track, frame):
    """The capture time (aware UTC) of `frame`: the track's own (times file,
    EXIF) or the panel's date, start time and seconds per frame; None."""
    est = track.frame(frame) if track is not None else None
    if est is not None and est.time_utc:
        return dt.datetime.fromisoformat(est.time_utc)
    if not settings.date or settings.frame_seconds <= 0:
        return None
    try:
        day = dt.date.fromisoformat(settings.date)
    except ValueError:
        return None
    first = track.frames[0].frame if track is not None and track.frames else frame
    start = clock.local_start(day, settings.start_hour, settings_zone(settings))
    return (start + dt.timedelta(seconds=settings.frame_seconds * (frame - first))).astimezone(
        dt.timezone.utc)


def north_offset_known(track):
    """How the track's azimuths relate to north: 'fitted' (physical
    smoothing found north), 'given' (the Sun Position add-on's), or None
    (azimuths are relative to the scene's +Y)."""
    if track is None:
        return None
    if track.extra.get("sun_path_fit"):
        return "fitted"
    if track.north_offset_deg:
        return "given"
    return None


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
        track = results.load_track()
        fit = track.extra.get("sun_path_fit") if track is not None else None
        lat = fit["latitude_deg"] if fit else settings.latitude
        lon = fit["longitude_deg"] if fit else settings.longitude
        written = ["place"]
        sp.latitude, sp.longitude = lat, lon
        if track is not None and north_offset_known(track):
            sp.north_offset = math.radians(((track.north_offset_deg + 180.0) % 360.0) - 180.0)
            written.append("north")
        try:
            when = frame_time_utc(settings, track, scene.frame_current)
            tz = settings_zone(settings)
        except bridge.SceneError as e:
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


def marked_points(clip, frame):
    """(name, ground xyz, OpenCV pixel) of every track with a marker on
    `frame` whose name ends with its ground coordinates ("foot 0 0",
    "3.2,-1.5", "x y z"); tracks without numbers are listed apart."""
    import re

    def numbers(name):  # whole tokens only: "p0 1 2" is the point (1, 2)
        out = []
        for token in re.split(r"[\s,;]+", name):
            try:
                out.append(float(token))
            except ValueError:
                pass
        return out
    w, h = clip.size
    points, skipped = [], []
    for track in clip.tracking.tracks:
        marker = track.markers.find_frame(frame)
        nums = numbers(track.name)
        if marker is None or marker.mute:
            continue
        if len(nums) < 2:
            skipped.append(track.name)
            continue
        xyz = (nums[-3], nums[-2], nums[-1]) if len(nums) >= 3 else (nums[-2], nums[-1], 0.0)
        # Marker positions are 0..1 from the frame's bottom-left corner.
        px = (marker.co[0] * w - 0.5, (1.0 - marker.co[1]) * h - 0.5)
        points.append((track.name, xyz, px))
    return points, skipped


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
        clip = bridge.active_movieclip(context)
        if clip is None:
            self.report({"ERROR"}, "No clip: open the footage in the Movie Clip Editor")
            return {"CANCELLED"}
        frame = scene.frame_current - clip.frame_start + 1
        points, skipped = marked_points(clip, frame)
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
        if not r["success"]:
            extra = (f" (tracks without coordinates in their names: {', '.join(skipped)})"
                     if skipped else "")
            self.report({"ERROR"}, r["message"] + extra)
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
        cam.lens = r["focal_px"] * 36.0 / (w if w >= h else h)
        from mathutils import Matrix
        cam_obj.matrix_world = Matrix([list(row) for row in r["matrix_world"]])
        # The clip's own tracking camera too, as Blender's solver fills it.
        tc = clip.tracking.camera
        tc.sensor_width = 36.0
        tc.units = "MILLIMETERS"
        tc.focal_length = cam.lens
        scene.render.resolution_x, scene.render.resolution_y = w, h
        scene.render.resolution_percentage = 100
        scene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1.0
        worst = max(zip(r["errors_px"], [p[0] for p in points]))
        level = "WARNING" if r["message"] else "INFO"
        self.report({level}, f"Camera solved from {len(points)} points: lens {cam.lens:.1f} mm, "
                             f"reprojection {r['rms_px']:.2f} px RMS (worst {worst[0]:.2f} px at "
                             f"'{worst[1]}')" + (f": {r['message']}" if r["message"] else ""))
        return {"FINISHED"}


classes = (CLIP_OT_sunlapse_solve_camera, CLIP_OT_sunlapse_check_scene,
           CLIP_OT_sunlapse_initial_sun, CLIP_OT_sunlapse_estimate, CLIP_OT_sunlapse_cancel,
           CLIP_OT_sunlapse_apply_lamp, CLIP_OT_sunlapse_export, CLIP_OT_sunlapse_setup_ar,
           CLIP_OT_sunlapse_to_sun_position)
_register, _unregister = bpy.utils.register_classes_factory(classes)


def register():
    _register()


def unregister():
    RUN.update(running=False, cancel=True)
    _unregister()
