"""The one Estimate Sun run of this Blender session (a second would race the
first for the stored track): its state, read by the panels and the status
bar, and written by the modal operator and its worker thread."""

import time

import bpy

RUN = {"running": False, "fraction": 0.0, "cancel": False, "outcome": None, "drawn": 0}
# A run whose modal handler has not ticked for this long is taken as ended.
STALE_RUN_S = 10.0


def running() -> bool:
    """Whether a run goes on (one whose handler stopped ticking, after an
    error, is taken as ended)."""
    if RUN["running"] and RUN.get("thread") is not None and \
            time.monotonic() - RUN.get("tick", 0.0) > STALE_RUN_S:
        RUN["running"] = False
    return RUN["running"]


def redraw_all():
    wm = bpy.context.window_manager
    for win in wm.windows:
        for area in win.screen.areas:
            if area.type in ("CLIP_EDITOR", "VIEW_3D", "STATUSBAR"):
                area.tag_redraw()
