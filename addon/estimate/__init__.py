"""bpy-free estimation controllers over the native core."""
