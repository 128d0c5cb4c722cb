"""Renders a time-lapse with a known Sun: the project's ground truth.

  blender -b --factory-startup --python examples/generate_scene.py -- \
      --preset plaza --out DIR [--tiny] [--frames N] [--resolution WxH] [--samples S]
      [--minutes-per-frame M]
  blender -b --factory-startup --python examples/generate_scene.py -- \
      --random KEY --out DIR [--tiny] [--frames N] [--resolution WxH] [--samples S]
      [--spec-only] [--still-camera]

--random builds a scene of the randomised suite (bench/suite.py): KEY is an
integer seed or a fixed member (the plaza of issue 14); examples/random_scene.py
draws it (place, date, hours, north offset, camera, casters, ground, clutter,
clouds, exposure drift, shake, noise, compression, or a room lit through a
window; for the kinds of random_scene.PREFIXES also twilight, a rough
model, an overcast run, buildings, several days with their nights, trees)
and it is written to DIR/spec.json too. Its defaults are the suite's: 32
frames at 320x180 (48 for multi-day members). --still-camera renders a
moving member (moving<seed>) with its camera held at the drawn view: the
same scene shot from a tripod (bench/moving_run.py's baseline).

Writes into DIR:
  clip.mp4          the footage (Cycles, few samples, no denoising, H.264)
  truth.sun.json    per-frame Sun in the track-file shape ("sunlapse.truth")
  scene.blend       what a user would have: the coarse model in a collection
                    "Model", the matched camera, the clip as a MovieClip; no
                    lamp, none of the footage-only objects; for a rough-model
                    member (rough<seed>) the model and camera as a user
                    models them by hand, off the true ones
  scene_true.blend  rough-model members only: the same with the true model
  masks/mask_NNNN.png   ground-truth cast-shadow masks on the ground for a few
                    frames (255 = ground in shadow, 0 = elsewhere)
  render.blend      the full render scene, for inspection and truth checks

For random scenes the footage also has what the user's scene does not: the
camera shakes, the exposure drifts and clouds dim the Sun, an overcast run
turns the lamp off and the sky grey, trees cast dappled shadows (all in
render.blend, none in scene.blend, where the camera is at rest), and the
truth's extra.random_scene holds the spec.

The Sun is a Sun lamp of the real angular size (0.545 deg) whose direction on
every frame comes from the ephemeris (_native.sun_position) at the preset's
place and local times; a Nishita sky follows the same Sun.
"""

import argparse
import datetime as dt
import json
import math
import os
import shutil
import subprocess
import sys

import bpy
from mathutils import Euler, Quaternion, Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import random_scene  # noqa: E402
import run_estimate  # noqa: E402

run_estimate.load_sunlapse()
from sunlapse.estimate import native_loader  # noqa: E402
from sunlapse.core import trackfile  # noqa: E402

SUN_ANGULAR_DIAMETER_DEG = 0.545
# Sun lamp irradiance (W/m^2 in Blender's units).
SUN_STRENGTH = 4.0
# The sky's Background strength (skylight only: the lamp is the Sun).
SKY_STRENGTH = 0.12

# Each preset differs in place (both hemispheres), season, time of day (high
# and low Sun), north offset, camera height and angle, ground texture and the
# footage-only objects. minutes_per_frame keeps the Sun's motion well under
# 1 deg per frame.
PRESETS = {
    "plaza": dict(
        description="Paris, midsummer morning, high Sun; paving; camera 9 m up",
        lat=48.853, lon=2.349, utc_offset_h=2, date=(2025, 6, 21), start=(9, 30),
        minutes_per_frame=2.0, frames=90, north_offset_deg=0.0,
        camera=dict(height=9.0, distance=13.0, yaw_deg=200.0, lens=28.0),
        ground="paving", layout="plaza"),
    "southern_winter": dict(
        description="Sydney, June afternoon, low Sun; asphalt; camera 4 m up, shallow",
        lat=-33.87, lon=151.21, utc_offset_h=10, date=(2025, 6, 15), start=(13, 0),
        minutes_per_frame=1.5, frames=90, north_offset_deg=35.0,
        camera=dict(height=4.0, distance=12.0, yaw_deg=160.0, lens=24.0),
        ground="asphalt", layout="yard"),
    "tropic_noon": dict(
        description="Nairobi, March late morning, Sun near zenith; dirt and grass; "
                    "camera 15 m up, steep",
        lat=-1.29, lon=36.82, utc_offset_h=3, date=(2025, 3, 3), start=(10, 0),
        minutes_per_frame=1.5, frames=90, north_offset_deg=-60.0,
        camera=dict(height=15.0, distance=7.0, yaw_deg=30.0, lens=30.0),
        ground="grass", layout="street"),
    "nordic_autumn": dict(
        description="Oslo, October midday, low Sun; cobbles; camera 6 m up",
        lat=59.91, lon=10.75, utc_offset_h=2, date=(2025, 10, 8), start=(11, 0),
        minutes_per_frame=2.0, frames=90, north_offset_deg=120.0,
        camera=dict(height=6.0, distance=11.0, yaw_deg=300.0, lens=28.0),
        ground="cobbles", layout="plaza"),
    "indoor_window": dict(
        description="Madrid, November afternoon, a room lit through a window",
        lat=40.42, lon=-3.70, utc_offset_h=1, date=(2025, 11, 5), start=(13, 0),
        minutes_per_frame=1.5, frames=90, north_offset_deg=15.0,
        camera=dict(height=2.3, distance=0.0, yaw_deg=0.0, lens=18.0),
        ground="wood", layout="room", exposure=1.5, sample_factor=2),
}


# ---------------------------------------------------------------------------
# Materials

def _principled(name, color, roughness=0.8):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    bsdf = mat.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*color, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Specular"].default_value = 0.2
    return mat


