"""Driven inside a Blender with a real window (tests/ui/test_ui.py):
  blender --factory-startup [--enable-event-simulate] SCENE.blend --python ui_script.py -- MODE OUT
MODE: modal (run Estimate Sun as a click does, wait, apply, screenshot), esc
(start it and press Esc at once), close (start it, then open the .blend
again, closing the file under the run) or walkthrough (the artist's steps, one
screenshot each into the folder OUT, with what the test checks beside them).
Prints RESULT lines for the test."""
import json
import os
import shutil
import subprocess
import sys

import bpy

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "examples"))
# In another Blender, the packaged core where its extension put it.
if os.environ.get("SUNLAPSE_UI_SYS_PATH"):
    sys.path.insert(0, os.environ["SUNLAPSE_UI_SYS_PATH"])
import run_estimate  # noqa: E402

# The splash (5.x's first-start Quick Setup too) would cover the editors.
bpy.context.preferences.view.show_splash = False
sunlapse = run_estimate.load_sunlapse()
sunlapse.register()
from sunlapse import operators, panels  # noqa: E402
from sunlapse.blender import background, store  # noqa: E402

mode, out = sys.argv[sys.argv.index("--") + 1:][:2]
state = {"polls": 0}


def screenshot(path):
    """Blender's own screenshot; where its read-back of the window comes out
    black (Blender 5.x on Mesa's llvmpipe under Xvfb) the X server's image of
    the screen instead (xwd), which is what a user sees."""
    bpy.ops.screen.screenshot(filepath=path)
    import numpy as np
    img = bpy.data.images.load(path)
    try:
        rgba = np.array(img.pixels[:], dtype=np.float32).reshape(-1, 4)
        blank = rgba.size == 0 or rgba[:, :3].max() == 0.0
    finally:
        bpy.data.images.remove(img)
    if blank and shutil.which("xwd"):
        xwd_to_png(subprocess.run(["xwd", "-root", "-silent"], capture_output=True,
                                  check=True).stdout, path)
        result("screenshot_from", "xwd")


def xwd_to_png(data, path):
    """A 24/32-bit TrueColor X window dump saved as PNG through Blender."""
    import struct
    import numpy as np
    header = struct.unpack(">25I", data[:100])
    size, width, height, bytes_per_line, ncolors = (header[0], header[4], header[5],
                                                    header[12], header[19])
    start = size + 12 * ncolors
    rows = np.frombuffer(data[start:start + bytes_per_line * height], dtype=np.uint8)
    bgrx = rows.reshape(height, bytes_per_line)[:, :4 * width].reshape(height, width, 4)
    rgba = np.ones((height, width, 4), dtype=np.float32)
    rgba[..., :3] = bgrx[..., [2, 1, 0]] / 255.0
    img = bpy.data.images.new("sunlapse screenshot", width, height)
    img.pixels.foreach_set(rgba[::-1].ravel())  # Blender's rows go bottom-up
    img.filepath_raw = path
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)


def result(key, value):
    print(f"RESULT {key} {value}", flush=True)


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
        result("invoke", bpy.ops.clip.sunlapse_estimate("INVOKE_DEFAULT"))
    if mode == "esc":
        for value in ("PRESS", "RELEASE"):
            win.event_simulate(type="ESC", value=value, x=area.x + 50, y=area.y + 50)
    return None


@bpy.app.handlers.persistent
def closed_then(*_):
    """After the file is opened again under the run: wait for the worker,
    then say what happened (the timer survives the load)."""
    state["loaded"] = True


def close_file():
    bpy.app.handlers.load_post.append(closed_then)
    bpy.ops.wm.open_mainfile(filepath=bpy.data.filepath)
    bpy.app.timers.register(after_close, first_interval=0.5, persistent=True)
    return None


def after_close():
    state["polls"] += 1
    thread = background.RUN.get("thread")
    if thread is not None and thread.is_alive() and state["polls"] < 60:
        return 0.5
    result("loaded", state.get("loaded", False))
    result("worker_alive", thread is not None and thread.is_alive())
    result("outcome", json.dumps(background.RUN["outcome"]))
    result("notice_left", "notice" in background.RUN)
    bpy.app.timers.register(lambda: bpy.ops.wm.quit_blender() and None, first_interval=1.0,
                            persistent=True)
    return None


