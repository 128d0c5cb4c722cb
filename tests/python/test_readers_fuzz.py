"""Property-based fuzzing of the readers (issue 15): a track file or times
file, however malformed, is either read into values everything downstream
can use, or refused with the module's own error, never another exception.

Bounded in time for the default run (SUNLAPSE_FUZZ_EXAMPLES raises the
number of examples for a longer hunt)."""
import codecs
import datetime as dt
import json
import math
import os

from hypothesis import HealthCheck, given, settings, strategies as st

from core import clock, frametimes, trackfile

EXAMPLES = int(os.environ.get("SUNLAPSE_FUZZ_EXAMPLES", 150))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
                suppress_health_check=list(HealthCheck))

json_values = st.recursive(
    st.none() | st.booleans() | st.integers(-2 ** 40, 2 ** 40) |
    st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=8),
    lambda inner: st.lists(inner, max_size=4) |
    st.dictionaries(st.text(max_size=6), inner, max_size=4),
    max_leaves=12)

VALID_FRAME = {"frame": 1, "zenith_deg": 40.0, "azimuth_deg": 120.0, "raw_zenith_deg": 41.0,
               "raw_azimuth_deg": 119.0, "confidence": 0.9,
               "shadow": {"start_px": [1.0, 2.0], "end_px": [3.0, 4.0]},
               "sun_ambient_ratio": 2.0, "time_utc": "2005-03-21T08:00:00+00:00"}
VALID = {"format": "sunlapse.track", "version": 1, "clip": "c.mp4", "frame_start": 1,
         "north_offset_deg": 10.0, "method": {"smoothing": "two_pass"},
         "initial": {"frame": 1, "zenith_deg": 40.0, "azimuth_deg": 120.0, "residual": 0.1,
                     "confidence": 0.9, "seconds": 1.0},
         "frames": [VALID_FRAME, dict(VALID_FRAME, frame=2)]}


@st.composite
def mutated_tracks(draw):
    """A valid track with one to three fields (top level, initial, a frame
    or its shadow) replaced by arbitrary JSON values or deleted."""
    d = json.loads(json.dumps(VALID))
    for _ in range(draw(st.integers(1, 3))):
        where = draw(st.sampled_from(["top", "initial", "frame", "shadow"]))
        if where == "top":
            target, keys = d, list(VALID)
        elif where == "initial" and isinstance(d.get("initial"), dict):
            target, keys = d["initial"], list(VALID["initial"])
        elif where == "frame" and isinstance(d.get("frames"), list) and d["frames"] and \
                isinstance(d["frames"][0], dict):
            target, keys = d["frames"][0], list(VALID_FRAME)
        elif where == "shadow" and isinstance(d.get("frames"), list) and d["frames"] and \
                isinstance(d["frames"][0], dict) and isinstance(d["frames"][0].get("shadow"), dict):
            target, keys = d["frames"][0]["shadow"], ["start_px", "end_px"]
        else:
            continue
        key = draw(st.sampled_from(keys))
        if draw(st.booleans()):
            target.pop(key, None)
        else:
            target[key] = draw(json_values)
    return d


def assert_usable(track):
    """What the panel, overlay, Apply and Export rely on."""
    assert isinstance(track.clip, str) and isinstance(track.frame_start, int)
    assert math.isfinite(track.north_offset_deg) and isinstance(track.method, dict)
    assert track.initial is None or isinstance(track.initial, dict)
    numbers = [f.frame for f in track.frames]
    assert numbers == sorted(set(numbers))
    for f in track.frames:
        assert isinstance(f.frame, int) and not isinstance(f.frame, bool)
        assert 0.0 <= f.confidence <= 1.0
        assert f.has_estimate == (f.zenith_deg is not None)
        for v in (f.zenith_deg, f.azimuth_deg, f.raw_zenith_deg, f.raw_azimuth_deg,
                  f.sun_ambient_ratio):
            assert v is None or (isinstance(v, float) and math.isfinite(v))
        if f.zenith_deg is not None:
            assert 0.0 <= f.zenith_deg <= 180.0
        for px in (f.shadow_start_px, f.shadow_end_px):
            assert px is None or (len(px) == 2 and all(math.isfinite(v) for v in px))
        assert f.reason is None or isinstance(f.reason, str)
    # Export works on it: writing and reading back gives the same track.
    again = trackfile.from_json(json.loads(json.dumps(trackfile.to_json(track))))
    assert [f.frame for f in again.frames] == numbers


def read_or_refuse(d):
    try:
        track = trackfile.from_json(d, source="fuzz")
    except trackfile.TrackFileError:
        return None
    assert_usable(track)
    return track


