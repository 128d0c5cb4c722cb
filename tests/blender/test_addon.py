"""Registration, the panel and the Check Scene operator; the scripted entry."""
import json
import os
import subprocess

import bpy
import pytest

import scenes
from conftest import ROOT, sunlapse


def test_register_and_unregister_leave_nothing_behind(empty_scene):
    assert hasattr(bpy.types.Scene, "sunlapse")
    assert hasattr(bpy.types, "CLIP_PT_sunlapse")
    assert "sunlapse_check_scene" in dir(bpy.ops.clip)
    sunlapse.unregister()
    try:
        assert not hasattr(bpy.types.Scene, "sunlapse")
        assert not hasattr(bpy.types, "CLIP_PT_sunlapse")
        assert not hasattr(bpy.types, "VIEW3D_PT_sunlapse")
        assert not hasattr(bpy.types, "SunlapseSettings")
        assert "sunlapse_check_scene" not in dir(bpy.ops.clip)
        from sunlapse.blender import store
        assert store.invalidate not in bpy.app.handlers.load_post
    finally:
        sunlapse.register()


def test_check_scene_operator_reports_a_valid_scene(empty_scene, tmp_path):
    scene = empty_scene
    scene.render.resolution_x, scene.render.resolution_y = 64, 48
    scenes.add_box_on_plane(scene)
    scenes.add_camera(scene, (0, -12, 6), (0, 0, 0))
    scenes.load_clip(scene, scenes.write_frames(str(tmp_path / "f")))
    assert bpy.ops.clip.sunlapse_check_scene() == {"FINISHED"}
    assert "26 triangles in 3 objects" in scene.sunlapse.last_report
    assert "ground: Ground" in scene.sunlapse.last_report


def test_check_scene_warns_about_a_model_with_no_ground(empty_scene, tmp_path):
    """A lone box (the default cube) and a camera: Check Scene said all was
    well; Estimate Sun then stopped at "no ground"."""
    scene = empty_scene
    scene.render.resolution_x, scene.render.resolution_y = 64, 48
    scenes.add_box_on_plane(scene)
    bpy.data.objects.remove(bpy.data.objects["Ground"])
    scenes.add_camera(scene, (0, -12, 6), (0, 0, 0))
    scenes.load_clip(scene, scenes.write_frames(str(tmp_path / "f")))
    assert bpy.ops.clip.sunlapse_check_scene() == {"FINISHED"}
    report = scene.sunlapse.last_report
    assert "'Box' is taken for the ground, but only 33% of it is horizontal" in report


def test_check_scene_operator_cancels_without_camera(empty_scene, tmp_path):
    scenes.add_box_on_plane(empty_scene)
    scenes.load_clip(empty_scene, scenes.write_frames(str(tmp_path / "f")))
    with pytest.raises(RuntimeError, match="no camera"):
        # In background mode a reported ERROR surfaces as RuntimeError.
        bpy.ops.clip.sunlapse_check_scene()


# ---------------------------------------------------------------------------
# examples/run_estimate.py, run as a user would, in a separate Blender.

def make_blend(tmp_path, camera=True, model=True, clip=True):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 64, 48
    if model:
        scenes.add_box_on_plane(scene)
    if camera:
        scenes.add_camera(scene, (0, -12, 6), (0, 0, 0))
    if clip:
        scenes.load_clip(scene, scenes.write_frames(str(tmp_path / "frames")))
    path = str(tmp_path / "scene.blend")
    bpy.ops.wm.save_as_mainfile(filepath=path)
    return path


def run_estimate(blend, out, *extra):
    cmd = [bpy.app.binary_path, "-b", "--factory-startup", blend, "--python-exit-code", "1",
           "--python", os.path.join(ROOT, "examples", "run_estimate.py"), "--", "--out", out,
           *extra]
    return subprocess.run(cmd, capture_output=True, text=True, timeout=300)


