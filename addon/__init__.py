"""sunlapse: find the Sun on every frame of a time-lapse clip.

Registration only; see properties.py, operators.py and panels.py.
"""

bl_info = {
    "name": "sunlapse",
    "author": "sunlapse developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Movie Clip Editor › Sidebar › Sun; 3D View › Sidebar › Sun",
    "description": "Estimate the Sun's direction on every frame of a time-lapse "
                   "clip and animate a Sun lamp for AR renders",
    "doc_url": "",
    "category": "Lighting",
}

if "bpy" in locals():  # script reload (F3 › Reload Scripts)
    import importlib
    for _m in _modules:  # noqa: F821
        importlib.reload(_m)

import bpy  # noqa: E402

from . import broken  # noqa: E402

# Why the add-on cannot work in this Blender ("" when it can): a Python
# without numpy registers broken.py's notice instead of a traceback.
BROKEN = ""
try:
    from . import operators, overlay, panels, properties  # noqa: E402
    _modules: tuple = (properties, operators, panels, overlay)
except ImportError as e:
    if e.name != "numpy":
        raise
    BROKEN = broken.numpy_missing(e)
    _modules = ()
_cli_handle = None


def register():
    global _cli_handle
    if BROKEN:
        broken.register(BROKEN)
    for m in _modules:
        m.register()
    # Blender 4.2+: `blender -c sunlapse SCENE.blend --out TRACK.json ...`
    if bpy.app.version >= (4, 2, 0) and hasattr(bpy.utils, "register_cli_command"):
        if BROKEN:
            _cli_handle = bpy.utils.register_cli_command("sunlapse", broken.command)
        else:
            from . import cli
            _cli_handle = bpy.utils.register_cli_command("sunlapse", cli.command)


def unregister():
    global _cli_handle
    if _cli_handle is not None:
        bpy.utils.unregister_cli_command(_cli_handle)
        _cli_handle = None
    for m in reversed(_modules):
        m.unregister()
    if BROKEN:
        broken.unregister()