def ground_material(kind, roughness=0.9, specular=0.2):
    """Procedural ground textures that look like real surfaces. A rough
    Principled BSDF is brighter at grazing views (far from the camera), as
    real ground is; a Lambertian ground would be flat."""
    mat = _principled(f"ground_{kind}", (0.3, 0.3, 0.3), roughness=roughness)
    nt = mat.node_tree
    bsdf = nt.nodes["Principled BSDF"]
    bsdf.inputs["Specular"].default_value = specular
    coord = nt.nodes.new("ShaderNodeTexCoord")
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 3.0
    noise.inputs["Detail"].default_value = 8.0
    nt.links.new(coord.outputs["Object"], noise.inputs["Vector"])
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    nt.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    palette = {
        "paving": ((0.32, 0.30, 0.27), (0.45, 0.42, 0.38)),
        "asphalt": ((0.08, 0.08, 0.085), (0.16, 0.16, 0.16)),
        "grass": ((0.10, 0.16, 0.05), (0.30, 0.24, 0.15)),
        "cobbles": ((0.22, 0.21, 0.20), (0.38, 0.36, 0.33)),
        "wood": ((0.30, 0.18, 0.09), (0.45, 0.30, 0.16)),
    }[kind]
    ramp.color_ramp.elements[0].color = (*palette[0], 1)
    ramp.color_ramp.elements[1].color = (*palette[1], 1)
    color = ramp.outputs["Color"]
    if kind in ("paving", "cobbles", "wood"):
        # Joints between slabs / stones / boards.
        if kind == "wood":
            pattern = nt.nodes.new("ShaderNodeTexWave")
            pattern.inputs["Scale"].default_value = 2.0
            pattern.inputs["Distortion"].default_value = 4.0
            fac = pattern.outputs["Fac"]
        else:
            pattern = nt.nodes.new("ShaderNodeTexBrick")
            pattern.inputs["Scale"].default_value = 1.2 if kind == "paving" else 4.0
            pattern.inputs["Mortar Size"].default_value = 0.015
            pattern.inputs["Color1"].default_value = (1, 1, 1, 1)
            pattern.inputs["Color2"].default_value = (0.8, 0.8, 0.8, 1)
            pattern.inputs["Mortar"].default_value = (0.45, 0.45, 0.45, 1)
            fac = pattern.outputs["Color"]
        nt.links.new(coord.outputs["Object"], pattern.inputs["Vector"])
        mix = nt.nodes.new("ShaderNodeMixRGB")
        mix.blend_type = "MULTIPLY"
        mix.inputs["Fac"].default_value = 1.0
        nt.links.new(color, mix.inputs["Color1"])
        nt.links.new(fac, mix.inputs["Color2"])
        color = mix.outputs["Color"]
    nt.links.new(color, bsdf.inputs["Base Color"])
    return mat


# ---------------------------------------------------------------------------
# Geometry

def _box(name, size, location, rotation_z_deg, collection, material):
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    ob = bpy.context.active_object
    ob.name = name
    ob.scale = size
    ob.location = (location[0], location[1], location[2] + size[2] / 2.0)
    ob.rotation_euler = (0, 0, math.radians(rotation_z_deg))
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    for c in ob.users_collection:
        c.objects.unlink(ob)
    collection.objects.link(ob)
    ob.data.materials.append(material)
    return ob


def _extra(kind, name, location, collection, material):
    if kind == "cylinder":
        bpy.ops.mesh.primitive_cylinder_add(radius=0.35, depth=0.9,
                                            location=(location[0], location[1], 0.45))
    else:
        bpy.ops.mesh.primitive_uv_sphere_add(radius=0.6, location=(location[0], location[1], 0.5))
    ob = bpy.context.active_object
    ob.name = name
    for c in ob.users_collection:
        c.objects.unlink(ob)
    collection.objects.link(ob)
    ob.data.materials.append(material)
    return ob


def build_layout(layout, model, extras, ground_mat):
    """Model objects (in `model`) and footage-only objects (in `extras`)."""
    grey = _principled("concrete", (0.55, 0.53, 0.5))
    dark = _principled("painted_metal", (0.12, 0.14, 0.16), roughness=0.5)
    green = _principled("foliage", (0.08, 0.2, 0.05))
    size = 10.0 if layout == "room" else 40.0
    bpy.ops.mesh.primitive_plane_add(size=size)
    ground = bpy.context.active_object
    ground.name = "Ground"
    for c in ground.users_collection:
        c.objects.unlink(ground)
    model.objects.link(ground)
    ground.data.materials.append(ground_mat)
    if layout == "plaza":
        _box("Pole1", (0.15, 0.15, 3.0), (-2.5, 1.5, 0), 0, model, dark)
        _box("Pole2", (0.12, 0.12, 2.5), (2.0, -2.0, 0), 0, model, dark)
        _box("Pole3", (0.15, 0.15, 3.5), (3.5, 3.0, 0), 0, model, dark)
        _box("Box1", (1.2, 1.2, 1.0), (-1.0, -3.0, 0), 20, model, grey)
        _box("Box2", (0.8, 1.6, 1.4), (0.5, 3.5, 0), -10, model, grey)
        _box("Wall", (5.0, 0.3, 2.0), (-3.0, 6.0, 0), 5, model, grey)
        _extra("cylinder", "Bin", (4.0, -3.5), extras, green)
    elif layout == "yard":
        _box("Pole1", (0.15, 0.15, 2.5), (-1.0, 0.0, 0), 0, model, dark)
        _box("Pole2", (0.15, 0.15, 2.5), (2.5, 1.5, 0), 0, model, dark)
        _box("Shed", (2.0, 2.5, 2.2), (-4.0, 3.0, 0), 15, model, grey)
        _box("Fence", (6.0, 0.1, 1.2), (1.0, 5.0, 0), 0, model, grey)
        _extra("sphere", "Bush", (3.0, -2.0), extras, green)
        _extra("cylinder", "Bin", (-2.5, -2.0), extras, dark)
    elif layout == "street":
        for i, x in enumerate((-3.0, -1.0, 1.0, 3.0)):
            _box(f"Bollard{i + 1}", (0.2, 0.2, 1.0 + 0.3 * i), (x, -1.5, 0), 0, model, dark)
        _box("Lamppost", (0.15, 0.15, 4.0), (0.0, 2.0, 0), 0, model, dark)
        _box("Kiosk", (1.5, 1.5, 2.2), (-3.0, 3.0, 0), 30, model, grey)
        _extra("sphere", "Bush", (3.0, 2.5), extras, green)
    elif layout == "room":
        build_room(model, extras, grey, dark, green)
    else:
        raise ValueError(f"unknown layout {layout}")
    return ground


def build_room(model, extras, wall_mat, dark, green):
    """Furniture of a 6 x 5 x 3 m room around the origin; the walls come from
    place_room_walls once the Sun's side is known."""
    _box("Table", (1.2, 0.8, 0.75), (0.5, 0.3, 0), 10, model, dark)
    _box("Cabinet", (0.5, 1.0, 1.6), (-2.2, -1.5, 0), 0, model, wall_mat)
    _extra("cylinder", "Vase", (-1.0, 1.2), extras, green)


