import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
# bpy-free modules of the add-on, importable without Blender.
sys.path.insert(0, os.path.join(ROOT, "addon"))
