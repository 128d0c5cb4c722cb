"""Builds an AMOS webcam clip's .blend the way a user would in the add-on:
load the frames (an image sequence filled by amos_fetch.py), mark known
points as tracking markers named with their coordinates, run "Solve Camera
from Marked Points", model the casters as coarse boxes, set the place and the
frames' times (Frame Times, UTC).

  blender -b --factory-startup --python-exit-code 1 --python examples/real/make_amos_blend.py -- \
      amos-mulhouse [--footage ../shared/real/amos] [--out examples/real/amos-mulhouse.blend]

Mulhouse, Place de la Reunion (frames of data/webcam/courbevoie): the camera
looks along the old town hall's facade (right) at the end face of the Temple
Saint-Etienne (left) across the square. Units: metres at an assumed camera
height of about 10 m; the scale is a guess and no angle depends on it. Model:
the square's open paving as the ground (the near foreground, with cafe
terraces and palms, is left out), the town hall as a box to its eave with a
steep gable roof (the caster of the big ground shadow of the mornings), the
temple's nave and tower as boxes, and the house beside it as a box. North
(docs/accuracy.md): the model's +Y, the facade's direction, points 28 deg east
of north; it is stored as the Sun Position add-on's north offset (-28 deg),
which a run reads when that add-on is enabled (bench/real.py passes
`--addons sun_position`).
"""
import argparse
import math
import os
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.dirname(HERE))
from run_estimate import load_sunlapse  # noqa: E402
sys.path.insert(0, HERE)
from make_blend import mark_points  # noqa: E402

# (name, x range, y range, z top[, ridge (x, z) for a gable roof along y])
SCENES = {
    "amos-mulhouse": {
        "lens_mm": 31.18,  # 60 deg across 36 mm: assumed (the marks are off one plane)
        "latitude": 47.7467, "longitude": 7.3386,  # Place de la Reunion (47 44'48"N 7 20'19"E)
        # +Y (along the town hall's facade, away from the camera) points 28 deg
        # east of north: Sun Position's north offset is -28 (world azimuth =
        # geographic + offset). Evidence in docs/accuracy.md: the facade's
        # lighting at known times and the Tour de l'Europe's bearing.
        "north_offset_deg": -28.0,
        "ground": ((-62.0, 11.5), (20.0, 81.0)),
        "boxes": [
            ("TownHall", (11.5, 27.5), (-20.0, 112.0), 18.0, (19.5, 29.0)),
            ("TempleNave", (-62.0, -25.0), (81.0, 140.0), 28.0, None),
            ("TempleTower", (-38.0, -25.0), (81.0, 93.0), 50.0, None),
            ("House", (-24.0, -10.0), (81.0, 95.0), 16.0, None),
        ],
    },
    "amos-stlouis": {
        # 604 px across 800 (67 deg): fitted with the camera's height (8 m
        # assumed) to the dome's tip, the Arch's apex and south leg and the
        # portico's base (docs/accuracy.md); the marks are off one plane.
        "lens_mm": 27.18,
        "latitude": 38.6260, "longitude": -90.1905,  # Kiener Plaza
        # x east, y north: the grid (Market Street, the Gateway Mall's axis
        # through the Old Courthouse to the Arch) taken as cardinal.
        "north_offset_deg": 0.0,
        "ground": ((-104.0, -36.0), (-32.0, 20.0)),
        "boxes": [
            ("Courthouse", (-35.0, 35.0), (-20.0, 20.0), 15.5, None),
            ("Tower", (20.0, 40.0), (-56.0, -30.0), 52.0, None),
        ],
        # (name, centre, radius, bottom, top, apex): the dome's drum as an
        # octagonal prism and its cupola as a pyramid to the lantern's tip.
        "domes": [("Dome", (0.0, 0.0), 10.4, 15.5, 42.0, 58.5)],
    },
}


def parse(argv):
    p = argparse.ArgumentParser(prog="make_amos_blend.py")
    p.add_argument("clip", choices=sorted(SCENES))
    p.add_argument("--footage", default=os.path.join(os.path.dirname(ROOT), "shared", "real",
                                                     "amos"))
    p.add_argument("--out")
    return p.parse_args(argv)


def mesh_object(name, verts, faces, collection):
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], faces)
    mesh.update()
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    return obj