def place_room_walls(model, wall_mat, sun_azimuth_world_deg):
    """Four walls and a ceiling; the wall toward the Sun has a window."""
    w, d, h, t = 6.0, 5.0, 3.0, 0.2
    rot = sun_azimuth_world_deg  # the window wall faces the mid-clip Sun
    walls = []
    # Window wall (toward local +Y, turned to face the Sun): four pieces
    # around a 2 m x 1.4 m opening whose sill is 0.6 m high.

    def put(name, size, loc):
        ob = _box(name, size, loc, 0, model, wall_mat)
        walls.append(ob)
        return ob
    put("WallWin_L", (2.0, t, h), (-2.0, d / 2, 0))
    put("WallWin_R", (2.0, t, h), (2.0, d / 2, 0))
    put("WallWin_Low", (2.0, t, 0.6), (0.0, d / 2, 0))
    put("WallWin_Top", (2.0, t, 1.0), (0.0, d / 2, 2.0))
    put("WallBack", (w, t, h), (0, -d / 2, 0))
    put("WallSideA", (t, d, h), (-w / 2, 0, 0))
    put("WallSideB", (t, d, h), (w / 2, 0, 0))
    put("Ceiling", (w + t, d + t, t), (0, 0, h))
    # Turn the room so that local +Y points to the Sun's azimuth.
    pivot = bpy.data.objects.new("RoomPivot", None)
    model.objects.link(pivot)
    pivot.rotation_euler = (0, 0, -math.radians(rot))
    for ob in walls:
        ob.parent = pivot
    bpy.context.view_layer.update()
    for ob in walls:
        mw = ob.matrix_world.copy()
        ob.parent = None
        ob.matrix_world = mw
    bpy.data.objects.remove(pivot)
    return walls


# ---------------------------------------------------------------------------
# Sun, sky, camera

def lamp_euler(zenith_deg, azimuth_world_deg):
    """XYZ Euler that turns the lamp's local +Z toward the Sun.

    R = Rz(g) Rx(t) maps +Z to (sin t sin g, -sin t cos g, cos t); the Sun is
    (sin z sin a, sin z cos a, cos z), so t = z and g = 180 deg - a.
    """
    return (math.radians(zenith_deg), 0.0, math.radians(180.0 - azimuth_world_deg))


def sky_angles(zenith_deg, azimuth_world_deg):
    """Nishita sky node (Cycles 3.x): the sun sits at
    geographical_to_direction(elevation, rotation + 90 deg), so
    rotation = -azimuth_world."""
    return math.radians(90.0 - zenith_deg), math.radians(-azimuth_world_deg) % (2 * math.pi)


def setup_camera(scene, cam_cfg, layout, width, height, sun_azimuth_world_deg):
    cam = bpy.data.cameras.new("Camera")
    cam.lens = cam_cfg["lens"]
    cam.sensor_width = 36.0
    cam.sensor_fit = "AUTO"
    ob = bpy.data.objects.new("Camera", cam)
    scene.collection.objects.link(ob)
    if layout == "room":
        # In the corner opposite the window, looking at the sunlit floor.
        back = Vector((math.sin(math.radians(sun_azimuth_world_deg)),
                       math.cos(math.radians(sun_azimuth_world_deg)), 0))
        side = Vector((back.y, -back.x, 0))
        ob.location = -2.1 * back + 2.4 * side * 0.5 + Vector((0, 0, cam_cfg["height"]))
        target = 0.6 * back + Vector((0, 0, 0.2))
    else:
        yaw = math.radians(cam_cfg["yaw_deg"])
        ob.location = (cam_cfg["distance"] * math.sin(yaw), cam_cfg["distance"] * math.cos(yaw),
                       cam_cfg["height"])
        target = Vector((0, 0, 0))
    ob.rotation_euler = (target - ob.location).to_track_quat("-Z", "Y").to_euler()
    scene.camera = ob
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100
    return ob


def local_times(preset, count):
    y, m, d = preset["date"]
    hh, mm = preset["start"]
    tz = dt.timezone(dt.timedelta(hours=preset["utc_offset_h"]))
    start = dt.datetime(y, m, d, hh, mm, tzinfo=tz)
    step = dt.timedelta(minutes=preset["minutes_per_frame"])
    return [start + i * step for i in range(count)]


def sun_at(native, when, preset):
    u = when.astimezone(dt.timezone.utc)
    return native.sun_position(u.year, u.month, u.day, u.hour, u.minute,
                               u.second + u.microsecond * 1e-6, preset["lat"], preset["lon"])


def add_sun_and_sky(scene, suns, north, strength_factors=None, sky_importance=True,
                    sky_factors=None, overcast=None):
    """A Sun lamp of the real angular size and a Nishita sky that follows it,
    keyframed on every frame. `strength_factors` dims the lamp per frame
    (clouds, the horizon), `sky_factors` the sky (twilight: the sky keeps
    the colour of a Sun just below the horizon, dimmer). Without
    `sky_importance` Cycles builds no importance map of the world: the sky
    (no Sun disc) is smooth, and rebuilding the map on every frame costs ~8x
    the render of a small frame (measured 10.2 vs 1.3 s). `overcast`, a pair
    (radiance, per-frame shares), mixes in a flat grey sky of that radiance
    (a background node named "Overcast") by each frame's share."""
    lamp_data = bpy.data.lights.new("Sun", "SUN")
    lamp_data.angle = math.radians(SUN_ANGULAR_DIAMETER_DEG)
    lamp_data.energy = SUN_STRENGTH
    lamp = bpy.data.objects.new("Sun", lamp_data)
    scene.collection.objects.link(lamp)
    lamp.rotation_mode = "XYZ"

    world = bpy.data.worlds.new("Sky")
    scene.world = world
    world.use_nodes = True
    if not sky_importance:
        world.cycles.sampling_method = "NONE"
    sky = world.node_tree.nodes.new("ShaderNodeTexSky")
    sky.sky_type = "NISHITA"
    sky.sun_disc = False  # the lamp is the Sun; the sky only adds skylight
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Strength"].default_value = SKY_STRENGTH
    world.node_tree.links.new(sky.outputs["Color"], bg.inputs["Color"])
    mix = None
    if overcast is not None:
        nt = world.node_tree
        grey = nt.nodes.new("ShaderNodeBackground")
        grey.name = "Overcast"
        grey.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        grey.inputs["Strength"].default_value = overcast[0]
        mix = nt.nodes.new("ShaderNodeMixShader")
        out = nt.nodes["World Output"]
        nt.links.new(bg.outputs["Background"], mix.inputs[1])
        nt.links.new(grey.outputs["Background"], mix.inputs[2])
        nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])

    for i, (z, a) in enumerate(suns):
        f = i + 1
        lamp.rotation_euler = lamp_euler(z, a + north)
        lamp.keyframe_insert("rotation_euler", frame=f)
        if strength_factors is not None:
            lamp_data.energy = SUN_STRENGTH * strength_factors[i]
            lamp_data.keyframe_insert("energy", frame=f)
        sky.sun_elevation, sky.sun_rotation = sky_angles(min(z, 89.5), a + north)
        sky.keyframe_insert("sun_elevation", frame=f)
        sky.keyframe_insert("sun_rotation", frame=f)
        if sky_factors is not None:
            bg.inputs["Strength"].default_value = SKY_STRENGTH * sky_factors[i]
            bg.inputs["Strength"].keyframe_insert("default_value", frame=f)
        if mix is not None:
            mix.inputs["Fac"].default_value = overcast[1][i]
            mix.inputs["Fac"].keyframe_insert("default_value", frame=f)
    curves = list(lamp.animation_data.action.fcurves) + \
        list(world.node_tree.animation_data.action.fcurves)
    if lamp_data.animation_data:
        curves += list(lamp_data.animation_data.action.fcurves)
    for fc in curves:
        for kp in fc.keyframe_points:
            kp.interpolation = "LINEAR"
    return lamp


