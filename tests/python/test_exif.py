import datetime as dt

import pytest

from core import clock, exif

UTC = dt.timezone.utc


def write_jpeg(path, when=None, subsec=None, offset=None, gps=None):
    from PIL import Image
    from PIL.TiffImagePlugin import IFDRational
    e = Image.Exif()
    sub = {}
    if when:
        sub[0x9003] = when
    if subsec:
        sub[0x9291] = subsec
    if offset:
        sub[0x9011] = offset
    if sub:
        e[0x8769] = sub
    if gps:
        (lat_ref, lat), (lon_ref, lon) = gps
        e[0x8825] = {1: lat_ref, 2: tuple(IFDRational(v) for v in lat),
                     3: lon_ref, 4: tuple(IFDRational(v) for v in lon)}
    Image.new("RGB", (8, 6), (90, 100, 110)).save(str(path), exif=e)
    return str(path)


def test_time_subseconds_and_gps_are_read_in_a_zone_with_daylight_saving(tmp_path):
    p = write_jpeg(tmp_path / "a_0001.jpg", "2025:06:21 09:30:00", "25",
                   gps=(("S", (33, 52, 12)), ("W", (70, 30, 0))))
    c = exif.read_capture(p, clock.zone("Europe/Paris"))
    assert c.time_utc == dt.datetime(2025, 6, 21, 7, 30, 0, 250000, tzinfo=UTC)  # CEST
    assert c.latitude_deg == pytest.approx(-(33 + 52 / 60 + 12 / 3600))
    assert c.longitude_deg == pytest.approx(-70.5)
    winter = write_jpeg(tmp_path / "b_0001.jpg", "2025:01:21 09:30:00")
    assert exif.read_capture(winter, clock.zone("Europe/Paris")).time_utc.hour == 8  # CET


def test_the_files_own_offset_wins_over_the_given_zone(tmp_path):
    p = write_jpeg(tmp_path / "a_0001.jpg", "2025:06:21 09:30:00", offset="-03:00")
    c = exif.read_capture(p, clock.zone("Europe/Paris"))
    assert c.time_utc == dt.datetime(2025, 6, 21, 12, 30, tzinfo=UTC) and c.zone_from_file


def test_sequence_files_in_number_order_and_times_by_frame(tmp_path):
    for k, t in ((1, "10:00:00"), (2, "10:02:00"), (3, "10:01:00"), (5, "10:09:00")):
        write_jpeg(tmp_path / f"shot_{k:03d}.jpg", f"2025:03:03 {t}")
    write_jpeg(tmp_path / "other_002.jpg", "2025:03:03 11:00:00")
    native = pytest.importorskip("_native")
    seq = native.find_image_sequence(str(tmp_path / "shot_001.jpg"))
    files = [seq.path(k) for k in range(seq.num_frames)]
    assert [f[-12:] for f in files] == ["shot_001.jpg", "shot_002.jpg", "shot_003.jpg",
                                        "shot_004.jpg", "shot_005.jpg"]  # 4 is missing
    caps = exif.read_sequence(files, clock.zone("", 3.0))
    assert [c.path[-12:] for c in caps] == ["shot_001.jpg", "shot_002.jpg", "shot_003.jpg"]
    table = exif.times_by_frame(caps, first_frame=10)
    assert [table[f].strftime("%H:%M") for f in (10, 11, 12)] == ["07:00", "07:02", "07:01"]


def test_missing_times_and_bad_input_say_what_is_wrong(tmp_path):
    p = write_jpeg(tmp_path / "a_0001.jpg")
    c = exif.read_capture(p, UTC)
    assert c.time_utc is None and c.latitude_deg is None
    assert exif.times_by_frame([c], 1) is None
    assert exif.place([c]) is None
    with pytest.raises(clock.ClockError, match="'Mars/Olympus' is not a known zone"):
        clock.zone("Mars/Olympus")
    bad = write_jpeg(tmp_path / "b_0001.jpg", "21/06/2025 09:30")
    with pytest.raises(exif.ExifError, match="b_0001.jpg: '21/06/2025 09:30' is not an EXIF"):
        exif.read_capture(bad, UTC)
    (tmp_path / "c_0001.jpg").write_text("not an image")
    with pytest.raises(exif.ExifError, match="c_0001.jpg: cannot be read"):
        exif.read_capture(str(tmp_path / "c_0001.jpg"), UTC)


def test_local_start_uses_the_days_offset():
    paris = clock.zone("Europe/Paris")
    assert clock.local_start(dt.date(2025, 6, 21), 9.5, paris).astimezone(UTC).hour == 7
    assert clock.local_start(dt.date(2025, 12, 21), 9.5, paris).astimezone(UTC).hour == 8
    assert clock.utc_offset_hours(paris, dt.datetime(2025, 6, 21, 12, tzinfo=UTC)) == 2.0
