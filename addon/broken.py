"""What the add-on registers when it cannot load: its Python lacks numpy,
which every Blender ships. Debian's Blender runs on the first python3.11 on
PATH, so a pyenv, conda or virtualenv Python there hides the system's
packages. Then the sidebar's Sun tab says why and the command line prints
one line and exits 4, never a traceback (bpy and the glue's text helper:
nothing here imports numpy)."""

import sys

import bpy

from .blender.text import wrapped

# Exit code of an incomplete install: cli.EXIT_INTERNAL, as a missing
# native core (cli.py is not imported here: it needs more than bpy).
EXIT_BROKEN = 4
reason = ""  # set by register(), or by examples/run_estimate.py


def numpy_missing(error: ImportError) -> str:
    return (f"this Blender's Python ({sys.prefix}) cannot import numpy ({error}). If "
            "another Python comes first on PATH (pyenv, conda, a virtualenv), Debian's "
            "Blender runs on it: start Blender with /usr/bin first on PATH.")


def _draw(self, context):
    box = self.layout.box()
    box.alert = True
    box.label(text="sunlapse cannot load", icon="ERROR")
    # All of it: the Read All button's operator is not registered here.
    wrapped(box, context, reason, max_lines=40)


def command(argv):
    """`blender -c sunlapse ...` (Blender 4.2+) and examples/run_estimate.py
    when the add-on cannot load: the reason in one line."""
    sys.stderr.write(f"sunlapse: error: {reason}\n")
    return EXIT_BROKEN


_classes = tuple(
    type(f"{prefix}_PT_sunlapse_broken", (bpy.types.Panel,), {
        "bl_idname": f"{prefix}_PT_sunlapse_broken", "bl_space_type": space,
        "bl_region_type": "UI", "bl_category": "Sun", "bl_label": "sunlapse",
        "draw": _draw})
    for space, prefix in (("CLIP_EDITOR", "CLIP"), ("VIEW_3D", "VIEW3D")))


def register(why: str) -> None:
    global reason
    reason = why
    for c in _classes:
        bpy.utils.register_class(c)


def unregister() -> None:
    for c in reversed(_classes):
        bpy.utils.unregister_class(c)