def error_lines(proc):
    return [line for line in proc.stderr.splitlines() if line.startswith("sunlapse: error:")]


def test_scripted_run_writes_a_track_for_a_valid_scene(empty_scene, tmp_path):
    blend = make_blend(tmp_path)
    out = str(tmp_path / "out.sun.json")
    proc = run_estimate(blend, out)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(out))
    assert track["format"] == "sunlapse.track" and track["version"] == 1
    assert [f["frame"] for f in track["frames"]] == [1, 2, 3]
    # Flat grey frames cannot fix the Sun: whatever comes out has almost no
    # confidence; later frames wait for shadow tracking and say so.
    assert track["frames"][0]["confidence"] < 0.1
    assert track["method"]["confidence"] == "probability within 2 deg"
    assert all(f["reason"] for f in track["frames"][1:])
    assert track["clip"].endswith("frame_0001.png")
    # The user is told why, in words.
    warnings = [line for line in proc.stdout.splitlines()
                if line.startswith("sunlapse: warning:")]
    assert warnings and "no frame shows shadows the model can cast" in warnings[-1]


@pytest.mark.parametrize("missing,reason", [
    ("camera", "no camera"), ("model", "model is empty"), ("clip", "No clip")])
def test_scripted_run_fails_with_one_line_reason(empty_scene, tmp_path, missing, reason):
    blend = make_blend(tmp_path, **{missing: False})
    out = str(tmp_path / "out.sun.json")
    proc = run_estimate(blend, out)
    assert proc.returncode not in (0, None)
    lines = error_lines(proc)
    assert len(lines) == 1 and reason in lines[0], proc.stderr
    assert not os.path.exists(out)


def test_a_blender_python_without_numpy_is_a_one_line_error(empty_scene, tmp_path):
    """Debian's Blender run from a shell whose PATH starts with another
    Python (pyenv, conda) cannot import numpy: it was a traceback from the
    add-on's import. numpy is hidden here as that Python hides it."""
    blend = make_blend(tmp_path)
    out = str(tmp_path / "out.sun.json")
    cmd = [bpy.app.binary_path, "-b", "--factory-startup", blend, "--python-exit-code", "1",
           "--python-expr", "import sys; sys.modules['numpy'] = None",
           "--python", os.path.join(ROOT, "examples", "run_estimate.py"), "--", "--out", out]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 4, proc.stdout + proc.stderr
    lines = error_lines(proc)
    assert len(lines) == 1 and "cannot import numpy" in lines[0] and "PATH" in lines[0]
    assert "Traceback" not in proc.stdout + proc.stderr
    assert not os.path.exists(out)


def test_a_blender_python_without_numpy_registers_a_notice_not_a_traceback(tmp_path):
    """The add-on enabled in such a Blender: the Sun tab says why (and
    where the Python came from), registering and unregistering raise
    nothing."""
    check = "\n".join([
        "import importlib.util, sys, bpy",
        f"addon = {os.path.join(ROOT, 'addon')!r}",
        "spec = importlib.util.spec_from_file_location('sunlapse', addon + '/__init__.py',",
        "                                              submodule_search_locations=[addon])",
        "m = importlib.util.module_from_spec(spec); sys.modules['sunlapse'] = m",
        "spec.loader.exec_module(m)",
        "m.register()",
        "print('REASON', m.BROKEN)",
        "t = bpy.types",
        "print('PANELS', hasattr(t, 'CLIP_PT_sunlapse_broken'),",
        "      hasattr(t, 'VIEW3D_PT_sunlapse_broken'), hasattr(t, 'CLIP_PT_sunlapse'))",
        "m.unregister()",
        "print('GONE', hasattr(bpy.types, 'CLIP_PT_sunlapse_broken'))"])
    cmd = [bpy.app.binary_path, "-b", "--factory-startup", "--python-exit-code", "1",
           "--python-expr", "import sys; sys.modules['numpy'] = None", "--python-expr", check]
    proc = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    out = proc.stdout + proc.stderr
    assert proc.returncode == 0 and "Traceback" not in out, out
    assert "REASON this Blender's Python" in out and "cannot import numpy" in out, out
    assert "PANELS True True False" in out and "GONE False" in out, out


