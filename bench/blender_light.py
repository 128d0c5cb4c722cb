"""Run inside Blender by bench/ar_light_stills.py (not on its own):

  blender -b SCENE.blend --python bench/blender_light.py -- ROOT

Estimates the Sun as the panel's Estimate Sun does, then measures the
footage's light as Set Up AR Render does (sunlapse.blender.ar.measure_light,
on the frames it picks), with the add-on of the tree ROOT. Prints one line,
"LIGHT " and JSON: the seconds measure_light took and each frame's measured
shadow/lit ratio (linear R, G, B; null where none was measured).
"""
import json
import os
import sys
import time

import bpy

ROOT = os.path.abspath(sys.argv[sys.argv.index("--") + 1])
sys.path.insert(0, os.path.join(ROOT, "examples"))
import run_estimate  # noqa: E402

run_estimate.load_sunlapse()
if not hasattr(bpy.types.Scene, "sunlapse"):
    sys.modules["sunlapse"].register()
from sunlapse.blender import ar, store  # noqa: E402

if bpy.ops.clip.sunlapse_estimate() != {"FINISHED"}:
    sys.exit("blender_light: Estimate Sun failed")
track = store.load_track()
t0 = time.perf_counter()
samples, _, _, _ = ar.measure_light(bpy.context, track, ar.light_frames(track))
seconds = time.perf_counter() - t0
ratios = {s.frame: (list(s.balance.shadow_ratio) if s.balance else None) for s in samples}
print("LIGHT " + json.dumps({"seconds": seconds, "ratios": ratios}), flush=True)