def configure_render(scene, samples, exposure, frames, frames_dir):
    scene.frame_start, scene.frame_end = 1, frames
    r = scene.render
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.max_bounces = 4
    scene.cycles.seed = 0
    scene.cycles.use_animated_seed = True  # noise changes frame to frame, like a sensor
    scene.view_settings.view_transform = "Filmic"
    scene.view_settings.look = "Medium Contrast"
    scene.view_settings.exposure = exposure
    r.image_settings.file_format = "PNG"
    r.image_settings.color_mode = "RGB"
    r.fps = 25
    r.filepath = os.path.join(frames_dir, "frame_")


def encode_clip(frames_dir, clip_path, crf=20, noise=0):
    """H.264 like a camera's; `noise` adds temporal grain (ffmpeg's noise
    filter strength, 0-100) before compression, like a sensor's."""
    vf = ["-vf", f"noise=alls={noise}:allf=t"] if noise else []
    subprocess.run(["ffmpeg", "-y", "-loglevel", "error", "-framerate", "25",
                    "-i", os.path.join(frames_dir, "frame_%04d.png"), *vf, "-c:v", "libx264",
                    "-preset", "medium", "-crf", str(crf), "-pix_fmt", "yuv420p", clip_path],
                   check=True)


# ---------------------------------------------------------------------------

def parse_args(argv):
    p = argparse.ArgumentParser(prog="generate_scene.py")
    which = p.add_mutually_exclusive_group(required=True)
    which.add_argument("--preset", choices=sorted(PRESETS))
    which.add_argument("--random", metavar="KEY",
                       help="a random scene of the suite (examples/random_scene.py): an "
                            "integer seed, <kind><seed> for a kind in "
                            + ", ".join(random_scene.PREFIXES) + ", or a fixed member: "
                            + ", ".join(sorted(random_scene.FIXED)))
    p.add_argument("--out", required=True)
    p.add_argument("--tiny", action="store_true",
                   help="test size: 3 frames, 128x96, 4 samples")
    p.add_argument("--frames", type=int)
    p.add_argument("--resolution", help="WxH")
    p.add_argument("--samples", type=int)
    p.add_argument("--minutes-per-frame", type=float,
                   help="time between frames (default: the preset's)")
    p.add_argument("--mask-frames", type=int, default=3,
                   help="how many frames get a ground-truth shadow mask")
    p.add_argument("--spec-only", action="store_true",
                   help="with --random: write spec.json (what would be rendered) and stop")
    p.add_argument("--still-camera", action="store_true",
                   help="with --random moving<seed>: the camera held at the drawn view")
    args = p.parse_args(argv)
    if args.random is None and args.spec_only:
        p.error("--spec-only needs --random")
    if args.still_camera and not str(args.random or "").startswith(random_scene.MOVING_PREFIX):
        p.error(f"--still-camera needs --random {random_scene.MOVING_PREFIX}<seed>")
    if args.resolution:
        try:
            w, h = (int(v) for v in args.resolution.lower().split("x"))
            assert w > 0 and h > 0
        except (ValueError, AssertionError):
            p.error(f"--resolution must be WxH in pixels (e.g. 320x180), got '{args.resolution}'")
    for flag in ("frames", "samples"):
        v = getattr(args, flag)
        if v is not None and v < (2 if flag == "frames" and args.random is not None else 1):
            p.error(f"--{flag} must be a positive integer, got {v}")
    return args


