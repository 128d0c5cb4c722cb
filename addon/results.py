"""What a run leaves in the .blend, and applying it to the scene (bpy side).

The track is kept in a Text datablock, so it is saved with the file and
survives reopening; the Sun lamp gets real F-curves (render farms and
`blender -b -a` play them), keyed in the lamp's own rotation mode.
"""

import csv
import json
import math
import os

import bpy

from . import lamp
from .core import trackfile

TEXT_NAME = "sunlapse.sun.json"
KEYED_FRAMES_PROP = "sunlapse_frames"


def store_track(track: trackfile.Track) -> bpy.types.Text:
    text = bpy.data.texts.get(TEXT_NAME) or bpy.data.texts.new(TEXT_NAME)
    text.clear()
    text.write(json.dumps(trackfile.to_json(track), indent=1))
    from . import overlay
    overlay.invalidate()
    return text


def load_track():
    """The track stored in this .blend, or None."""
    text = bpy.data.texts.get(TEXT_NAME)
    if text is None:
        return None
    try:
        # Validated once here (trackfile.loads): the panel, overlay, Apply and
        # Export may trust what they get. A track edited into nonsense in the
        # Text Editor reads as no track.
        return trackfile.loads(text.as_string(), source=TEXT_NAME)
    except trackfile.TrackFileError as e:
        print(f"sunlapse: warning: the stored track is unusable: {e}")
        return None


def _remove_own_keys(obj, paths, frames):
    """Deletes the keyframes sunlapse put on `paths` at `frames`; the user's
    other keys (other frames, other properties) stay."""
    ad = obj.animation_data
    if not ad or not ad.action or not frames:
        return
    frames = set(int(f) for f in frames)
    for fc in list(ad.action.fcurves):
        if fc.data_path not in paths:
            continue
        for kp in reversed(list(fc.keyframe_points)):
            if int(round(kp.co.x)) in frames:
                fc.keyframe_points.remove(kp, fast=True)
        fc.update()
        if len(fc.keyframe_points) == 0:
            ad.action.fcurves.remove(fc)


def _linear(obj, paths):
    for fc in obj.animation_data.action.fcurves:
        if fc.data_path in paths:
            for kp in fc.keyframe_points:
                kp.interpolation = "LINEAR"


def sky_node(scene):
    """The scene's Nishita Sky Texture node, if its world uses one."""
    world = scene.world
    if world is None or not world.use_nodes:
        return None
    for node in world.node_tree.nodes:
        if node.type == "TEX_SKY" and node.sky_type == "NISHITA":
            return node
    return None