def test_a_camera_that_sees_no_model_is_a_one_line_user_error(empty_scene, tmp_path):
    """It was "internal error: ValueError ..." with a traceback (exit 4)."""
    blend = make_blend(tmp_path, camera=False)
    bpy.ops.wm.open_mainfile(filepath=blend)
    scenes.add_camera(bpy.context.scene, (0, -12, 6), (0, -40, 6))  # looking away
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    out = str(tmp_path / "out.sun.json")
    proc = run_estimate(blend, out)
    assert proc.returncode == 3, proc.stdout + proc.stderr
    lines = error_lines(proc)
    assert len(lines) == 1 and "sees none of the model" in lines[0], proc.stderr
    assert "Traceback" not in proc.stdout + proc.stderr
    assert not os.path.exists(out)
    # Check Scene says the same, as an error, before any run.
    with pytest.raises(RuntimeError, match="sees none of the model"):
        bpy.ops.clip.sunlapse_check_scene()


def test_camera_motion_is_measured_from_the_evaluated_poses(empty_scene):
    """Issue 26: a camera keyed per frame (a slider's, as a solve delivers
    it) was read on one frame, and the track came out 66 deg off on
    average, without a word. Whether it moves, and how far, is decided from
    its poses (the run then sees each frame from its own, and Check Scene
    says so); one keyed still, or with a solve's jitter, stays put."""
    import math
    from sunlapse.blender import gather
    scene = empty_scene
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    scene.camera = cam
    for f, x, yaw in ((1, 0.0, 0.0), (60, 0.7, 30.0)):
        cam.location = (x, -8.0, 5.0)
        cam.rotation_euler = (math.radians(60.0), 0.0, math.radians(yaw))
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_euler", frame=f)
    scene.frame_set(7)
    said = gather.camera_motion(bpy.context, cam, (1, 60))
    assert said is not None and "0.70 m" in said and "30.0 deg" in said, said
    assert scene.frame_current == 7  # put back
    assert gather.camera_motion(bpy.context, cam, (1, 1)) is None
    cam.animation_data_clear()
    for f in range(1, 61, 10):  # a solve's jitter: millimetres, hundredths of a degree
        cam.location = (0.001 * (f % 3), -8.0, 5.0)
        cam.rotation_euler = (math.radians(60.0 + 0.01 * (f % 2)), 0.0, 0.0)
        cam.keyframe_insert("location", frame=f)
        cam.keyframe_insert("rotation_euler", frame=f)
    assert gather.camera_motion(bpy.context, cam, (1, 60)) is None
    cam.data.lens = 30.0
    cam.data.keyframe_insert("lens", frame=1)
    cam.data.lens = 50.0
    cam.data.keyframe_insert("lens", frame=60)
    assert "its lens by" in gather.camera_motion(bpy.context, cam, (1, 60))