def new_scene():
    """An empty file with the two collections every generated scene has: the
    model a user would have, and what only the footage shows."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.preferences.filepaths.save_version = 0  # no .blend1 backups
    scene = bpy.context.scene
    model = bpy.data.collections.new("Model")
    extras = bpy.data.collections.new("FootageOnly")
    scene.collection.children.link(model)
    scene.collection.children.link(extras)
    return scene, model, extras


def main(argv):
    args = parse_args(argv)
    native = native_loader.require()
    if args.random is not None:
        return main_random(args, native)
    preset = dict(PRESETS[args.preset])
    if args.minutes_per_frame:
        preset["minutes_per_frame"] = args.minutes_per_frame
    frames = args.frames or (3 if args.tiny else preset["frames"])
    width, height = (128, 96) if args.tiny else (640, 360)
    if args.resolution:
        width, height = (int(v) for v in args.resolution.lower().split("x"))
    samples = (args.samples or (4 if args.tiny else 16)) * preset.get("sample_factor", 1)
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    frames_dir = os.path.join(out, "frames")
    masks_dir = os.path.join(out, "masks")
    for d in (frames_dir, masks_dir):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)

    times = local_times(preset, frames)
    suns = [sun_at(native, t, preset) for t in times]
    if any(z >= 88.0 for z, _ in suns):
        raise SystemExit(f"preset {args.preset}: the Sun sets during the clip")
    north = preset["north_offset_deg"]
    mid_az_world = suns[len(suns) // 2][1] + north

    scene, model, extras = new_scene()
    ground_mat = ground_material(preset["ground"])
    ground = build_layout(preset["layout"], model, extras, ground_mat)
    if preset["layout"] == "room":
        place_room_walls(model, bpy.data.materials["concrete"], mid_az_world)
    setup_camera(scene, preset["camera"], preset["layout"], width, height, mid_az_world)

    lamp = add_sun_and_sky(scene, suns, north)
    configure_render(scene, samples, preset.get("exposure", 0.0), frames, frames_dir)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "render.blend"))
    bpy.ops.render.render(animation=True)

    clip_path = os.path.join(out, "clip.mp4")
    encode_clip(frames_dir, clip_path)

    mask_frames = sorted({1 + round(k * (frames - 1) / max(1, args.mask_frames - 1))
                          for k in range(args.mask_frames)})
    render_masks(scene, ground, suns, north, mask_frames, masks_dir)

    truth = trackfile.Track(
        clip="clip.mp4", frame_start=1, north_offset_deg=north, format=trackfile.FORMAT_TRUTH,
        method={"initial": "ephemeris", "smoothing": None,
                "options": {"preset": args.preset}},
        initial={"zenith_deg": suns[0][0], "azimuth_deg": suns[0][1], "residual": 0.0},
        frames=[trackfile.FrameEstimate(frame=i + 1, zenith_deg=z, azimuth_deg=a,
                                        raw_zenith_deg=z, raw_azimuth_deg=a, confidence=1.0)
                for i, (z, a) in enumerate(suns)],
        extra={"preset": args.preset, "description": preset["description"],
               "place": {"latitude_deg": preset["lat"], "longitude_deg": preset["lon"]},
               "local_times": [t.isoformat() for t in times],
               "utc_times": [t.astimezone(dt.timezone.utc).isoformat() for t in times],
               "model_collection": "Model", "ground_objects": ["Ground"],
               "footage_only_objects": sorted(o.name for o in extras.objects),
               "shadow_masks": {str(f): f"masks/mask_{f:04d}.png" for f in mask_frames},
               "render": {"width": width, "height": height, "samples": samples}})
    trackfile.write_track(os.path.join(out, "truth.sun.json"), truth)

    save_user_blend(scene, out, clip_path, lamp, extras)
    print(f"generate_scene: {args.preset}: {frames} frames {width}x{height} -> {out}")

# ---------------------------------------------------------------------------
# Random scenes (the scene suite): examples/random_scene.py draws, this builds.


def _link_only(ob, collection):
    for c in ob.users_collection:
        c.objects.unlink(ob)
    collection.objects.link(ob)


def _cylinder(name, radius, height, location, collection, material, vertices=24):
    bpy.ops.mesh.primitive_cylinder_add(radius=radius, depth=height, vertices=vertices,
                                        location=(location[0], location[1], height / 2.0))
    ob = bpy.context.active_object
    ob.name = name
    _link_only(ob, collection)
    ob.data.materials.append(material)
    return ob


def _rotated(location, rotation_z_deg, du, dv):
    """location + (du, dv) turned by rotation_z_deg (counter-clockwise, as
    Blender's Z rotation)."""
    a = math.radians(rotation_z_deg)
    return (location[0] + du * math.cos(a) - dv * math.sin(a),
            location[1] + du * math.sin(a) + dv * math.cos(a), location[2])


def build_item(item, collection, mats):
    """One caster or clutter object of a random scene (see random_scene.py)."""
    shape, name, size = item["shape"], item["name"], item["size"]
    loc, rot = item["location"], item["rotation_z_deg"]
    if shape == "pole":
        if item.get("round"):
            return [_cylinder(name, size[0] / 2, size[2], loc, collection, mats["dark"], 12)]
        return [_box(name, size, loc, rot, collection, mats["dark"])]
    if shape in ("box", "wall", "bench", "car"):
        mat = {"box": mats["grey"], "wall": mats["grey"], "bench": mats["wood"],
               "car": mats["car"]}[shape]
        return [_box(name, size, loc, rot, collection, mat)]
    if shape == "kiosk":
        roof_t, o = 0.15, item["roof_overhang"]
        body = _box(name, (size[0], size[1], size[2] - roof_t), loc, rot, collection, mats["grey"])
        roof = _box(name + "_roof", (size[0] + 2 * o, size[1] + 2 * o, roof_t),
                    (loc[0], loc[1], size[2] - roof_t), rot, collection, mats["dark"])
        return [body, roof]
    if shape == "lshape":
        t = item["thickness"]
        a = _box(name + "_a", (size[0], t, size[2]), _rotated(loc, rot, size[0] / 2, t / 2),
                 rot, collection, mats["grey"])
        b = _box(name + "_b", (t, size[1], size[2]), _rotated(loc, rot, t / 2, size[1] / 2),
                 rot, collection, mats["grey"])
        return [a, b]
    if shape == "cylinder":
        return [_cylinder(name, size[0], size[2], loc, collection, mats["grey"])]
    if shape == "bin":
        return [_cylinder(name, size[0], size[2], loc, collection, mats["green"])]
    if shape == "person":
        return [_cylinder(name, size[0], size[2], loc, collection, mats["cloth"], 12)]
    if shape == "building":
        # A flat-roofed block and the eaves slab over its walls.
        o, roof_t = item["eaves"], random_scene.EAVES_THICKNESS_M
        body = _box(name, (size[0], size[1], size[2] - roof_t), loc, rot, collection,
                    mats["wall"])
        roof = _box(name + "_eaves", (size[0] + 2 * o, size[1] + 2 * o, roof_t),
                    (loc[0], loc[1], size[2] - roof_t), rot, collection, mats["dark"])
        return [body, roof]
    if shape == "tree":
        return build_tree(item, collection, mats)
    if shape == "bush":
        bpy.ops.mesh.primitive_uv_sphere_add(radius=size[0],
                                             location=(loc[0], loc[1], 0.8 * size[0]))
        ob = bpy.context.active_object
        ob.name = name
        _link_only(ob, collection)
        ob.data.materials.append(mats["green"])
        return [ob]
    raise ValueError(f"unknown shape {shape}")


def leaf_material(seed):
    """Foliage with gaps: a noise texture cuts the crown's shell into leaves
    and holes (about half), so its shadow is dappled."""
    mat = bpy.data.materials.new(f"leaves_{seed}")
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        if n.type != "OUTPUT_MATERIAL":
            nt.nodes.remove(n)
    coord = nt.nodes.new("ShaderNodeTexCoord")
    noise = nt.nodes.new("ShaderNodeTexNoise")
    noise.inputs["Scale"].default_value = 2.5
    noise.inputs["Detail"].default_value = 4.0
    noise.inputs["W"].default_value = float(seed)
    noise.noise_dimensions = "4D"
    ramp = nt.nodes.new("ShaderNodeValToRGB")
    ramp.color_ramp.interpolation = "CONSTANT"
    ramp.color_ramp.elements[1].position = 0.5
    leaf = nt.nodes.new("ShaderNodeBsdfDiffuse")
    leaf.inputs["Color"].default_value = (0.06, 0.16, 0.04, 1.0)
    hole = nt.nodes.new("ShaderNodeBsdfTransparent")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(coord.outputs["Object"], noise.inputs["Vector"])
    nt.links.new(noise.outputs["Fac"], ramp.inputs["Fac"])
    nt.links.new(ramp.outputs["Color"], mix.inputs["Fac"])
    nt.links.new(hole.outputs["BSDF"], mix.inputs[1])
    nt.links.new(leaf.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], nt.nodes["Material Output"].inputs["Surface"])
    return mat


