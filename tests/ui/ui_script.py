"""Driven inside a Blender with a real window (tests/ui/test_ui.py):
  blender --factory-startup [--enable-event-simulate] SCENE.blend --python ui_script.py -- MODE OUT
MODE: modal (run Estimate Sun as a click does, wait, apply, screenshot) or
esc (start it and press Esc at once). Prints RESULT lines for the test."""
import os
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples"))
import run_estimate  # noqa: E402

sunlapse = run_estimate.load_sunlapse()
sunlapse.register()
from sunlapse import results  # noqa: E402

mode, out = sys.argv[sys.argv.index("--") + 1:][:2]
state = {"polls": 0}


def clip_area():
    win = bpy.context.window
    area = max(win.screen.areas, key=lambda a: a.width * a.height)
    area.type = "CLIP_EDITOR"
    area.spaces.active.clip = bpy.context.scene.active_clip
    area.spaces.active.show_region_ui = True
    return win, area, next(r for r in area.regions if r.type == "WINDOW")


def start():
    win, area, region = clip_area()
    bpy.context.scene.frame_set(2)
    with bpy.context.temp_override(window=win, area=area, region=region):
        print("RESULT invoke", bpy.ops.clip.sunlapse_estimate("INVOKE_DEFAULT"), flush=True)
    if mode == "esc":
        for value in ("PRESS", "RELEASE"):
            win.event_simulate(type="ESC", value=value, x=area.x + 50, y=area.y + 50)
    return None


def poll():
    state["polls"] += 1
    track = results.load_track()
    if mode == "esc":
        if state["polls"] < 8:
            return 0.5
        print("RESULT stored", track is not None, flush=True)
        bpy.ops.wm.quit_blender()
        return None
    if track is None and state["polls"] < 120:
        return 0.5
    print("RESULT stored", track is not None, flush=True)
    if track is not None:
        print("RESULT apply", bpy.ops.clip.sunlapse_apply_lamp(), flush=True)
        bpy.app.timers.register(shot, first_interval=1.0)
    else:
        bpy.ops.wm.quit_blender()
    return None


def shot():
    bpy.ops.screen.screenshot(filepath=out)  # the overlay draws in this redraw
    print("RESULT screenshot", os.path.exists(out), flush=True)
    bpy.ops.wm.quit_blender()


bpy.app.timers.register(start, first_interval=2.0)
bpy.app.timers.register(poll, first_interval=3.0)
