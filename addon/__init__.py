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
    for _m in (native_loader, properties, operators, panels):  # noqa: F821
        importlib.reload(_m)

import bpy  # noqa: E402

from . import native_loader, operators, panels, properties  # noqa: E402

_modules = (properties, operators, panels)


def register():
    for m in _modules:
        m.register()


def unregister():
    for m in reversed(_modules):
        m.unregister()