def build_tree(item, collection, mats):
    """A trunk and a leafy crown of two shells (outer and inner), both cut
    into leaves and holes."""
    r, loc = item["size"][0], item["location"]
    trunk = _cylinder(item["name"] + "_trunk", item["trunk_radius"],
                      item["trunk_height"] + 0.5 * r, loc, collection, mats["bark"], 10)
    leaves = leaf_material(item["leaf_seed"])
    out = [trunk]
    for k, radius in enumerate((r, 0.6 * r)):
        bpy.ops.mesh.primitive_ico_sphere_add(
            subdivisions=3, radius=radius,
            location=(loc[0], loc[1], item["trunk_height"] + 0.8 * r))
        ob = bpy.context.active_object
        ob.name = f"{item['name']}_crown{k + 1}"
        ob.scale = (1.0, 1.0, 0.8)
        _link_only(ob, collection)
        ob.data.materials.append(leaves)
        out.append(ob)
    return out


def build_random_room(spec, model, mats):
    """Four walls (one with the window) and a ceiling slab, turned so the
    window wall faces spec.room.facing_world_deg."""
    r = spec["room"]
    w, d, h, t = r["width"], r["depth"], r["height"], r["wall"]
    win = r["window"]
    facing = r["facing_world_deg"]

    def put(name, su, sv, sz, u, v, z):
        p = random_scene._room_to_world(facing, u, v, z)
        return _box(name, (su, sv, sz), p, -facing, model, mats["wall"])
    left_w = win["u"] - win["width"] / 2 + w / 2
    right_w = w / 2 - (win["u"] + win["width"] / 2)
    put("WallWin_L", left_w, t, h, -w / 2 + left_w / 2, d / 2, 0)
    put("WallWin_R", right_w, t, h, w / 2 - right_w / 2, d / 2, 0)
    put("WallWin_Low", win["width"], t, win["sill"], win["u"], d / 2, 0)
    put("WallWin_Top", win["width"], t, h - win["top"], win["u"], d / 2, win["top"])
    put("WallBack", w, t, h, 0, -d / 2, 0)
    put("WallSideA", t, d, h, -w / 2, 0, 0)
    put("WallSideB", t, d, h, w / 2, 0, 0)
    put("Ceiling", w + t, d + t, t, 0, 0, h)


