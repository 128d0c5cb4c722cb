"""Per-frame capture times (a times CSV): frames visited in capture order,
smoothing over real time, physical smoothing clocked by the file."""
import datetime as dt
import json
import os

from sunlapse.core.angles import angle_between_deg, sun_in_world_from_geographic
from test_addon import error_lines, run_estimate


def write_times(path, rows):
    with open(path, "w") as f:
        f.write("frame,local_time\n")
        for frame, t in rows:
            f.write(f"{frame},{t.strftime('%Y-%m-%d %H:%M:%S')}\n")
    return str(path)


def local_times(truth):
    return [dt.datetime.fromisoformat(t).replace(tzinfo=None) for t in truth.extra["local_times"]]


def test_frames_are_tracked_in_the_order_they_were_taken(tiny_plaza, tmp_path):
    out, truth = tiny_plaza
    t = local_times(truth)
    step = t[1] - t[0]
    # Frame 1 is said to be the last capture (as the March sundial clip's is):
    # the run takes the frames as 2, 3, 1, and frame 1 still gets its own
    # Sun (the images are what they are; only the order changes).
    rows = [(1, t[-1] + step), (2, t[1]), (3, t[2])]
    times = write_times(tmp_path / "t.csv", rows)
    path = str(tmp_path / "o.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), path, "--times", times,
                        "--utc-offset", "2")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(path))
    assert track["frame_times"]["out_of_order_frames"] == [2]
    for f, (_, when) in zip(track["frames"], rows):
        utc = (when - dt.timedelta(hours=2)).replace(tzinfo=dt.timezone.utc)
        assert dt.datetime.fromisoformat(f["time_utc"]) == utc
    for f, ref in zip(track["frames"], truth.frames):
        assert f["raw_zenith_deg"] is not None, f
        err = angle_between_deg(
            sun_in_world_from_geographic(f["raw_zenith_deg"], f["raw_azimuth_deg"],
                                         track["north_offset_deg"]),
            sun_in_world_from_geographic(ref.zenith_deg, ref.azimuth_deg, truth.north_offset_deg))
        assert err < 3.0, (f["frame"], err)


def test_physical_smoothing_takes_its_clock_from_the_times_file(tiny_plaza, tmp_path):
    out, truth = tiny_plaza
    times = write_times(tmp_path / "t.csv", list(zip((1, 2, 3), local_times(truth))))
    path = str(tmp_path / "p.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), path, "--times", times,
                        "--utc-offset", "2", "--smoothing", "physical",
                        "--latitude", "48.85", "--longitude", "2.35")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(path))
    assert track["method"]["smoothing"] == "physical"
    assert abs(track["sun_path_fit"]["time_offset_s"]) < 900
    for f, ref in zip(track["frames"], truth.frames):
        assert abs(((f["azimuth_deg"] - ref.azimuth_deg) + 180) % 360 - 180) < 5


def test_a_times_file_that_misses_frames_is_a_clear_error(tiny_plaza, tmp_path):
    out, truth = tiny_plaza
    times = write_times(tmp_path / "t.csv", list(zip((1, 2), local_times(truth))))
    path = str(tmp_path / "m.sun.json")
    proc = run_estimate(os.path.join(out, "scene.blend"), path, "--times", times)
    assert proc.returncode == 3
    assert "no time for clip frame(s) 3" in error_lines(proc)[0]
    assert not os.path.exists(path)
    proc = run_estimate(os.path.join(out, "scene.blend"), path, "--times",
                        str(tmp_path / "none.csv"))
    assert proc.returncode == 3 and "no such file" in error_lines(proc)[0]


def test_a_first_frame_without_a_clear_sun_is_tracked_back_from_the_next(tiny_plaza, tmp_path):
    """Frame 1 is black: it gets no angles and says why; the frames after
    it are found as if it were not there."""
    import shutil

    import bpy
    from conftest import sunlapse
    out, truth = tiny_plaza
    seq = tmp_path / "frames"
    seq.mkdir()
    for n in (2, 3):
        shutil.copy(os.path.join(out, "frames", f"frame_{n:04d}.png"), seq / f"frame_{n:04d}.png")
    bpy.ops.wm.open_mainfile(filepath=os.path.join(out, "scene.blend"))
    if not hasattr(bpy.types.Scene, "sunlapse"):
        sunlapse.register()
    w, h = bpy.context.scene.active_clip.size
    black = bpy.data.images.new("black", w, h)
    black.pixels[:] = [0.0, 0.0, 0.0, 1.0] * (w * h)
    black.filepath_raw = str(seq / "frame_0001.png")
    black.file_format = "PNG"
    black.save()
    clip = bpy.data.movieclips.load(str(seq / "frame_0001.png"))
    bpy.context.scene.active_clip = clip
    blend = str(tmp_path / "black_first.blend")
    bpy.ops.wm.save_as_mainfile(filepath=blend)
    path = str(tmp_path / "b.sun.json")
    proc = run_estimate(blend, path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    track = json.load(open(path))
    assert track["initial"]["frame"] in (2, 3)
    f1, f2, f3 = track["frames"]
    assert f1["raw_zenith_deg"] is None and "black" in f1["reason"]
    for f, ref in ((f2, truth.frames[1]), (f3, truth.frames[2])):
        err = angle_between_deg(
            sun_in_world_from_geographic(f["raw_zenith_deg"], f["raw_azimuth_deg"],
                                         track["north_offset_deg"]),
            sun_in_world_from_geographic(ref.zenith_deg, ref.azimuth_deg, truth.north_offset_deg))
        assert err < 3.0, (f["frame"], err)


def test_the_place_and_times_say_which_frames_are_night_in_a_two_pass_run(tiny_plaza, tmp_path):
    """Frame 3 stamped 02:00 (night at the given place) has no direct
    sunlight and gets the Sun the ephemeris puts there, below the horizon,
    whatever its shadows show (street lights cast hard shadows too);
    without the place its footage decides."""
    out, truth = tiny_plaza
    t = local_times(truth)
    night = dt.datetime.combine(t[1].date() + dt.timedelta(days=1), dt.time(2, 0))
    times = write_times(tmp_path / "t.csv", [(1, t[0]), (2, t[1]), (3, night)])
    frames = {}
    for name, place in (("placed", ["--latitude", "48.85", "--longitude", "2.35"]),
                        ("unplaced", [])):
        path = str(tmp_path / f"{name}.sun.json")
        proc = run_estimate(os.path.join(out, "scene.blend"), path, "--times", times,
                            "--utc-offset", "2", *place)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        frames[name] = json.load(open(path))["frames"]
    f3 = frames["placed"][2]
    assert f3["sunlight"] == "no" and f3["predicted"] and f3["confidence"] == 0.0, f3
    assert f3["zenith_deg"] > 90.0 and "ephemeris" in f3["reason"], f3
    assert [f["sunlight"] for f in frames["placed"][:2]] == ["yes", "yes"]
    assert frames["unplaced"][2]["sunlight"] == "yes", frames["unplaced"][2]
