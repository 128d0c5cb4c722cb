"""Times gathering a ~1M-triangle model from Blender and building the BVH.

  blender -b --factory-startup --python bench/bench_gather.py
"""
import os
import sys
import time

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(ROOT, "examples"))
import run_estimate  # noqa: E402

run_estimate.load_sunlapse()
from sunlapse.blender import gather  # noqa: E402

bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_grid_add(x_subdivisions=708, y_subdivisions=708, size=100)
grid = bpy.context.active_object
grid.modifiers.new("wave", "WAVE")  # an evaluated modifier, as users have
bpy.context.view_layer.update()
t0 = time.perf_counter()
model = gather.gather_model(bpy.context)
t1 = time.perf_counter()
scene = gather.build_scene(model)
t2 = time.perf_counter()
print(f"gather: {model.num_triangles} triangles in {t1 - t0:.3f} s")
print(f"bvh_build: {t2 - t1:.3f} s")
print(f"gather_and_build: {t2 - t0:.3f} s")
