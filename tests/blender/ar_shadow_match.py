"""How well an AR insert's shadow matches the footage's real shadows.

Inside Blender, on a generated preset (examples/generate_scene.py): the
artist's path (Estimate Sun, Apply, Set Up AR Render), then one small render
of frame F with the plate, the composite, the Shadow Catcher pass and the
inserts' alpha written beside it as EXR. Per channel, in display values:

  insert:  composite / plate over the core of the insert's shadow
  real:    plate in the real cast shadows (the generator's truth mask)
           over the plate on the lit ground within a few pixels of them

Used by test_user_path.py and bench/ar_light.py; prints the figures in
docs/accuracy.md when run as
  blender -b --factory-startup --python tests/blender/ar_shadow_match.py -- PRESET_DIR [FRAME]
With FRAME "all" it measures every frame against the model's shadow toward
the frame's true Sun and prints one JSON line per frame (AR_FRAME {...}).
"""
import os
import sys

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))

# The sample insert is scaled up so its shadow covers enough pixels of a
# tiny (128x96) render to measure.
INSERT_SCALE = 3.0
# The insert's shadow: where the catcher keeps less than this (its sky
# occlusion darkens the ground around it by a few percent, not a shadow).
CATCHER_SHADOW = 0.85


def _load_exr(path):
    img = bpy.data.images.load(path)
    px = np.array(img.pixels[:], dtype=np.float64).reshape(img.size[1], img.size[0], -1)
    bpy.data.images.remove(img)
    return px[::-1]  # top row first, as the masks


def _load_png_gray(path):
    img = bpy.data.images.load(path)
    img.colorspace_settings.name = "Non-Color"
    px = np.array(img.pixels[:], dtype=np.float64).reshape(img.size[1], img.size[0], -1)
    bpy.data.images.remove(img)
    return px[::-1, :, 0]


def _file_outputs(scene, folder):
    nt = scene.node_tree
    rl = next(n for n in nt.nodes if n.bl_idname == "CompositorNodeRLayers")
    mc = nt.nodes["sunlapse clip"]
    over = nt.nodes["sunlapse over clip"]
    fo = nt.nodes.new("CompositorNodeOutputFile")
    fo.base_path = folder
    fo.format.file_format = "OPEN_EXR"
    fo.format.color_depth = "32"
    fo.file_slots.clear()
    for name, socket in (("plate", mc.outputs["Image"]), ("composite", over.outputs["Image"]),
                         ("catcher", rl.outputs["Shadow Catcher"]), ("alpha", rl.outputs["Alpha"])):
        fo.file_slots.new(name)
        nt.links.new(socket, fo.inputs[name])


def artist_path(preset_dir, samples=32, estimate=True):
    """Opens preset_dir/scene.blend and runs the artist's path on it:
    Estimate Sun, Apply to Sun Lamp, Set Up AR Render; the sample insert
    scaled up to cast a measurable shadow."""
    from sunlapse.blender import gather
    bpy.ops.wm.open_mainfile(filepath=os.path.join(preset_dir, "scene.blend"))
    import run_estimate  # noqa: F401  (examples/ on sys.path)
    if not hasattr(bpy.types.Scene, "sunlapse"):
        sys.modules["sunlapse"].register()
    scene = bpy.context.scene
    if scene.cycles.max_bounces == 0:
        # Suite scenes rendered before 2026-11-28 kept the mask render's 0
        # bounces in the user's file; a user's file has Blender's own.
        scene.cycles.max_bounces = type(scene.cycles).bl_rna.properties["max_bounces"].default
    if estimate:
        assert bpy.ops.clip.sunlapse_estimate() == {"FINISHED"}
    assert bpy.ops.clip.sunlapse_apply_lamp() == {"FINISHED"}
    assert bpy.ops.clip.sunlapse_setup_ar() == {"FINISHED"}
    insert = bpy.data.objects[gather.INSERT_NAME]
    insert.scale = (INSERT_SCALE,) * 3
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False


