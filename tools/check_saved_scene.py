"""Checks a .blend saved by a scripted run with --apply-lamp --save, in the
Blender that made it, using the add-on installed there (tools/test-packages.sh):

  blender -b SAVED.blend --python tools/check_saved_scene.py -- TRACK.sun.json AR_DIR

- the Sun lamp, frame by frame, points where the track says (every frame the
  track can key, and no other), within TOLERANCE_DEG;
- Set Up AR Render succeeds, compositor included, and one composited frame
  renders into AR_DIR.
Prints one line per check and exits 1 when one fails.
"""
import os
import sys

import bpy

TOLERANCE_DEG = 0.01


def installed_addon():
    """The add-on as Blender loaded it: `sunlapse` (3.x zip) or
    `bl_ext.<repo>.sunlapse` (4.2+ extension)."""
    for name, module in sorted(sys.modules.items()):
        if name.split(".")[-1] == "sunlapse" and hasattr(module, "blender"):
            return module
    raise SystemExit("check: the sunlapse add-on is not enabled in this Blender")


def check_lamp(addon, track_path):
    from importlib import import_module
    trackfile = import_module(addon.__name__ + ".core.trackfile")
    angles = import_module(addon.__name__ + ".core.angles")
    keys = import_module(addon.__name__ + ".blender.keys")
    track = trackfile.read_track(track_path)
    scene = bpy.context.scene
    sun = scene.sunlapse.sun_lamp
    if sun is None:
        return False, "no Sun lamp is set in the saved file"
    keyable = track.keyable()
    keyed = list(sun.get(keys.KEYED_FRAMES_PROP, []))
    if keyed != [f.frame for f in keyable]:
        return False, f"keyed frames {keyed[:5]}... differ from the track's {len(keyable)}"
    worst = 0.0
    for f in keyable:
        scene.frame_set(f.frame)
        lamp_z = sun.matrix_world.col[2][:3]
        azimuth_world = angles.azimuth_world_from_geographic(f.azimuth_deg,
                                                             track.north_offset_deg)
        want = angles.sun_in_world_from_angles(f.zenith_deg, azimuth_world)
        worst = max(worst, angles.angle_between_deg(lamp_z, want))
    ok = worst <= TOLERANCE_DEG and len(keyable) > 0
    return ok, (f"{len(keyable)} frames keyed, the lamp at most {worst:.5f} deg from the "
                f"track (allowed {TOLERANCE_DEG})")


def check_ar(addon, folder):
    from importlib import import_module
    ar = import_module(addon.__name__ + ".blender.ar")
    warnings = []
    summary = ar.setup(bpy.context, warnings=warnings)
    if "compositor not set up" in summary or any("compositor" in w for w in warnings):
        return False, f"AR setup left the compositor out: {summary} {warnings}"
    scene = bpy.context.scene
    scene.cycles.samples = 4
    scene.render.resolution_percentage = 25
    frame = scene.frame_current
    os.makedirs(folder, exist_ok=True)
    ar.render_frames(bpy.context, folder, (frame, frame))
    path = os.path.join(folder, f"ar_{frame:04d}.png")
    if not os.path.exists(path):
        return False, f"AR setup: {summary}; no composited frame at {path}"
    img = bpy.data.images.load(path)
    pixels = list(img.pixels[:4 * 64])
    # The composite lays the clip under the render: not blank.
    lit = max(pixels[i] for i in range(0, len(pixels), 4))
    return lit > 0.05, f"AR setup: {summary}; composited frame {os.path.basename(path)}"


def main():
    track_path, ar_dir = sys.argv[sys.argv.index("--") + 1:][:2]
    addon = installed_addon()
    failed = False
    for name, (ok, text) in (("lamp", check_lamp(addon, track_path)),
                             ("ar", check_ar(addon, ar_dir))):
        print(f"check {name}: {'ok' if ok else 'FAILED'}: {text}", flush=True)
        failed = failed or not ok
    sys.exit(1 if failed else 0)


main()
