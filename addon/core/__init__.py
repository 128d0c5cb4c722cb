"""bpy-free parts of sunlapse: usable and testable without Blender."""