def poll():
    state["polls"] += 1
    track = store.load_track()
    if mode == "close":
        bpy.app.timers.register(close_file, first_interval=0.1, persistent=True)
        return None
    if mode == "esc":
        if background.RUN["running"] and state["polls"] < 60:
            return 0.5
        result("stored", track is not None)
        result("outcome", json.dumps(background.RUN["outcome"]))
        bpy.ops.wm.quit_blender()
        return None
    if track is None and state["polls"] < 120:
        return 0.5
    result("stored", track is not None)
    if track is not None:
        result("moving", "moving_camera" in (track.method.get("options") or {}))
        result("apply", bpy.ops.clip.sunlapse_apply_lamp())
        bpy.app.timers.register(shot, first_interval=1.0)
    else:
        bpy.ops.wm.quit_blender()
    return None


def shot():
    screenshot(out)  # the overlay draws in this redraw
    result("screenshot", os.path.exists(out))
    bpy.ops.wm.quit_blender()


# ---------------------------------------------------------------------------
# The walkthrough: each step leaves OUT/NN_name.png and a record in
# OUT/steps.json of the regions the test checks (window pixels, y up).

steps = []


def region_rect(area, kind):
    r = next(r for r in area.regions if r.type == kind)
    return [r.x, r.y, r.width, r.height]


def statusbar_rect(win):
    """The status bar (a global area, not in screen.areas): the window's
    bottom strip."""
    scale = bpy.context.preferences.system.ui_scale
    return [0, 0, win.width, int(22 * scale)]


def snap(name, **facts):
    path = os.path.join(out, f"{len(steps) + 1:02d}_{name}.png")
    screenshot(path)
    steps.append(dict(name=name, path=path, **facts))
    result("step", name)


def label_fits():
    """Every label, button and property name the sub-panels draw, measured
    with the UI font against the room the sidebar gives it at its width:
    [(text, needed px, available px)] of those that would be cut."""
    import blf
    win, area, _ = clip_area()
    region = next(r for r in area.regions if r.type == "UI")
    scale = bpy.context.preferences.system.ui_scale
    from sunlapse.blender import compat
    size = compat.label_points(bpy.context) * scale
    compat.font_size(size)
    unit = 20 * scale
    # The sidebar keeps a tab column and panel margins; sub-panels indent.
    content = region.width - 1.2 * unit - 1.6 * unit
    cut = []

    class Rec:
        """Stands in for UILayout: records what would be drawn and where."""

        def __init__(self, width, split=False):
            self.width, self.use_property_split, self.use_property_decorate = width, split, False
            self.enabled = self.active = self.alert = True
            self.alignment, self.scale_y, self.scale_x = "EXPAND", 1.0, 1.0
            self._n = 1

        def _child(self, width=None):
            return Rec(self.width if width is None else width, self.use_property_split)

        def column(self, **kw):
            return self._child()

        def box(self):
            return self._child(self.width - 0.5 * unit)

        def row(self, **kw):
            r = self._child()
            r._row = True
            return r

        def split(self, factor=0.5, **kw):
            return self._child(self.width * factor)

        def _need(self, text, icon, avail):
            need = blf.dimensions(0, text)[0] + (unit if icon not in (None, "NONE") else 0) \
                + 0.3 * unit
            if need > avail + 0.5:
                cut.append((text, round(need), round(avail)))

        def label(self, text="", icon="NONE", **kw):
            self._need(text, icon, self.width)

        def operator(self, idname, text=None, icon="NONE", **kw):
            if text is None:
                mod, name = idname.split(".")
                text = getattr(getattr(bpy.ops, mod), name).get_rna_type().name
            self._need(text, icon, self.width)

        def prop(self, data, name, text=None, icon="NONE", **kw):
            p = data.bl_rna.properties[name]
            text = p.name if text is None else text
            if not text:
                return
            if p.type == "BOOLEAN":  # beside its checkbox, in the value column
                avail = (0.6 * self.width if self.use_property_split else self.width) - unit
            elif self.use_property_split:
                avail = 0.4 * self.width
            else:
                avail = 0.45 * self.width
            self._need(text, icon, avail)

        def progress(self, text="", **kw):
            self._need(text, "NONE", self.width - unit)

    class FakePanel:
        pass

    ctx_region = region
    running = dict(background.RUN)
    background.RUN.update(running=True, fraction=0.38, cancel=False)  # its progress row too
    fp = FakePanel()
    fp.layout = Rec(content)
    panels.draw_progress(fp.layout)
    background.RUN.update(running)
    for section in panels._SECTIONS:
        fp = FakePanel()
        fp.layout = Rec(content)
        with bpy.context.temp_override(window=win, area=area, region=ctx_region):
            section[2](fp, bpy.context)
    return cut, region.width