def _render_model_casting(scene, frame, work, ground_names):
    """Shadow Catcher pass (linear) of `frame` with the model's casters
    casting (rendered as objects, not catchers) and the inserts hidden: the
    model itself as the insert, whose real shadow the footage shows."""
    from sunlapse.blender import gather
    ground = set(ground_names)
    casters = [o for o in bpy.data.objects
               if o.type == "MESH" and o.is_shadow_catcher and o.name not in ground]
    inserts = [o for o in bpy.data.objects if gather.is_insert(o)]
    for o in casters:
        o.is_shadow_catcher = False
        o.update_tag()  # else Cycles keeps the object as it synced it last render
    for o in inserts:
        o.hide_render = True
    try:
        folder = os.path.join(work, "model")
        fo = next(n for n in scene.node_tree.nodes if n.bl_idname == "CompositorNodeOutputFile")
        fo.base_path = folder
        bpy.ops.render.render(write_still=True)
        return _load_exr(os.path.join(folder, f"catcher{frame:04d}.exr"))[..., :3]
    finally:
        for o in casters:
            o.is_shadow_catcher = True
            o.update_tag()
        for o in inserts:
            o.hide_render = False


def measure_frame(preset_dir, frame, work, truth_masks=True, model_casting=False):
    """Renders frame `frame` of the scene artist_path set up and measures
    it; returns a dict of per-channel ratios (insert, real; real is None
    where the footage shows no measurable shadow, insert None where the
    insert casts none) and counts. The real shadows are the generator's
    truth mask nearest the frame (truth_masks) or the model's cast shadow
    toward the true Sun of the frame. With model_casting, "model" is the
    same ratio of a second render in which the model's casters cast their
    own shadows (_render_model_casting) over the real shadows' pixels."""
    from sunlapse.blender import gather, job, lamp
    from sunlapse.estimate import notes
    from sunlapse.core import arlight, trackfile
    scene = bpy.context.scene
    scene.frame_set(frame)
    if not any(n.bl_idname == "CompositorNodeOutputFile" for n in scene.node_tree.nodes):
        _file_outputs(scene, work)
    fo = next(n for n in scene.node_tree.nodes if n.bl_idname == "CompositorNodeOutputFile")
    fo.base_path = work
    scene.render.filepath = os.path.join(work, "render.png")
    bpy.ops.render.render(write_still=True)
    tag = f"{frame:04d}.exr"
    plate = arlight.linear_to_srgb(_load_exr(os.path.join(work, "plate" + tag))[..., :3])
    comp = arlight.linear_to_srgb(_load_exr(os.path.join(work, "composite" + tag))[..., :3])
    catcher = _load_exr(os.path.join(work, "catcher" + tag))[..., :3].mean(axis=2)
    alpha = _load_exr(os.path.join(work, "alpha" + tag))[..., 0]

    # The insert's shadow: where the catcher darkens and no insert covers.
    free = alpha < 0.01
    shade = (catcher < CATCHER_SHADOW) & free
    core = arlight.erode(shade, 1) if arlight.erode(shade, 1).sum() >= 6 else shade
    insert_ratio = (np.median(comp[core] / np.maximum(plate[core], 1e-6), axis=0)
                    if core.any() else None)

    truth = trackfile.read_track(os.path.join(preset_dir, "truth.sun.json"))
    settings = scene.sunlapse
    model, cam, clip = job.gather_all(bpy.context, settings)
    ids = model.ids_of(truth.extra["ground_objects"])
    masks = truth.extra["shadow_masks"]
    mask_frame = min((int(k) for k in masks), key=lambda k: abs(k - frame)) if truth_masks \
        else frame
    t = truth.frame(mask_frame)
    sun = tuple(float(v) for v in lamp.sun_vector(t.zenith_deg,
                                                  t.azimuth_deg + truth.north_offset_deg))
    ground, cast = notes.ground_and_model_shadow(gather.build_scene(model),
                                                 gather.build_camera(cam), ids, sun)
    if truth_masks:
        real_shadow = _load_png_gray(os.path.join(preset_dir, masks[str(mask_frame)])) > 0.5
    else:
        real_shadow = (cast > 0) if t.zenith_deg < 90.0 else np.zeros_like(cast, bool)
    ground = (ground > 0) & free & ~arlight.dilate(shade, 1)
    dark = arlight.erode(real_shadow, 1) & ground
    band = max(4, round(ground.shape[1] / 25))
    lit = arlight.dilate(real_shadow, band) & ~arlight.dilate(real_shadow, 2) & ground
    measurable = dark.sum() >= arlight.MIN_PIXELS and lit.sum() >= arlight.MIN_PIXELS
    real_ratio = (np.median(plate[dark], axis=0) / np.median(plate[lit], axis=0)
                  if measurable else None)
    model_ratio = model_open_ratio = None
    if model_casting and measurable:
        # The catcher's darkening where the real shadows are against its
        # darkening on the lit ground beside them (the casters hide some
        # sky from that ground too, as the real ones do from the footage's),
        # shown on that lit ground: display values, as the real ratio.
        catcher_model = _render_model_casting(scene, frame, work, truth.extra["ground_objects"])
        lit_linear = np.median(arlight.srgb_to_linear(plate[lit]), axis=0)
        darkening = np.median(catcher_model[dark], axis=0)
        beside = np.maximum(np.median(catcher_model[lit], axis=0), 1e-6)
        shown = np.maximum(arlight.linear_to_srgb(lit_linear), 1e-6)
        model_ratio = arlight.linear_to_srgb(lit_linear * darkening / beside) / shown
        # The same against open ground (the measure before 2026-11-28).
        model_open_ratio = arlight.linear_to_srgb(lit_linear * darkening) / shown
    # The plate as the composite shows it against the frame the estimate
    # reads (OpenCV): 8-bit display levels.
    from sunlapse.estimate import frames as clip_frames
    bgr = clip_frames.read_frame(clip.filepath, frame - clip.frame_start)
    plate_levels = np.abs(plate * 255.0 - bgr[..., ::-1].astype(np.float64))

    def listed(v):
        return None if v is None else [float(x) for x in v]
    return {"insert": listed(insert_ratio), "real": listed(real_ratio),
            "model": listed(model_ratio), "model_open": listed(model_open_ratio),
            "plate_vs_reader_mean": float(plate_levels.mean()),
            "plate_vs_reader_max": float(plate_levels.max()),
            "insert_px": int(core.sum()), "real_px": int(dark.sum()), "lit_px": int(lit.sum()),
            "frame": frame, "sun_elevation_deg": 90.0 - t.zenith_deg,
            "lamp_energy": float(settings.sun_lamp.data.energy) if settings.sun_lamp else None}