def building(name, xr, yr, top, ridge, collection):
    (x0, x1), (y0, y1) = xr, yr
    v = [(x0, y0, 0), (x1, y0, 0), (x1, y1, 0), (x0, y1, 0),
         (x0, y0, top), (x1, y0, top), (x1, y1, top), (x0, y1, top)]
    f = [(0, 3, 2, 1), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
    if ridge is None:
        f.append((4, 5, 6, 7))
    else:
        rx, rz = ridge
        v += [(rx, y0, rz), (rx, y1, rz)]
        f += [(4, 8, 9, 7), (8, 5, 6, 9), (4, 5, 8), (7, 9, 6)]
    return mesh_object(name, v, f, collection)


def dome(name, centre, radius, bottom, top, apex, collection, sides=8):
    import math as m
    cx, cy = centre
    ring = [(cx + radius * m.cos(2 * m.pi * (k + 0.5) / sides),
             cy + radius * m.sin(2 * m.pi * (k + 0.5) / sides)) for k in range(sides)]
    v = [(x, y, bottom) for x, y in ring] + [(x, y, top) for x, y in ring] + [(cx, cy, apex)]
    f = [tuple(range(sides - 1, -1, -1))]
    f += [(k, (k + 1) % sides, sides + (k + 1) % sides, sides + k) for k in range(sides)]
    f += [(sides + k, sides + (k + 1) % sides, 2 * sides) for k in range(sides)]
    return mesh_object(name, v, f, collection)


def main():
    args = parse(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else [])
    spec = SCENES[args.clip]
    out = os.path.abspath(args.out or os.path.join(HERE, f"{args.clip}.blend"))
    load_sunlapse().register()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    clip = bpy.data.movieclips.load(os.path.join(os.path.abspath(args.footage), args.clip,
                                                 "0001.png"))
    scene.active_clip = clip
    scene.frame_start = clip.frame_start
    scene.frame_end = clip.frame_start + clip.frame_duration - 1
    scene.frame_set(clip.frame_start)
    mark_points(clip, os.path.join(HERE, f"{args.clip}.marks.json"))
    if bpy.ops.clip.sunlapse_solve_camera(focal_mm=spec["lens_mm"]) != {"FINISHED"}:
        raise SystemExit("make_amos_blend: the camera solve failed")
    report = scene.sunlapse.last_report

    model = bpy.data.collections.new("Model")
    scene.collection.children.link(model)
    (gx0, gx1), (gy0, gy1) = spec["ground"]
    mesh_object("Ground", [(gx0, gy0, 0), (gx1, gy0, 0), (gx1, gy1, 0), (gx0, gy1, 0)],
                [(0, 1, 2, 3)], model)
    for name, xr, yr, top, ridge in spec["boxes"]:
        building(name, xr, yr, top, ridge, model)
    for name, centre, radius, bottom, top, apex in spec.get("domes", []):
        dome(name, centre, radius, bottom, top, apex, model)

    s = scene.sunlapse
    s.model_collection = model
    s.camera = scene.camera
    s.ground_objects = "Ground"
    s.latitude, s.longitude = spec["latitude"], spec["longitude"]
    s.utc_offset = 0.0
    if spec.get("north_offset_deg") is not None:
        # North is stored where the add-on reads it: Blender's Sun Position
        # add-on (its place set to the same, since the add-on falls back to it).
        import addon_utils
        addon_utils.enable("sun_position", default_set=True)
        sp = scene.sun_pos_properties
        sp.latitude, sp.longitude = spec["latitude"], spec["longitude"]
        sp.north_offset = math.radians(spec["north_offset_deg"])
    times = os.path.join(os.path.abspath(args.footage), f"{args.clip}.times.csv")
    s.times_file = "//" + os.path.relpath(times, os.path.dirname(out))
    bpy.ops.wm.save_as_mainfile(filepath=out, relative_remap=True, compress=True)
    cam = scene.camera
    print(f"make_amos_blend: {out}: {report}; camera at ({cam.location.x:.1f}, "
          f"{cam.location.y:.1f}, {cam.location.z:.1f}); clip {clip.filepath}, "
          f"{clip.frame_duration} frames {clip.size[0]}x{clip.size[1]}")


if __name__ == "__main__":
    main()