def main_random(args, native):
    small = (128, 72) if args.tiny else random_scene.DEFAULT_RESOLUTION
    resolution = tuple(int(v) for v in args.resolution.lower().split("x")) \
        if args.resolution else small
    frames = args.frames or (3 if args.tiny else random_scene.DEFAULT_FRAMES)
    try:
        spec = random_scene.draw(args.random, native.sun_position, frames=frames,
                                 resolution=resolution)
    except ValueError as e:
        raise SystemExit(f"generate_scene: error: --random: {e}")
    frames = spec["render"]["frames"]  # multi-day members have more
    if args.still_camera:
        del spec["camera_motion"]
    if args.samples or args.tiny:
        spec["render"]["samples"] = args.samples or 4
    out = os.path.abspath(args.out)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, "spec.json"), "w") as fh:
        json.dump(spec, fh, indent=1, sort_keys=True)
    if args.spec_only:
        print(f"generate_scene: {args.random}: spec -> {out}/spec.json")
        return
    frames_dir = os.path.join(out, "frames")
    masks_dir = os.path.join(out, "masks")
    for d in (frames_dir, masks_dir):
        shutil.rmtree(d, ignore_errors=True)
        os.makedirs(d)
    width, height = spec["render"]["resolution"]
    times = random_scene.frame_times_local(spec)
    suns = random_scene.suns_of(spec, native.sun_position)
    north = spec["north_offset_deg"]
    strength = [random_scene.sun_strength_factor(spec, i, suns[i][0]) for i in range(frames)]
    twilight = [random_scene.twilight_light(spec, z) for z, _ in suns]
    overcast = None
    if spec.get("overcast"):
        # The flat sky's radiance: sky_level of the clear Sun's irradiance
        # on the ground at the run's middle (a uniform sky L gives pi L).
        o = spec["overcast"]
        z_mid = suns[(o["first"] + o["last"]) // 2 - 1][0]
        radiance = o["sky_level"] * SUN_STRENGTH * math.cos(math.radians(z_mid)) / math.pi
        overcast = (radiance, [random_scene.overcast_sky(spec, i) for i in range(frames)])

    scene, model, extras = new_scene()
    g = spec["ground"]
    mats = {"grey": _principled("concrete", (0.55, 0.53, 0.5)),
            "dark": _principled("painted_metal", (0.12, 0.14, 0.16), roughness=0.5),
            "green": _principled("foliage", (0.08, 0.2, 0.05)),
            "wood": _principled("bench_wood", (0.35, 0.22, 0.12), roughness=0.7),
            "car": _principled("car_paint", (0.5, 0.05, 0.04), roughness=0.3),
            "cloth": _principled("cloth", (0.15, 0.15, 0.3), roughness=0.9),
            "wall": _principled("plaster", (0.7, 0.68, 0.64), roughness=0.9),
            "bark": _principled("bark", (0.12, 0.08, 0.05), roughness=0.9)}
    ground_mat = ground_material(g["kind"], g["roughness"], g["specular"])
    if spec["kind"] == "room":
        r = spec["room"]
        bpy.ops.mesh.primitive_plane_add(size=1.0)
        ground = bpy.context.active_object
        ground.scale = (r["width"] + r["wall"], r["depth"] + r["wall"], 1.0)
        ground.rotation_euler = (0, 0, -math.radians(r["facing_world_deg"]))
        bpy.ops.object.transform_apply(location=False, rotation=True, scale=True)
        build_random_room(spec, model, mats)
    else:
        # Far enough that every pixel sees ground (the drawer keeps the
        # horizon out of view within 70 m).
        bpy.ops.mesh.primitive_plane_add(size=400.0 if "urban" in spec else 160.0)
        ground = bpy.context.active_object
    ground.name = g["name"]
    _link_only(ground, model)
    ground.data.materials.append(ground_mat)
    for item in spec["casters"]:
        build_item(item, model, mats)
    for item in spec["clutter"] + spec.get("trees", []):
        build_item(item, extras, mats)

    cam = bpy.data.cameras.new("Camera")
    cam.lens = spec["camera"]["lens_mm"]
    cam.sensor_width = random_scene.SENSOR_WIDTH_MM
    cam.sensor_fit = "AUTO"
    cam_obj = bpy.data.objects.new("Camera", cam)
    scene.collection.objects.link(cam_obj)
    cam_obj.location = spec["camera"]["location"]
    rest = (Vector(spec["camera"]["target"]) - cam_obj.location).to_track_quat("-Z", "Y").to_euler()
    cam_obj.rotation_euler = rest
    scene.camera = cam_obj
    scene.render.resolution_x, scene.render.resolution_y = width, height
    scene.render.resolution_percentage = 100

    lamp = add_sun_and_sky(scene, suns, north, strength_factors=strength, sky_importance=False,
                           sky_factors=[t[0] for t in twilight]
                           if random_scene.keyed_sky(spec) else None, overcast=overcast)
    exposure = spec.get("exposure_ev", 0.0)
    configure_render(scene, spec["render"]["samples"], exposure, frames, frames_dir)
    scene.cycles.seed = spec["render"].get("seed", 0)
    deg = spec["degradations"]
    if "camera_motion" in spec:
        key_camera_move(spec, cam_obj, rest, frames)
    if deg["shake_deg"]:
        cam_obj["rest_rotation_euler"] = list(rest)
        for i, off in enumerate(random_scene.shake_offsets_deg(spec)):
            cam_obj.rotation_euler = [rest[k] + math.radians(off[k]) for k in range(3)]
            cam_obj.keyframe_insert("rotation_euler", frame=i + 1)
        cam_obj.rotation_euler = rest
    if deg["exposure_drift"] or random_scene.keyed_sky(spec) or spec.get("overcast"):
        scene["rest_exposure"] = exposure
        for i in range(frames):
            scene.view_settings.exposure = (exposure + random_scene.exposure_offset(spec, i)
                                            + twilight[i][1]
                                            + random_scene.overcast_exposure_ev(spec, i))
            scene.view_settings.keyframe_insert("exposure", frame=i + 1)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "render.blend"))
    bpy.ops.render.render(animation=True)

    clip_path = os.path.join(out, "clip.mp4")
    encode_clip(frames_dir, clip_path, crf=deg["crf"], noise=deg["noise"])

    mask_frames = sorted({1 + round(k * (frames - 1) / max(1, args.mask_frames - 1))
                          for k in range(args.mask_frames)})
    if scene.animation_data:  # masks at the rest exposure (they threshold irradiance)
        scene.animation_data_clear()
    render_masks(scene, ground, suns, north, mask_frames, masks_dir, strength)

    truth = trackfile.Track(
        clip="clip.mp4", frame_start=1, north_offset_deg=north, format=trackfile.FORMAT_TRUTH,
        method={"initial": "ephemeris", "smoothing": None,
                "options": {"random_scene": spec["key"]}},
        initial={"zenith_deg": suns[0][0], "azimuth_deg": suns[0][1], "residual": 0.0},
        frames=[trackfile.FrameEstimate(frame=i + 1, zenith_deg=z, azimuth_deg=a,
                                        raw_zenith_deg=z, raw_azimuth_deg=a, confidence=1.0)
                for i, (z, a) in enumerate(suns)],
        extra={"preset": f"random:{spec['key']}", "description": random_scene.describe(spec),
               "place": spec["place"],
               "local_times": [t.isoformat() for t in times],
               "utc_times": [t.astimezone(dt.timezone.utc).isoformat() for t in times],
               "model_collection": "Model", "ground_objects": [g["name"]],
               "footage_only_objects": sorted(o.name for o in extras.objects),
               "shadow_masks": {str(f): f"masks/mask_{f:04d}.png" for f in mask_frames},
               "render": {"width": width, "height": height,
                          "samples": spec["render"]["samples"]},
               "random_scene": spec})
    trackfile.write_track(os.path.join(out, "truth.sun.json"), truth)

    if "camera_motion" in spec:  # the user has the camera as a solve gives it
        key_camera_move(spec, cam_obj, rest, frames, jitter=True)
    if "rough_model" in spec:
        save_user_blend(scene, out, clip_path, lamp, extras, "scene_true.blend")
        roughen(spec, scene, model, mats)
        bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "scene.blend"))
    else:
        save_user_blend(scene, out, clip_path, lamp, extras)
    print(f"generate_scene: random {spec['key']}: {frames} frames {width}x{height} -> {out}")


def key_camera_move(spec, cam_obj, rest, frames, jitter=False):
    """Keys a moving member's camera on every frame (random_scene.camera_move
    about the rest pose), with a camera solve's error when `jitter`."""
    # The rest location is kept from the first call: by the second the
    # location is a key's.
    if "rest_location" not in cam_obj:
        cam_obj["rest_location"] = list(cam_obj.location)
    location, rest_q = Vector(cam_obj["rest_location"]), rest.to_quaternion()
    for i in range(frames):
        offset, pan, tilt = random_scene.camera_move(spec, i)
        q = (Quaternion((0.0, 0.0, 1.0), math.radians(pan)) @ rest_q
             @ Quaternion((1.0, 0.0, 0.0), math.radians(tilt)))
        at = location + Vector(offset)
        if jitter:
            d_loc, d_rot = random_scene.solve_jitter(spec, i)
            at += Vector(d_loc)
            q = Euler([math.radians(v) for v in d_rot]).to_quaternion() @ q
        cam_obj.location = at
        cam_obj.rotation_euler = q.to_euler("XYZ", rest)
        cam_obj.keyframe_insert("location", frame=i + 1)
        cam_obj.keyframe_insert("rotation_euler", frame=i + 1)


