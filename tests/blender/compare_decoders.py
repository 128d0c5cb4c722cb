"""The clip as Blender's compositor shows it against the frame the estimate
reads (FFmpeg), per channel, in 8-bit display levels:

  blender -b --factory-startup --python tests/blender/compare_decoders.py -- CLIP [FRAME] [VIEW]

CLIP: a movie file (or a folder with scene.blend from examples/generate_scene.py);
FRAME: 1-based (default 2); VIEW: the view transform (default Standard; Filmic
shows what a default Blender 3.x scene displays)."""
import os
import sys
import tempfile

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(HERE)), "examples"))
sys.path.insert(0, HERE)
import run_estimate  # noqa: E402

run_estimate.load_sunlapse()
import ar_shadow_match  # noqa: E402
from sunlapse.estimate import frames as clip_frames  # noqa: E402
from sunlapse.core import arlight  # noqa: E402

args = sys.argv[sys.argv.index("--") + 1:]
src, frame = args[0], int(args[1]) if len(args) > 1 else 2
view = args[2] if len(args) > 2 else "Standard"
if os.path.isdir(src):
    bpy.ops.wm.open_mainfile(filepath=os.path.join(src, "scene.blend"))
    scene = bpy.context.scene
    clip = scene.active_clip
else:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    clip = bpy.data.movieclips.load(os.path.abspath(src))
    scene.render.resolution_x, scene.render.resolution_y = clip.size
    scene.render.resolution_percentage = 100
scene.use_nodes = True
nt = scene.node_tree
for n in list(nt.nodes):
    nt.nodes.remove(n)
mc = nt.nodes.new("CompositorNodeMovieClip")
mc.clip = clip
nt.links.new(mc.outputs["Image"], nt.nodes.new("CompositorNodeComposite").inputs["Image"])
scene.render.engine = "BLENDER_EEVEE"
scene.view_settings.view_transform = view
scene.view_settings.look = "None"
for o in list(bpy.data.objects):
    o.hide_render = True
work = tempfile.mkdtemp()
fo = nt.nodes.new("CompositorNodeOutputFile")
fo.base_path = work
fo.format.file_format = "OPEN_EXR" if view == "Standard" else "PNG"
fo.file_slots.clear()
fo.file_slots.new("plate")
nt.links.new(mc.outputs["Image"], fo.inputs["plate"])
scene.frame_set(clip.frame_start + frame - 1)
scene.render.filepath = os.path.join(work, "x.png")
bpy.ops.render.render(write_still=True)
tag = f"{clip.frame_start + frame - 1:04d}"
if view == "Standard":  # EXR: linear, encoded here as the display would
    shown = arlight.linear_to_srgb(ar_shadow_match._load_exr(
        os.path.join(work, f"plate{tag}.exr"))[..., :3]) * 255
else:                   # PNG: the view transform applied by Blender
    img = bpy.data.images.load(os.path.join(work, f"plate{tag}.png"))
    w, h = img.size
    shown = np.array(img.pixels[:]).reshape(h, w, -1)[::-1, :, :3] * 255
read = clip_frames.read_frame(bpy.path.abspath(clip.filepath), frame - 1)[..., ::-1].astype(float)
for c, name in enumerate("RGB"):
    a = np.vstack([read[..., c].ravel(), np.ones(read[..., c].size)]).T
    gain, off = np.linalg.lstsq(a, shown[..., c].ravel(), rcond=None)[0]
    print(f"DECODERS {os.path.basename(src)} frame {frame} {view} {name}: blender mean "
          f"{shown[..., c].mean():.1f}, opencv mean {read[..., c].mean():.1f}; blender = "
          f"{gain:.3f} x opencv + {off:.1f}")
