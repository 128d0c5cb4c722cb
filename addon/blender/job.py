"""A run's inputs gathered from the Blender scene into one RunJob: the
native scene and camera, the clip, the frames, the estimate's options (with
the frames' capture times and the place and time), and what the track
records about them. bpy reads only, on the main thread."""

from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Tuple

import bpy
import numpy as np

from . import gather
from .place import PlaceTimeFlags, place_and_time, settings_zone
from ..core import camerapath, clock, exif, frametimes
from ..estimate import native_loader
from ..estimate.options import EstimateOptions
from ..estimate.moving_view import NO_POSE


@dataclass
class RunJob:
    """One estimate's inputs, ready for estimate.run (any thread)."""
    scene: Any                 # native Scene
    camera: Any                # native Camera
    clip: gather.ClipInfo
    frames: List[int]          # scene frame numbers
    options: EstimateOptions
    # Recorded in the track's method options (ground, model, times' source).
    record: Dict[str, Any] = field(default_factory=dict)
    # A moving camera: the native camera on each frame (None: no pose there);
    # None for a camera that stays put.
    frame_cameras: Optional[Dict[int, Any]] = None


def ground_names(settings, model=None):
    """The picked Ground object and any more named in Other Ground; with the
    model given, names match its objects whatever their case (raises
    gather.SceneError naming one that matches none)."""
    names = [settings.ground_object.name] if settings.ground_object is not None else []
    names += [n.strip() for n in settings.ground_objects.split(",") if n.strip()]
    if model is None:
        return names
    by_lower = {n.lower(): n for n in model.names}
    out = []
    for n in names:
        match = n if n in model.names else by_lower.get(n.lower())
        if match is None:
            raise gather.SceneError(f"Ground: '{n}' is not an object of the model "
                                    f"(model objects: {', '.join(model.names[:8])}"
                                    f"{' ...' if len(model.names) > 8 else ''})")
        if match not in out:
            out.append(match)
    return out


def gather_all(context, settings=None, movieclip=None, collection=None,
               camera_obj=None, clip=None):
    """Model, camera and clip of the current scene; raises gather.SceneError.
    AR inserts are never part of the model (with Model empty, every visible
    mesh would otherwise count). `clip`: the clip already gathered (each
    gathering loads a frame in Blender and opens the file natively)."""
    settings = settings or context.scene.sunlapse
    clip = clip or gather.gather_clip(context, movieclip)
    clip_obj = movieclip or gather.active_movieclip(context)
    cam = gather.gather_camera(context, camera_obj or settings.camera, clip, clip_obj)
    model = gather.gather_model(context, collection or settings.model_collection,
                                exclude=gather.insert_names())
    return model, cam, clip


def load_frame_times(path, utc_offset_hours, clip, frames, tz=None):
    """{scene frame: aware datetime} for `frames` from a times CSV (its frame
    column counts the clip's frames from 1); raises gather.SceneError.
    With `tz` (a zone with daylight saving), local times are read in it on
    their own date; times with their own offset or in UTC are kept."""
    try:
        table = frametimes.read_times(path, tz or clock.zone("", utc_offset_hours))
        clip_frames = [f - clip.frame_start + 1 for f in range(frames[0], frames[1] + 1)]
        times = frametimes.times_for(table, clip_frames, path)
    except (frametimes.FrameTimesError, clock.ClockError) as e:
        raise gather.SceneError(str(e))
    return {f: t for f, t in zip(range(frames[0], frames[1] + 1), times)}


def exif_times(clip, frames, tz):
    """({scene frame: UTC time} or None, (lat, lon) or None) from the EXIF
    data of an image sequence's frames; raises gather.SceneError for a
    file whose time cannot be read."""
    sequence = native_loader.require().find_image_sequence(clip.filepath)
    if sequence is None:
        return None, None
    paths = [sequence.path(k) for k in range(min(sequence.num_frames, clip.frame_duration))]
    try:
        captures = exif.read_sequence(paths, tz)
    except exif.ExifError as e:
        raise gather.SceneError(f"EXIF times: {e}")
    table = exif.times_by_frame(captures, clip.frame_start)
    if table is not None and not all(f in table for f in range(frames[0], frames[1] + 1)):
        table = None
    return table, exif.place(captures)