def render_masks(scene, ground, suns, north, mask_frames, masks_dir, strength_factors=None):
    """Ground-truth cast-shadow masks, rendered by Blender itself: a white
    override material lit only by the Sun (no sky, no bounces); ground pixels
    darker than half the lit value are in shadow. The ground is picked by its
    object index through the compositor."""
    vl = scene.view_layers[0]
    # A pure Lambertian white, so lit ground is exactly E cos(z) / pi.
    white = bpy.data.materials.new("mask_white")
    white.use_nodes = True
    wnt = white.node_tree
    wnt.nodes.remove(wnt.nodes["Principled BSDF"])
    diffuse = wnt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (1, 1, 1, 1)
    wnt.links.new(diffuse.outputs["BSDF"], wnt.nodes["Material Output"].inputs["Surface"])
    vl.material_override = white
    vl.use_pass_object_index = True
    ground.pass_index = 1
    scene.world.node_tree.animation_data_clear()  # a twilight sky's keyed strength
    world_strength = scene.world.node_tree.nodes["Background"].inputs["Strength"]
    world_strength.default_value = 0.0
    if "Overcast" in scene.world.node_tree.nodes:
        scene.world.node_tree.nodes["Overcast"].inputs["Strength"].default_value = 0.0
    scene.cycles.max_bounces = 0
    scene.cycles.samples = 16
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.use_nodes = True
    nt = scene.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    rl = nt.nodes.new("CompositorNodeRLayers")
    idm = nt.nodes.new("CompositorNodeIDMask")
    idm.index = 1
    idm.use_antialiasing = False
    bw = nt.nodes.new("CompositorNodeRGBToBW")
    less = nt.nodes.new("CompositorNodeMath")
    less.operation = "LESS_THAN"
    mult = nt.nodes.new("CompositorNodeMath")
    mult.operation = "MULTIPLY"
    comp = nt.nodes.new("CompositorNodeComposite")
    nt.links.new(rl.outputs["IndexOB"], idm.inputs["ID value"])
    nt.links.new(rl.outputs["Image"], bw.inputs["Image"])
    nt.links.new(bw.outputs["Val"], less.inputs[0])
    nt.links.new(less.outputs["Value"], mult.inputs[0])
    nt.links.new(idm.outputs["Alpha"], mult.inputs[1])
    nt.links.new(mult.outputs["Value"], comp.inputs["Image"])
    scene.render.image_settings.color_mode = "BW"
    for f in mask_frames:
        scene.frame_set(f)
        z = suns[f - 1][0]
        # Lit ground irradiance = sun strength * cos(zenith) (white albedo,
        # horizontal ground); the mask keeps ground below half of that.
        k = 1.0 if strength_factors is None else strength_factors[f - 1]  # clouds
        less.inputs[1].default_value = 0.5 * k * SUN_STRENGTH * math.cos(math.radians(z)) / math.pi
        scene.render.filepath = os.path.join(masks_dir, f"mask_{f:04d}.png")
        bpy.ops.render.render(write_still=True)
    vl.material_override = None


def roughen(spec, scene, model, mats):
    """The model as a user models it by hand (spec["rough_model"]): each
    caster rebuilt moved, scaled and turned; the camera turned about an axis
    and its focal length off."""
    rough = spec["rough_model"]
    ground = spec["ground"]["name"]
    for ob in list(model.objects):
        if ob.name != ground:
            bpy.data.objects.remove(ob)
    for item in spec["casters"]:
        build_item(random_scene.rough_item(item, rough), model, mats)
    cam = scene.camera
    c = rough["camera"]
    turn = Quaternion(Vector(c["axis"]), math.radians(c["angle_deg"]))
    cam.rotation_euler = (turn @ cam.rotation_euler.to_quaternion()).to_euler(
        "XYZ", cam.rotation_euler)
    cam.data.lens *= c["lens_factor"]


def save_user_blend(scene, out, clip_path, lamp, extras, name="scene.blend"):
    """Strips the render scene down to what a user would have."""
    bpy.data.objects.remove(lamp)
    # Shake and exposure drift belong to the footage, not to the matched
    # camera: the user has the camera at rest and a fixed exposure. A moving
    # camera keeps its keys (a solve's, key_camera_move).
    if scene.camera.animation_data and "rest_location" not in scene.camera:
        scene.camera.animation_data_clear()
        rest = scene.camera.get("rest_rotation_euler")
        if rest is not None:
            scene.camera.rotation_euler = rest
            del scene.camera["rest_rotation_euler"]
    if scene.animation_data:
        scene.animation_data_clear()
        scene.view_settings.exposure = scene.get("rest_exposure", 0.0)
    if "rest_exposure" in scene:
        del scene["rest_exposure"]
    for ob in list(extras.objects):
        bpy.data.objects.remove(ob)
    bpy.data.collections.remove(extras)
    scene.use_nodes = False
    scene.world = None
    scene.view_layers[0].use_pass_object_index = False
    # The masks' render (render_masks) turned bounces off; a user's file has
    # Blender's own, and the AR render's inserts light their surroundings.
    scene.cycles.max_bounces = type(scene.cycles).bl_rna.properties["max_bounces"].default
    scene.render.image_settings.color_mode = "RGB"
    scene.view_settings.view_transform = "Filmic"
    clip = bpy.data.movieclips.load(clip_path)
    scene.active_clip = clip
    scene.frame_start = clip.frame_start
    scene.frame_end = clip.frame_start + clip.frame_duration - 1
    scene.render.filepath = "//render/"
    path = os.path.join(out, name)
    bpy.ops.wm.save_as_mainfile(filepath=path)
    bpy.ops.file.make_paths_relative()
    bpy.ops.wm.save_mainfile()


if __name__ == "__main__":
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    try:
        main(argv)
    except SystemExit:
        raise
    except Exception as e:
        import traceback
        traceback.print_exc()
        sys.stderr.write(f"generate_scene: error: {type(e).__name__}: {e}\n")
        sys.exit(1)