def test_check_scene_says_whether_the_camera_is_solved_and_how_well(empty_scene, tmp_path):
    """Issue 26: a camera on Blender's Camera Solver constraint is reported
    with its solve's error; no solve, no clip, or an error over a pixel is a
    doubt."""
    from types import SimpleNamespace as NS
    from sunlapse.blender import gather
    scene = empty_scene
    cam = bpy.data.objects.new("Camera", bpy.data.cameras.new("Camera"))
    scene.collection.objects.link(cam)
    assert gather.camera_solve(bpy.context, cam) is None          # no constraint
    con = cam.constraints.new("CAMERA_SOLVER")
    con.use_active_clip = False
    words, doubtful = gather.camera_solve(bpy.context, cam)
    assert doubtful and "Camera Solver constraint with no clip" in words, words
    img = bpy.data.images.new("frame", 8, 8)
    img.filepath_raw = str(tmp_path / "frame_0001.png")
    img.file_format = "PNG"
    img.save()
    con.clip = bpy.data.movieclips.load(str(tmp_path / "frame_0001.png"))
    words, doubtful = gather.camera_solve(bpy.context, cam)
    assert doubtful and "has no camera solve yet" in words, words

    def solved(error):
        rec = NS(is_valid=True, average_error=error, cameras=[0] * 120)
        clip = NS(name="shot", tracking=NS(reconstruction=rec))
        solver = NS(type="CAMERA_SOLVER", use_active_clip=False, clip=clip)
        obj = NS(name="Camera", constraints=[solver])
        return gather.camera_solve(NS(scene=NS(active_clip=None)), obj)
    words, doubtful = solved(0.31)
    assert not doubtful and "120 frame(s), average error 0.31 px" in words, words
    words, doubtful = solved(2.5)
    assert doubtful and "over 1 px" in words, words


def test_a_ground_out_of_view_is_named_in_a_warning(monkeypatch):
    from types import SimpleNamespace as NS
    from sunlapse.blender import gather, job
    model = NS(names=["Plane", "Box"], ids_of=lambda names: [
        i for i, n in enumerate(["Plane", "Box"]) if n in names])
    cam = NS(name="Camera")
    monkeypatch.setattr(gather, "objects_in_view", lambda *a: {1: 0.3})  # only the box
    doubts = job.view_doubts(model, cam, None, None, ["Plane"])
    assert len(doubts) == 1 and "'Plane' is out of the camera's view" in doubts[0]
    assert job.view_doubts(model, cam, None, None, ["Box"]) == []
    # A bollard's top named as the ground: a sliver of the view.
    monkeypatch.setattr(gather, "objects_in_view", lambda *a: {0: 0.004, 1: 0.6})
    doubts = job.view_doubts(model, cam, None, None, ["Plane"])
    assert len(doubts) == 1 and "'Plane' covers only 0.4% of the camera's view" in doubts[0]
    monkeypatch.setattr(gather, "objects_in_view", lambda *a: {})
    with pytest.raises(gather.SceneError, match="sees none of the model"):
        job.view_doubts(model, cam, None, None, ["Plane"])


def test_scripted_run_reports_a_clip_missing_on_disk(empty_scene, tmp_path):
    blend = make_blend(tmp_path)
    for f in os.listdir(tmp_path / "frames"):
        os.unlink(tmp_path / "frames" / f)
    proc = run_estimate(blend, str(tmp_path / "o.json"))
    assert proc.returncode != 0
    assert "not found on disk" in error_lines(proc)[0]


def test_scripted_run_rejects_bad_flags(empty_scene, tmp_path):
    blend = make_blend(tmp_path)
    proc = run_estimate(blend, str(tmp_path / "o.json"), "--frames", "9:1")
    assert proc.returncode != 0 and "--frames" in error_lines(proc)[0]
    proc = run_estimate(blend, str(tmp_path / "o.json"), "--collection", "Nope")
    assert proc.returncode != 0 and "Nope" in error_lines(proc)[0]


def test_scripted_run_reports_unknown_flags_in_one_line(empty_scene, tmp_path):
    blend = make_blend(tmp_path)
    proc = run_estimate(blend, str(tmp_path / "o.json"), "--nonsense")
    assert proc.returncode == 2
    assert "unrecognized arguments" in error_lines(proc)[0]


def test_overlay_maps_clip_pixels_to_the_view(empty_scene):
    from sunlapse import overlay

    class View2D:  # records what the clip editor's view2d is asked
        def view_to_region(self, u, v, clip=False):
            return (u, v)

    class Region:
        view2d = View2D()

    u, v = overlay.clip_to_region(Region(), 200, 100, -0.5, -0.5)   # top-left corner
    assert (u, v) == (0.0, 1.0)
    u, v = overlay.clip_to_region(Region(), 200, 100, 199.5, 99.5)  # bottom-right corner
    assert (u, v) == (1.0, 0.0)


