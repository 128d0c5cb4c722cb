"""Builds a clip's .blend the way a user would in the add-on: load the clip,
mark the dial's known points as tracking markers named with their ground
coordinates, run "Solve Camera from Marked Points", model the dial.

  blender -b --factory-startup --python-exit-code 1 --python examples/real/make_blend.py -- \
      CLIP MARKS.json OUT.blend --date YYYY-MM-DD --start-time HH:MM [--times TIMES.csv]

MARKS comes from measure_dial.py. Units: the nodus height h = 1 (the real
height is unknown and no angle depends on it). The model is the plate (a
plane; the paving around it is a few centimetres lower, which the plane
ignores), the gnomon as a thin vertical post at the origin and the nodus
ball on its top; its radius (0.13 h) was read from the ball's image.
The clip (and the frames' times file, the panel's Frame Times) is stored
with a path relative to the .blend, so the .blend finds the footage in
../shared/real/ beside the project's work tree without a copy.
"""
import json
import os
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.dirname(HERE))
from run_estimate import load_sunlapse  # noqa: E402

POST_WIDTH = 0.05   # h; the post is about two pixels wide at ~10 h
NODUS_RADIUS = 0.13  # h
PLATE_HALF = 12.0   # h; covers the frame's ground


def parse(argv):
    import argparse
    p = argparse.ArgumentParser(prog="make_blend.py")
    p.add_argument("clip")
    p.add_argument("marks")
    p.add_argument("out")
    p.add_argument("--date", required=True)
    p.add_argument("--start-time", required=True)
    p.add_argument("--utc-offset", type=float, default=1.0)
    p.add_argument("--times", help="CSV of each frame's local time (frame,local_time)")
    return p.parse_args(argv)


def box(name, size, centre, collection):
    import bmesh
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_cube(bm, size=1.0)
    for v in bm.verts:
        v.co = (v.co.x * size[0] + centre[0], v.co.y * size[1] + centre[1],
                v.co.z * size[2] + centre[2])
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def ball(name, radius, centre, collection):
    import bmesh
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=radius)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    obj.location = centre
    collection.objects.link(obj)
    return obj


def mark_points(clip, marks_json):
    """The marks file's points as tracking markers on the clip's first frame,
    named with their world coordinates (what Solve Camera from Marked
    Points reads)."""
    with open(marks_json) as f:
        marks = json.load(f)["marks"]
    w, h = clip.size
    for m in marks:
        track = clip.tracking.tracks.new(name=m["name"], frame=1)
        marker = track.markers.find_frame(1)
        px, py = m["pixel"]
        marker.co = ((px + 0.5) / w, 1.0 - (py + 0.5) / h)


def main():
    args = parse(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    load_sunlapse().register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    clip = bpy.data.movieclips.load(os.path.abspath(args.clip))
    scene.active_clip = clip
    scene.frame_start = clip.frame_start
    scene.frame_end = clip.frame_start + clip.frame_duration - 1
    scene.frame_set(clip.frame_start)
    mark_points(clip, args.marks)
    result = bpy.ops.clip.sunlapse_solve_camera()
    if result != {"FINISHED"}:
        raise SystemExit("make_blend: the camera solve failed")

    model = bpy.data.collections.new("Model")
    scene.collection.children.link(model)
    bpy.ops.mesh.primitive_plane_add(size=2 * PLATE_HALF)
    plate = bpy.context.active_object
    plate.name = "Plate"
    for c in plate.users_collection:
        c.objects.unlink(plate)
    model.objects.link(plate)
    box("Gnomon", (POST_WIDTH, POST_WIDTH, 1.0), (0.0, 0.0, 0.5), model)
    ball("Nodus", NODUS_RADIUS, (0.0, 0.0, 1.0), model)

    s = scene.sunlapse
    s.model_collection = model
    s.camera = scene.camera
    s.ground_objects = "Plate"
    s.ignore_top_rows = 16  # the time stamp and title banner
    s.latitude, s.longitude = 43.3, 5.4
    s.date = args.date
    hh, mm = (int(v) for v in args.start_time.split(":"))
    s.start_hour = hh + mm / 60.0
    s.utc_offset = args.utc_offset
    if args.times:
        out_dir = os.path.dirname(os.path.abspath(args.out))
        s.times_file = "//" + os.path.relpath(os.path.abspath(args.times), out_dir)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=os.path.abspath(args.out), relative_remap=True,
                                compress=True)
    cam = scene.camera
    print(f"make_blend: {args.out}: lens {cam.data.lens:.2f} mm, camera at "
          f"({cam.location.x:.2f}, {cam.location.y:.2f}, {cam.location.z:.2f}) h, "
          f"clip {clip.filepath}")


if __name__ == "__main__":
    main()