def test_the_valid_sample_is_read():
    assert read_or_refuse(json.loads(json.dumps(VALID))) is not None


@FUZZ
@given(mutated_tracks())
def test_track_reader_on_mutated_tracks(d):
    read_or_refuse(d)


@FUZZ
@given(json_values)
def test_track_reader_on_any_json_value(d):
    read_or_refuse(d)


@FUZZ
@given(st.binary(max_size=300) | st.text(max_size=300).map(lambda t: t.encode("utf-8")))
def test_track_file_reader_on_any_bytes(tmp_path_factory, data):
    path = tmp_path_factory.mktemp("t") / "x.sun.json"
    path.write_bytes(data)
    try:
        track = trackfile.read_track(str(path))
    except trackfile.TrackFileError as e:
        assert str(path) in str(e)
        return
    assert_usable(track)


def test_track_reader_refusals_name_the_field():
    bad = json.loads(json.dumps(VALID))
    bad["north_offset_deg"] = "east"
    try:
        trackfile.from_json(bad, source="f.json")
    except trackfile.TrackFileError as e:
        assert "north_offset_deg" in str(e) and "f.json" in str(e)
    else:
        raise AssertionError("a text north offset was accepted")
    bad = json.loads(json.dumps(VALID))
    bad["frames"][1]["shadow"]["end_px"] = ["a", 2]
    try:
        trackfile.from_json(bad, source="f.json")
    except trackfile.TrackFileError as e:
        assert "frame entry 1" in str(e) and "end_px" in str(e)
    else:
        raise AssertionError("non-numeric shadow pixels were accepted")


def test_nested_json_too_deep_for_python_is_refused():
    text = "[" * 100000 + "]" * 100000
    try:
        trackfile.loads(text, "deep.json")
    except trackfile.TrackFileError as e:
        assert "deep.json" in str(e)
    else:
        raise AssertionError


# --------------------------------------------------------------------------
# Times files

time_cells = st.one_of(
    st.text(max_size=25),
    st.datetimes(min_value=dt.datetime(1, 1, 2), max_value=dt.datetime(9999, 12, 30)).map(
        lambda t: t.isoformat(sep=" ")),
    st.sampled_from(["2005-03-21 08:06", "2005-03-21T08:06:00+01:00", "2005-03-21",
                     "0001-01-01 00:00+05:00", "9999-12-31T23:59:59-05:00", ""]))
rows = st.lists(st.tuples(st.one_of(st.integers(-3, 10).map(str), st.text(max_size=5)),
                          time_cells), max_size=6)


@st.composite
def times_files(draw):
    header = draw(st.sampled_from(["frame,local_time", "frame,utc_time", "frame,time",
                                   "frame;local_time", "\ufeffframe,local_time", "", "frame"]))
    lines = [header] + [f"{a},{b}" for a, b in draw(rows)]
    text = "\n".join(lines)
    encoding = draw(st.sampled_from(["utf-8", "utf-8-sig", "cp1252", "utf-16", "latin-1"]))
    try:
        data = text.encode(encoding)
    except UnicodeEncodeError:
        data = text.encode("utf-8")
    if draw(st.booleans()):
        cut = draw(st.integers(0, len(data)))
        data = data[:cut] + draw(st.binary(max_size=8)) + data[cut:]
    return data


@FUZZ
@given(times_files(), st.floats(-20, 20) | st.just(math.nan))
def test_times_reader_on_malformed_files(tmp_path_factory, data, utc_offset):
    path = tmp_path_factory.mktemp("t") / "times.csv"
    path.write_bytes(data)
    try:
        table = frametimes.read_times(str(path), clock.zone("", utc_offset))
    except clock.ClockError as e:
        assert "UTC offset" in str(e)
        return
    except frametimes.FrameTimesError as e:
        assert str(path) in str(e)
        return
    assert table
    for frame, when in table.items():
        assert isinstance(frame, int)
        assert when.utcoffset() == dt.timedelta(0)


def test_excel_csv_with_a_byte_order_mark_and_windows_1252(tmp_path):
    path = tmp_path / "bom.csv"
    path.write_bytes(codecs.BOM_UTF8 + b"frame,local_time\r\n1,2005-03-21 08:06\r\n")
    assert frametimes.read_times(str(path), clock.zone("", 1.0))[1].hour == 7
    path = tmp_path / "cp1252.csv"
    path.write_bytes("frame,local_time,note\r\n1,2005-03-21 08:06,caf\u00e9 \u20ac\r\n"
                     .encode("cp1252"))
    assert frametimes.read_times(str(path))[1].minute == 6