def _plot_track(n_frames):
    from sunlapse.core import trackfile
    frames = [{"frame": f, "zenith_deg": 40.0 + 30.0 * f / n_frames, "azimuth_deg": 180.0 + 0.5 * f,
               "confidence": 0.9} for f in range(1, n_frames + 1)]
    return trackfile.from_json({"format": trackfile.FORMAT_TRACK, "version": 1, "frames": frames})


@pytest.mark.parametrize("n_frames", [3, 24, 1000])
def test_the_plots_readout_never_covers_its_own_labels(n_frames):
    """The readout shared the frame labels' line: "fra5ne1 34.4 deg" at
    frame 5 of a 24-frame clip. Now no two labels overlap, at any frame, and
    none crosses the strips."""
    from sunlapse import overlay
    track = _plot_track(n_frames)
    x0, y0, w, h, size = 56, 30, 520, 190, 11
    frames = {1, 2, 5, n_frames // 2, n_frames - 1, n_frames} & set(range(1, n_frames + 1))
    for frame in sorted(frames):
        plot = overlay.plot_layout(track, frame, x0, y0, w, h, size)
        boxes = [(x, y, x + overlay._text_width(t, size), y + size) for t, x, y in plot["labels"]]
        assert len(boxes) == 3
        for i, a in enumerate(boxes):
            assert not (a[1] < y0 + h and a[3] > y0), (frame, plot["labels"][i])
            for b in boxes[i + 1:]:
                apart = a[2] <= b[0] or b[2] <= a[0] or a[3] <= b[1] or b[3] <= a[1]
                assert apart, (frame, plot["labels"])


def test_the_plot_shades_the_frames_without_sunlight_and_says_predicted():
    """Issue 25: frames without direct sunlight are shaded across the plot,
    one band per run of frames, and the readout says a Sun is predicted."""
    from sunlapse import overlay
    from sunlapse.core import trackfile
    frames = [{"frame": f, "zenith_deg": 70.0 + 2.0 * f, "azimuth_deg": 250.0,
               "confidence": 0.0 if f > 10 else 0.9,
               "sunlight": "no" if f > 10 or f == 4 else "yes", "predicted": f > 10}
              for f in range(1, 15)]
    track = trackfile.from_json({"format": trackfile.FORMAT_TRACK, "version": 1,
                                 "frames": frames})
    x0, w = 50, 520
    plot = overlay.plot_layout(track, 12, x0, 30, w, 190, 11)
    step = w / 13
    assert [(round(a, 3), round(b, 3)) for a, b in plot["unlit"]] == [
        (round(x0 + 2.5 * step, 3), round(x0 + 3.5 * step, 3)),
        (round(x0 + 9.5 * step, 3), round(x0 + w, 3))]  # not past the plot's end
    assert plot["labels"][2][0].endswith("(predicted: no sunlight)")
    assert "predicted" not in overlay.plot_layout(track, 2, x0, 30, w, 190, 11)["labels"][2][0]


def test_the_overlay_toggles_sit_in_the_clip_editors_overlay_popover():
    """Plot over Clip sat in the Lamp and Render panel; Blender users look
    for overlays in the editor's Overlays popover (Display before 4.2)."""
    from sunlapse import panels
    from sunlapse.blender import compat
    assert panels.draw_overlay_options in compat.clip_overlay_panel()._dyn_ui_initialize()

    class Layout:  # records the properties drawn; anything else is a layout
        def __init__(self):
            self.props = []
            self.use_property_split = self.use_property_decorate = False

        def prop(self, data, name, **_):
            self.props.append(name)

        def __getattr__(self, name):
            return lambda *a, **k: self
    layout = Layout()
    panels.draw_overlay_options(types_namespace(layout), bpy.context)
    assert layout.props == ["show_plot", "show_shadow"]
    lamp_panel = Layout()
    panels.draw_lamp(types_namespace(lamp_panel), bpy.context)
    assert "sun_lamp" in lamp_panel.props and "show_plot" not in lamp_panel.props


def test_a_long_summary_is_never_cut_off():
    """Summaries past the panel's lines ended in "...", with the rest lost:
    now every line shown is whole, and a button opens the whole text."""
    from sunlapse import panels
    text = " ".join(f"word{k}" for k in range(200)) + " THE-END"

    class Layout:  # records labels and operator buttons
        def __init__(self):
            self.labels, self.ops = [], []

        def column(self, **_):
            return self

        def label(self, text="", **_):
            self.labels.append(text)

        def operator(self, idname, **_):
            from types import SimpleNamespace
            op = SimpleNamespace(idname=idname)
            self.ops.append(op)
            return op
    layout = Layout()
    panels.wrapped(layout, bpy.context, text, max_lines=3)
    assert len(layout.labels) == 3 and not any(t.endswith("...") for t in layout.labels)
    assert " ".join(layout.labels) == text[:len(" ".join(layout.labels))]
    assert [o.idname for o in layout.ops] == ["clip.sunlapse_show_text"]
    assert layout.ops[0].text == text
    short = Layout()
    panels.wrapped(short, bpy.context, "all of it", max_lines=3)
    assert short.labels == ["all of it"] and short.ops == []
    # The popup's operator is registered and runs from a script too.
    assert bpy.ops.clip.sunlapse_show_text(text=text) == {"FINISHED"}


def test_panel_polls(empty_scene):
    from types import SimpleNamespace as NS
    poll = bpy.types.CLIP_PT_sunlapse.poll
    assert poll(NS(space_data=NS(mode="TRACKING")))
    assert not poll(NS(space_data=NS(mode="MASK")))      # mask editing: not ours
    assert not poll(NS(space_data=None))
    assert bpy.types.VIEW3D_PT_sunlapse.bl_category == "Sun"
    # Apply needs a stored track; Estimate is always offered (it says what is missing).
    assert not bpy.ops.clip.sunlapse_apply_lamp.poll()


def test_the_estimate_tooltip_describes_the_default_method():
    """The tooltip described the thesis's baseline (an initial Sun on the
    first frame, then tracking), not the whole-clip estimate users get."""
    doc = bpy.types.CLIP_OT_sunlapse_estimate.__doc__
    assert "whole clip" in doc and "initial Sun on the first" not in doc


def test_every_operator_sits_in_the_clip_editors_track_menu():
    """Operators in no menu are not found by F3 (it searches menus): they sit
    in Track › Sun (sunlapse), as Blender's own tracking tools sit there."""
    from sunlapse import operators, panels
    assert panels.draw_track_menu in bpy.types.CLIP_MT_track._dyn_ui_initialize()

    class Layout:  # records what the menu draws
        def __init__(self):
            self.ops = []

        def operator(self, idname, **_):
            self.ops.append(idname)
    menu = Layout()
    panels.CLIP_MT_sunlapse.draw(types_namespace(menu), bpy.context)
    ours = {c.bl_idname for c in operators.classes if c.bl_idname != "clip.sunlapse_cancel"
            and "INTERNAL" not in getattr(c, "bl_options", set())}
    assert set(menu.ops) == ours, ours ^ set(menu.ops)


def types_namespace(layout):
    import types
    return types.SimpleNamespace(layout=layout)


def test_a_scripted_run_warns_when_an_objects_top_is_taken_for_the_ground(empty_scene, tmp_path):
    """The ground named (or found) is a box: the run says so, naming it."""
    blend = make_blend(tmp_path)
    proc = run_estimate(blend, str(tmp_path / "t.sun.json"), "--ground", "Box")
    assert "sunlapse: warning: 'Box' is taken for the ground" in proc.stdout