def render_and_measure(preset_dir, frame, work, samples=32, estimate=True):
    """artist_path, then measure_frame against the truth masks."""
    artist_path(preset_dir, samples, estimate)
    return measure_frame(preset_dir, frame, work)


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    sys.path.insert(0, HERE)
    import json
    import tempfile
    import run_estimate
    run_estimate.load_sunlapse()
    args = sys.argv[sys.argv.index("--") + 1:]
    preset = os.path.abspath(args[0])
    if len(args) > 1 and args[1] == "all":
        artist_path(preset, samples=int(args[2]) if len(args) > 2 else 32)
        scene = bpy.context.scene
        for f in range(scene.frame_start, scene.frame_end + 1):
            with tempfile.TemporaryDirectory() as work:
                print("AR_FRAME " + json.dumps(measure_frame(preset, f, work, truth_masks=False,
                                                             model_casting=True)), flush=True)
        sys.exit(0)
    frame = int(args[1]) if len(args) > 1 else 1
    with tempfile.TemporaryDirectory() as work:
        r = render_and_measure(preset, frame, work)
    diff = max(abs(a - b) for a, b in zip(r["insert"], r["real"]))
    print("AR_SHADOW {} frame {}: insert R/G/B {:.2f}/{:.2f}/{:.2f} real {:.2f}/{:.2f}/{:.2f} "
          "max diff {:.3f} ({} insert px, {} real shadow px); plate vs OpenCV reader: mean "
          "{:.2f}, max {:.0f} levels".format(
              os.path.basename(os.path.normpath(args[0])), frame, *r["insert"], *r["real"], diff,
              r["insert_px"], r["real_px"], r["plate_vs_reader_mean"], r["plate_vs_reader_max"]))