def sun_tab(then, tries=[0]):
    """Ctrl+Wheel over the sidebar cycles its tabs (Blender 3.4 has no
    property for the active one) until the Sun panel draws."""
    win, area, _ = clip_area()
    ui = next(r for r in area.regions if r.type == "UI")
    before = panels.DRAWN.get("CLIP_EDITOR", 0)

    def check():
        if panels.DRAWN.get("CLIP_EDITOR", 0) > before:
            result("sun_tab", tries[0])
            bpy.app.timers.register(then, first_interval=0.3)
            return None
        tries[0] += 1
        if tries[0] > 24:
            screenshot(os.path.join(out, "sun_tab_not_found.png"))  # for the failure
            result("sun_tab", "not found")
            bpy.ops.wm.quit_blender()
            return None
        # Over the region's empty foot: over a field, Ctrl+Wheel edits it.
        x, y = ui.x + ui.width // 2, ui.y + 30
        win.event_simulate(type="MOUSEMOVE", value="NOTHING", x=x, y=y)  # 5.x: hover first
        win.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=x, y=y, ctrl=True)
        nonlocal_before[0] = panels.DRAWN.get("CLIP_EDITOR", 0)
        return 0.4
    nonlocal_before = [before]

    def check2():
        if panels.DRAWN.get("CLIP_EDITOR", 0) > nonlocal_before[0]:
            result("sun_tab", tries[0])
            bpy.app.timers.register(then, first_interval=0.3)
            return None
        return check()
    bpy.app.timers.register(check2, first_interval=0.5)
    return None


def walkthrough():
    win, area, region = clip_area()
    scene = bpy.context.scene
    scene.frame_set(2)
    return sun_tab(walkthrough_steps)


def walkthrough_steps():
    win, area, region = clip_area()
    with bpy.context.temp_override(window=win, area=area, region=region):
        bpy.ops.clip.view_all(fit_view=True)
    with bpy.context.temp_override(window=win, area=area, region=region):
        result("check", bpy.ops.clip.sunlapse_check_scene())
    cut, width = label_fits()
    result("sidebar_width", width)
    result("cut_labels", json.dumps(cut))
    bpy.app.timers.register(step_scene, first_interval=0.5)
    return None


def step_scene():
    win, area, region = clip_area()
    snap("scene_checked", sidebar=region_rect(area, "UI"),
         report=bpy.context.scene.sunlapse.last_report)
    with bpy.context.temp_override(window=win, area=area, region=region):
        result("invoke", bpy.ops.clip.sunlapse_estimate("INVOKE_DEFAULT"))
        # A second start while the first runs is refused.
        try:
            second = bpy.ops.clip.sunlapse_estimate("INVOKE_DEFAULT")
        except RuntimeError as e:
            second = f"error: {e}"
        result("second_invoke", second)
    bpy.app.timers.register(step_running, first_interval=0.3)
    return None


def step_running():
    win = bpy.context.window
    running = background.RUN["running"]
    drawn = background.RUN["drawn"]
    snap("estimating", running=running, drawn=drawn, statusbar=statusbar_rect(win))
    result("running_at_shot", running)
    bpy.app.timers.register(wait_estimate, first_interval=0.5)
    return None


def wait_estimate():
    state["polls"] += 1
    if background.RUN["running"] and state["polls"] < 240:
        return 0.5
    result("outcome", json.dumps(background.RUN["outcome"]))
    result("drawn_during_run", background.RUN["drawn"])
    win, area, region = clip_area()
    with bpy.context.temp_override(window=win, area=area, region=region):
        result("apply", bpy.ops.clip.sunlapse_apply_lamp())
    bpy.app.timers.register(step_estimated, first_interval=1.0)
    return None


