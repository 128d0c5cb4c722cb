"""How well an AR insert's shadow matches the footage's real shadows.

Inside Blender, on a generated preset (examples/generate_scene.py): the
artist's path (Estimate Sun, Apply, Set Up AR Render), then one small render
of frame F with the plate, the composite, the Shadow Catcher pass and the
inserts' alpha written beside it as EXR. Per channel, in display values:

  insert:  composite / plate over the core of the insert's shadow
  real:    plate in the real cast shadows (the generator's truth mask)
           over the plate on the lit ground within a few pixels of them

Used by test_user_path.py; prints the figures in docs/accuracy.md when run as
  blender -b --factory-startup --python tests/blender/ar_shadow_match.py -- PRESET_DIR [FRAME]
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


def render_and_measure(preset_dir, frame, work, samples=32, estimate=True):
    """Runs the artist's path on preset_dir/scene.blend and measures frame
    `frame`; returns a dict of per-channel ratios (insert, real) and counts."""
    from sunlapse.blender import gather, job, lamp
    from sunlapse.estimate import notes
    from sunlapse.core import arlight, trackfile
    bpy.ops.wm.open_mainfile(filepath=os.path.join(preset_dir, "scene.blend"))
    import run_estimate  # noqa: F401  (examples/ on sys.path)
    if not hasattr(bpy.types.Scene, "sunlapse"):
        sys.modules["sunlapse"].register()
    scene = bpy.context.scene
    if estimate:
        assert bpy.ops.clip.sunlapse_estimate() == {"FINISHED"}
    assert bpy.ops.clip.sunlapse_apply_lamp() == {"FINISHED"}
    assert bpy.ops.clip.sunlapse_setup_ar() == {"FINISHED"}
    insert = bpy.data.objects[gather.INSERT_NAME]
    insert.scale = (INSERT_SCALE,) * 3
    scene.cycles.samples = samples
    scene.cycles.use_denoising = False
    scene.frame_set(frame)
    _file_outputs(scene, work)
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
    insert_ratio = np.median(comp[core] / np.maximum(plate[core], 1e-6), axis=0)

    # The real shadows: the generator's truth mask on the model's ground.
    truth = trackfile.read_track(os.path.join(preset_dir, "truth.sun.json"))
    masks = truth.extra["shadow_masks"]
    mask_frame = min((int(k) for k in masks), key=lambda k: abs(k - frame))
    real_shadow = _load_png_gray(os.path.join(preset_dir, masks[str(mask_frame)])) > 0.5
    settings = scene.sunlapse
    model, cam, clip = job.gather_all(bpy.context, settings)
    ids = model.ids_of(truth.extra["ground_objects"])
    t = truth.frame(mask_frame)
    sun = tuple(float(v) for v in lamp.sun_vector(t.zenith_deg,
                                                  t.azimuth_deg + truth.north_offset_deg))
    ground, _ = notes.ground_and_model_shadow(gather.build_scene(model), gather.build_camera(cam),
                                              ids, sun)
    ground = (ground > 0) & free & ~arlight.dilate(shade, 1)
    dark = arlight.erode(real_shadow, 1) & ground
    band = max(4, round(ground.shape[1] / 25))
    lit = arlight.dilate(real_shadow, band) & ~arlight.dilate(real_shadow, 2) & ground
    real_ratio = np.median(plate[dark], axis=0) / np.median(plate[lit], axis=0)
    # The plate as the composite shows it against the frame the estimate
    # reads (OpenCV): 8-bit display levels.
    from sunlapse.estimate import frames as clip_frames
    bgr = clip_frames.read_frame(clip.filepath, frame - clip.frame_start)
    plate_levels = np.abs(plate * 255.0 - bgr[..., ::-1].astype(np.float64))
    return {"insert": [float(x) for x in insert_ratio], "real": [float(x) for x in real_ratio],
            "plate_vs_reader_mean": float(plate_levels.mean()),
            "plate_vs_reader_max": float(plate_levels.max()),
            "insert_px": int(core.sum()), "real_px": int(dark.sum()), "lit_px": int(lit.sum()),
            "frame": frame}


if __name__ == "__main__":
    sys.path.insert(0, os.path.join(ROOT, "examples"))
    sys.path.insert(0, HERE)
    import tempfile
    import run_estimate
    run_estimate.load_sunlapse()
    args = sys.argv[sys.argv.index("--") + 1:]
    frame = int(args[1]) if len(args) > 1 else 1
    with tempfile.TemporaryDirectory() as work:
        r = render_and_measure(os.path.abspath(args[0]), frame, work)
    diff = max(abs(a - b) for a, b in zip(r["insert"], r["real"]))
    print("AR_SHADOW {} frame {}: insert R/G/B {:.2f}/{:.2f}/{:.2f} real {:.2f}/{:.2f}/{:.2f} "
          "max diff {:.3f} ({} insert px, {} real shadow px); plate vs OpenCV reader: mean "
          "{:.2f}, max {:.0f} levels".format(
              os.path.basename(os.path.normpath(args[0])), frame, *r["insert"], *r["real"], diff,
              r["insert_px"], r["real_px"], r["plate_vs_reader_mean"], r["plate_vs_reader_max"]))
