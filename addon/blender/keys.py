"""The track applied to the scene: the Sun lamp keyed with real F-curves
(render farms and `blender -b -a` play them) in the lamp's own rotation
mode, the sky and the lamp's strength keyed with it."""

import math

from . import compat, lamp
from ..core import angles
from ..core.trackfile import Sunlight

KEYED_FRAMES_PROP = "sunlapse_frames"


def _remove_own_keys(obj, paths, frames):
    """Deletes the keyframes sunlapse put on `paths` at `frames`; the user's
    other keys (other frames, other properties) stay."""
    curves = compat.fcurves(obj)
    if curves is None or not frames:
        return
    frames = set(int(f) for f in frames)
    for fc in list(curves):
        if fc.data_path not in paths:
            continue
        for kp in reversed(list(fc.keyframe_points)):
            if int(round(kp.co.x)) in frames:
                fc.keyframe_points.remove(kp, fast=True)
        fc.update()
        if len(fc.keyframe_points) == 0:
            curves.remove(fc)


def _linear(obj, paths):
    for fc in compat.fcurves(obj) or ():
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


def _key_strength(sun, frames, follow_ratio):
    """Lamp strength per frame: off where the frame has no direct sunlight
    (night, twilight, cloud: the sky carries the light); with follow_ratio
    in proportion to the measured sun/ambient ratio elsewhere (the lamp's
    present strength stands for the clip's median ratio, so a passing haze
    or the Sun getting low dims it as in the footage), else the lamp's
    present strength. Returns how many frames were keyed."""
    ratios = sorted(f.sun_ambient_ratio for f in frames if f.sun_ambient_ratio)
    data = sun.data
    _remove_own_keys(data, {"energy"}, data.get(KEYED_FRAMES_PROP, []))
    dark = any(f.sunlight == Sunlight.NO for f in frames)
    follow_ratio = follow_ratio and len(ratios) >= 2
    if not (dark or follow_ratio):
        return 0
    median = ratios[len(ratios) // 2] if follow_ratio else 1.0
    base = data.get("sunlapse_base_energy", data.energy)
    data["sunlapse_base_energy"] = base
    keyed = []
    for f in frames:
        if f.sunlight == Sunlight.NO:
            data.energy = 0.0
        elif follow_ratio and f.sun_ambient_ratio:
            data.energy = base * f.sun_ambient_ratio / median
        elif dark:
            data.energy = base
        else:
            continue
        data.keyframe_insert("energy", frame=f.frame)
        keyed.append(f.frame)
    data.energy = base
    data[KEYED_FRAMES_PROP] = keyed
    return len(keyed)


def apply_track(context, track, sun_obj=None, sync_sky=True, keyframe_strength=False,
                key_strength=True):
    """Keys the Sun lamp (created if needed) on every estimated frame; returns it.

    Running it again replaces its own keys only. The lamp's strength is
    keyed off on frames without direct sunlight, and with keyframe_strength
    follows the measured sun/ambient ratio; without key_strength it is left
    as it is (Set Up AR Render keys it from the footage's light). Frames
    that only extrapolate
    beyond the measured ones are not keyed (Track.extrapolated); frames
    whose Sun is predicted are.
    """
    frames = track.keyable()
    if not frames:
        raise ValueError("the track has no measured frame to apply (run Estimate Sun on "
                         "frames that show the scene)")
    sun = lamp.ensure_sun_lamp(context, sun_obj)
    paths = {"rotation_euler", "rotation_quaternion", "rotation_axis_angle"}
    _remove_own_keys(sun, paths, sun.get(KEYED_FRAMES_PROP, []))
    for f in frames:
        lamp.point_lamp(sun, f.zenith_deg, _azimuth_world(track, f), frame=f.frame)
    sun[KEYED_FRAMES_PROP] = [f.frame for f in frames]
    _linear(sun, paths)
    if key_strength:
        _key_strength(sun, frames, keyframe_strength)
    node = sky_node(context.scene) if sync_sky else None
    if node is not None:
        world = context.scene.world
        sky_paths = {f'nodes["{node.name}"].sun_elevation', f'nodes["{node.name}"].sun_rotation'}
        _remove_own_keys(world.node_tree, sky_paths, world.get(KEYED_FRAMES_PROP, []))
        for f in frames:
            # Cycles 3.x draws the sun at geographical_to_direction(elevation,
            # rotation + 90 deg): rotation = -(world azimuth).
            node.sun_elevation = math.radians(90.0 - f.zenith_deg)
            node.sun_rotation = math.radians(angles.wrap_azimuth_deg(-_azimuth_world(track, f)))
            node.keyframe_insert("sun_elevation", frame=f.frame)
            node.keyframe_insert("sun_rotation", frame=f.frame)
        world[KEYED_FRAMES_PROP] = [f.frame for f in frames]
    context.scene.frame_set(context.scene.frame_current)
    return sun


def _azimuth_world(track, f) -> float:
    return float(angles.azimuth_world_from_geographic(f.azimuth_deg, track.north_offset_deg))