def prepare_job(context, settings=None, collection=None, ground=None, frames=None,
                method=None, smoothing=None, times_file=None, utc_offset=None,
                place: Optional[PlaceTimeFlags] = None, warnings=None,
                clip=None) -> RunJob:
    """Everything a run needs, gathered on the main thread (bpy reads only,
    and the panel's place filled from the frames' GPS). `times_file` /
    `utc_offset` override the panel's Frame Times and UTC Offset, `place`
    the place and time (the CLI's flags: place.place_and_time). The
    camera's warnings go to `warnings` (a list) when given, else to
    stdout. `clip`: the clip when the caller gathered it already."""
    settings = settings or context.scene.sunlapse
    native_loader.require()
    model, cam, clip = gather_all(context, settings, collection=collection, clip=clip)
    names = ground or ground_names(settings, model) or gather.guess_ground(model, cam)
    missing = [g for g in names if g not in model.names]
    if missing:
        raise gather.SceneError(f"ground object(s) not in the model: {', '.join(missing)}")
    ids = model.ids_of(names)
    if not ids:
        raise gather.SceneError("no ground found: pick the object the shadows fall on "
                                "(Ground in the Scene panel)")
    if frames is None:
        frames = (clip.frame_start, clip.frame_end)
        if settings.use_frame_range:
            frames = (max(clip.frame_start, settings.frame_start),
                      min(clip.frame_end, settings.frame_end))
    if frames[0] > frames[1]:
        raise gather.SceneError(f"empty frame range {frames[0]}-{frames[1]}")
    camera_obj = settings.camera or context.scene.camera
    moved = gather.camera_motion(context, camera_obj, frames)
    if moved is not None and (method or settings.method) != "default":
        raise gather.SceneError(
            f"The camera '{cam.name}' moves over frames {frames[0]}-{frames[1]} ({moved}): "
            f"the thesis method follows a camera that stays put; use the default method, "
            f"or a Frame Range where the camera does not move")
    options = EstimateOptions(
        method=method or settings.method, smoothing=smoothing or settings.smoothing,
        ignore_top_rows=settings.ignore_top_rows,
        north_offset_deg=gather.scene_north_offset_deg(context), ground_object_ids=ids,
        refine_model=settings.refine_model)
    track_extra = {"ground": names, "model_objects": model.names, "camera": cam.name}
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
        place_and_time(context, settings, options, gps, place)
    elif options.frame_times is not None:
        # The place with the frames' times says which frames are night,
        # whatever the smoothing: the flags', else the GPS fix, else the
        # panel's (0, 0 is its default, not a place anybody films).
        flagged = (place.latitude_deg, place.longitude_deg) if place is not None and \
            place.latitude_deg is not None and place.longitude_deg is not None else None
        known = flagged or gps or ((settings.latitude, settings.longitude)
                                   if (settings.latitude, settings.longitude) != (0.0, 0.0)
                                   else None)
        if known is not None:
            options.latitude_deg, options.longitude_deg = known
    scene, camera = gather.build_scene(model), gather.build_camera(cam)
    doubts = view_doubts(model, cam, scene, camera, names)
    numbers = list(range(frames[0], frames[1] + 1))
    frame_cameras, motion_notes = None, []
    if moved is not None:
        frame_cameras, motion_notes = moving_camera(context, camera_obj, cam, numbers,
                                                    track_extra, moved)
    for w in cam.warnings + gather.ground_doubts(model, names) + doubts + motion_notes:
        if warnings is None:  # scripted runs: on stdout with the run's other warnings
            print(f"sunlapse: warning: {w}")
        else:
            warnings.append(w)
    return RunJob(scene, camera, clip, numbers, options, track_extra, frame_cameras)


def moving_camera(context, obj, cam, frames: List[int], record: Dict[str, Any],
                  moved: str) -> Tuple[Dict[int, Any], List[str]]:
    """({frame: the native camera on it, or why it has none (no solved pose,
    the solve jumping off its path there)}, what the user should hear of
    the solve) for a moving camera; the track records the motion and the
    frames left out."""
    path = gather.camera_path(context, obj, cam, frames)
    unposed = [f for f in frames if path[f] is None]
    if len(unposed) == len(frames):
        raise gather.SceneError(
            f"The camera '{cam.name}' has no solved pose on frames {frames[0]}-{frames[-1]}: "
            f"solve the camera over them (Movie Clip Editor › Solve Camera Motion)")
    posed = [f for f in frames if path[f] is not None]
    matrices = np.array([path[f].params["matrix_world"] for f in posed])
    rotations = matrices[:, :3, :3] / np.linalg.norm(matrices[:, :3, :3], axis=1)[:, None, :]
    jumped = camerapath.solve_jumps(posed, matrices[:, :3, 3], rotations)
    out: Dict[int, Any] = {f: NO_POSE for f in unposed}
    out.update(jumped)
    out.update({f: gather.build_camera(path[f]) for f in posed if f not in jumped})
    record["moving_camera"] = {"motion": moved, "frames_without_pose": unposed,
                               "frames_off_the_solve": sorted(jumped)}
    notes = []
    if unposed:
        notes.append(f"the camera '{cam.name}' has no solved pose on {len(unposed)} frame(s) "
                     f"({_frames_said(unposed)}): they get no estimate of their own")
    if jumped:
        notes.append(f"the camera solve jumps off its path on {len(jumped)} frame(s) "
                     f"({_frames_said(sorted(jumped))}): they are not used (check the tracks "
                     f"there and solve again)")
    solve = gather.camera_solve(context, obj)
    if solve is not None and solve[1]:
        notes.append(solve[0])
    return out, notes


def _frames_said(frames: List[int], most: int = 6) -> str:
    return ", ".join(map(str, frames[:most])) + (" ..." if len(frames) > most else "")


def view_doubts(model, cam, scene, camera, ground: List[str]) -> List[str]:
    """What the camera sees of the model: a SceneError when nothing (a camera
    not matched to the footage, or aimed away), warnings for a ground that
    is out of view or covers little of it (a bollard's top named as the
    ground: the Sun came out 4-9 deg off)."""
    seen = gather.objects_in_view(scene, camera, cam)
    if not seen:
        raise gather.SceneError(
            f"The camera '{cam.name}' sees none of the model ({len(model.names)} objects): "
            f"match it to the footage (Solve Camera, or place it by hand) so that the "
            f"model lies over the objects it stands for")
    out = []
    for name in ground:
        share = sum(seen.get(i, 0.0) for i in model.ids_of([name]))
        if share == 0.0:
            out.append(f"the ground '{name}' is out of the camera's view: the shadows are looked "
                       f"for on a surface the footage does not show (pick the surface they fall "
                       f"on as Ground)")
        elif share < GROUND_MIN_VIEW_SHARE:
            out.append(f"the ground '{name}' covers only {100 * share:.1f}% of the camera's "
                       f"view: the tracked shadows are looked for on it alone (pick the "
                       f"surface the shadows fall on as Ground)")
    return out


# A ground the shadows are followed on covers a fair part of the view: a
# bollard's top or a step covers under 1%, a plaza's paving 30-90%.
GROUND_MIN_VIEW_SHARE = 0.03