def step_estimated():
    win, area, region = clip_area()
    snap("estimated", clip_window=region_rect(area, "WINDOW"), sidebar=region_rect(area, "UI"),
         statusbar=statusbar_rect(win),
         apply=bpy.context.scene.sunlapse.last_apply)
    # The sidebar scrolled down to Lamp and Render (the Apply result).
    ui = next(r for r in area.regions if r.type == "UI")
    for _ in range(12):
        win.event_simulate(type="WHEELDOWNMOUSE", value="PRESS", x=ui.x + ui.width // 2,
                           y=ui.y + ui.height // 2)
    bpy.app.timers.register(step_lamp_panel, first_interval=0.8)
    return None


def step_lamp_panel():
    win, area, region = clip_area()
    snap("lamp_and_render", sidebar=region_rect(area, "UI"))
    with bpy.context.temp_override(window=win, area=area, region=region):
        result("setup_ar", bpy.ops.clip.sunlapse_setup_ar())
    scene = bpy.context.scene
    result("preview_samples", scene.cycles.preview_samples)
    # The AR preview as a user finds it: the same area switched back to the
    # 3D View it was, nothing else done (the view centred for the shot).
    area.type = "VIEW_3D"
    space = area.spaces.active
    space.show_region_ui = False
    scene.cycles.preview_samples = 4  # a 2-core test machine
    with bpy.context.temp_override(window=win, area=area,
                                   region=next(r for r in area.regions if r.type == "WINDOW")):
        bpy.ops.view3d.view_center_camera()
    bpy.app.timers.register(step_ar, first_interval=6.0)
    return None


def camera_frame_in_region(area):
    """The camera's frame (film) corners in window pixels."""
    from bpy_extras.view3d_utils import location_3d_to_region_2d
    region = next(r for r in area.regions if r.type == "WINDOW")
    rv3d = area.spaces.active.region_3d
    cam = bpy.context.scene.camera
    corners = [cam.matrix_world @ v for v in cam.data.view_frame(scene=bpy.context.scene)]
    pts = [location_3d_to_region_2d(region, rv3d, c) for c in corners]
    xs = [p.x + region.x for p in pts if p is not None]
    ys = [p.y + region.y for p in pts if p is not None]
    return [min(xs), min(ys), max(xs), max(ys)]


def step_ar():
    win = bpy.context.window
    area = next(a for a in win.screen.areas if a.type == "VIEW_3D")
    space = area.spaces.active
    sun = bpy.context.scene.sunlapse.sun_lamp
    snap("ar_preview", camera_frame=camera_frame_in_region(area), shading=space.shading.type,
         perspective=space.region_3d.view_perspective, clip=bpy.path.abspath(
             bpy.context.scene.active_clip.filepath), frame=bpy.context.scene.frame_current,
         sun_in_camera_frame=in_camera_view(sun))
    with open(os.path.join(out, "steps.json"), "w") as fh:
        json.dump(steps, fh, indent=1)
    result("blender", bpy.app.version[0])
    result("steps", len(steps))
    bpy.ops.wm.quit_blender()
    return None


def in_camera_view(obj):
    from bpy_extras.object_utils import world_to_camera_view
    scene = bpy.context.scene
    co = world_to_camera_view(scene, scene.camera, obj.matrix_world.translation)
    return bool(0 <= co.x <= 1 and 0 <= co.y <= 1 and co.z > 0)


if mode in ("esc", "close"):
    # A tiny clip is estimated in well under a second, before the Esc event
    # is even handled: each progress call is slowed down so that the worker
    # is still running when the cancel reaches it (as on a real clip).
    import time
    _run = operators.estimate_run.run

    def slow_run(*args, **kwargs):
        progress = args[6] if len(args) > 6 else kwargs.get("progress")
        if progress is not None:
            def slowed(fraction):
                time.sleep(0.3)
                return progress(fraction)
            args = args[:6] + (slowed,) + args[7:] if len(args) > 6 else args
            kwargs = dict(kwargs, progress=slowed) if "progress" in kwargs else kwargs
        return _run(*args, **kwargs)
    operators.estimate_run.run = slow_run

if mode == "walkthrough":
    os.makedirs(out, exist_ok=True)
    bpy.app.timers.register(walkthrough, first_interval=2.0)
else:
    bpy.app.timers.register(start, first_interval=2.0)
    bpy.app.timers.register(poll, first_interval=3.0)