def _key_strength(sun, frames):
    """Lamp strength per frame in proportion to the measured sun/ambient
    ratio: the lamp's present strength stands for the clip's median ratio, so
    a passing haze or the Sun getting low dims it as in the footage."""
    ratios = [f.sun_ambient_ratio for f in frames if f.sun_ambient_ratio]
    data = sun.data
    _remove_own_keys(data, {"energy"}, data.get(KEYED_FRAMES_PROP, []))
    if len(ratios) < 2:
        return 0
    ratios_sorted = sorted(ratios)
    median = ratios_sorted[len(ratios_sorted) // 2]
    base = data.get("sunlapse_base_energy", data.energy)
    data["sunlapse_base_energy"] = base
    keyed = []
    for f in frames:
        if f.sun_ambient_ratio:
            data.energy = base * f.sun_ambient_ratio / median
            data.keyframe_insert("energy", frame=f.frame)
            keyed.append(f.frame)
    data.energy = base
    data[KEYED_FRAMES_PROP] = keyed
    return len(keyed)


def apply_track(context, track, sun_obj=None, sync_sky=True, keyframe_strength=False):
    """Keys the Sun lamp (created if needed) on every estimated frame; returns it.

    Running it again replaces its own keys only. With keyframe_strength the
    lamp's strength follows the measured sun/ambient ratio. Frames that only
    extrapolate beyond the measured ones are not keyed (Track.extrapolated).
    """
    frames = track.keyable()
    if not frames:
        raise ValueError("the track has no measured frame to apply (run Estimate Sun on "
                         "frames that show the scene)")
    sun = lamp.ensure_sun_lamp(context, sun_obj)
    paths = {"rotation_euler", "rotation_quaternion", "rotation_axis_angle"}
    _remove_own_keys(sun, paths, sun.get(KEYED_FRAMES_PROP, []))
    for f in frames:
        lamp.point_lamp(sun, f.zenith_deg, f.azimuth_deg + track.north_offset_deg, frame=f.frame)
    sun[KEYED_FRAMES_PROP] = [f.frame for f in frames]
    _linear(sun, paths)
    if keyframe_strength:
        _key_strength(sun, frames)
    node = sky_node(context.scene) if sync_sky else None
    if node is not None:
        world = context.scene.world
        sky_paths = {f'nodes["{node.name}"].sun_elevation', f'nodes["{node.name}"].sun_rotation'}
        _remove_own_keys(world.node_tree, sky_paths, world.get(KEYED_FRAMES_PROP, []))
        for f in frames:
            # Cycles 3.x draws the sun at geographical_to_direction(elevation,
            # rotation + 90 deg): rotation = -(world azimuth).
            node.sun_elevation = math.radians(90.0 - f.zenith_deg)
            node.sun_rotation = (math.radians(-(f.azimuth_deg + track.north_offset_deg))
                                 % (2 * math.pi))
            node.keyframe_insert("sun_elevation", frame=f.frame)
            node.keyframe_insert("sun_rotation", frame=f.frame)
        world[KEYED_FRAMES_PROP] = [f.frame for f in frames]
    context.scene.frame_set(context.scene.frame_current)
    return sun


def export_csv(track, path):
    """frame, zenith_deg, azimuth_deg, confidence (one row per frame),
    written atomically (a temporary file in the same folder, renamed)."""
    import io
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(["frame", "zenith_deg", "azimuth_deg", "confidence"])
    for f in track.frames:
        w.writerow([f.frame,
                    "" if f.zenith_deg is None else f"{f.zenith_deg:.6f}",
                    "" if f.azimuth_deg is None else f"{f.azimuth_deg:.6f}",
                    f"{f.confidence:.4f}"])
    trackfile.write_text_atomic(path, buf.getvalue(), suffix=".csv", newline="")


def export_gltf(context, sun_obj, path):
    """The animated Sun lamp as glTF binary (.glb). Blender's bundled glTF
    exporter writes a light as a KHR_lights_punctual node and its rotation
    F-curves as node animation, which other tools (three.js, Unity, Unreal,
    Godot, Blender) read; FBX would also keep it, but glTF is the open one."""
    if sun_obj is None:
        raise ValueError("no Sun lamp to export: apply the track to a lamp first")
    view_layer = context.view_layer
    previous = [o for o in view_layer.objects if o.select_get()]
    active = view_layer.objects.active
    try:
        for o in previous:
            o.select_set(False)
        sun_obj.select_set(True)
        view_layer.objects.active = sun_obj
        # Through a temporary file in the same folder, renamed: a failed
        # export leaves an existing file as it was.
        import uuid
        tmp = os.path.join(os.path.dirname(os.path.abspath(path)),
                           f".sunlapse-{uuid.uuid4().hex}.glb")
        kwargs = dict(filepath=tmp, export_format="GLB", use_selection=True,
                      export_animations=True, export_force_sampling=True)
        # The option that turns lights on was renamed across Blender versions.
        props = bpy.ops.export_scene.gltf.get_rna_type().properties
        for name in ("export_lights", "export_punctual_lights"):
            if name in props:
                kwargs[name] = True
        try:
            result = bpy.ops.export_scene.gltf(**kwargs)
            if result == {"FINISHED"} and os.path.exists(tmp):
                os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    finally:
        sun_obj.select_set(False)
        for o in previous:
            o.select_set(True)
        view_layer.objects.active = active
    if result != {"FINISHED"}:
        raise RuntimeError(f"glTF export failed: {result}")
