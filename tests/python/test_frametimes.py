import datetime as dt

import pytest

from core import clock, frametimes

UTC = dt.timezone.utc


def write(tmp_path, text, name="t.csv"):
    p = tmp_path / name
    p.write_text(text)
    return str(p)


def test_local_times_are_read_with_the_utc_offset(tmp_path):
    path = write(tmp_path, "frame,local_time\n1,2005-03-21 18:08\n2,2005-03-21 08:06:30\n\n")
    t = frametimes.read_times(path, clock.zone("", 1))
    assert t == {1: dt.datetime(2005, 3, 21, 17, 8, tzinfo=UTC),
                 2: dt.datetime(2005, 3, 21, 7, 6, 30, tzinfo=UTC)}


def test_iso_times_keep_their_own_offset_and_utc_columns_are_utc(tmp_path):
    p1 = write(tmp_path, "frame, time\n3,2005-01-13T09:00:00+02:00\n", "a.csv")
    assert (frametimes.read_times(p1, clock.zone("", 1))[3]
            == dt.datetime(2005, 1, 13, 7, 0, tzinfo=UTC))
    p2 = write(tmp_path, "frame,utc_time\n1,2005-01-13 09:00\n", "b.csv")
    assert (frametimes.read_times(p2, clock.zone("", 5))[1]
            == dt.datetime(2005, 1, 13, 9, 0, tzinfo=UTC))


@pytest.mark.parametrize("text,match", [
    ("frame,when\n1,2005-01-13 09:00\n", "needs a header"),
    ("frame,local_time\n1,13/01/2005 9h\n", "line 2: '13/01/2005 9h' is not a date"),
    ("frame,local_time\nx,2005-01-13 09:00\n", "line 2"),
    ("frame,local_time\n1,2005-01-13 09:00\n1,2005-01-13 09:15\n", "frame 1 is listed twice"),
    ("frame,local_time\n", "no frames listed"),
])
def test_bad_files_say_where_and_why(tmp_path, text, match):
    with pytest.raises(frametimes.FrameTimesError, match=match):
        frametimes.read_times(write(tmp_path, text))


def test_missing_file_and_missing_frames(tmp_path):
    with pytest.raises(frametimes.FrameTimesError, match="no such file"):
        frametimes.read_times(str(tmp_path / "none.csv"))
    table = {1: dt.datetime(2005, 1, 1, tzinfo=UTC), 2: dt.datetime(2005, 1, 2, tzinfo=UTC)}
    with pytest.raises(frametimes.FrameTimesError, match="no time for clip frame.*3, 4"):
        frametimes.times_for(table, [1, 2, 3, 4])
    assert frametimes.times_for(table, [2, 1]) == [table[2], table[1]]


def test_chronological_order_and_out_of_order_frames():
    t = [dt.datetime(2005, 3, 21, h, tzinfo=UTC) for h in (18, 8, 8, 9)]
    frames = [1, 2, 3, 4]
    assert clock.chronological(frames, t) == [1, 2, 3, 0]   # ties keep frame order
    assert clock.chronological(frames, None) == [0, 1, 2, 3]
    assert clock.out_of_order(frames, t) == [2]
    assert clock.seconds_since(t) == [36000.0, 0.0, 0.0, 3600.0]


def test_local_start_is_hours_after_midnight_in_the_zone():
    t = clock.local_start(dt.date(2005, 3, 21), 10.5, clock.zone("", 1.0))
    assert t.isoformat() == "2005-03-21T10:30:00+01:00"
    assert t.astimezone(dt.timezone.utc).hour == 9


def test_times_that_cannot_order_the_frames_are_told_apart():
    t0 = dt.datetime(2025, 6, 21, 10, 0, tzinfo=dt.timezone.utc)
    step = [t0 + dt.timedelta(minutes=10 * k) for k in range(10)]
    assert clock.orderless(step) is None
    assert clock.orderless(step[:1]) is None
    # A burst's duplicate here and there still orders the clip.
    assert clock.orderless(step[:9] + [step[8]]) is None
    assert "same time" in clock.orderless([t0] * 5)
    # Dates without times of day: every frame of a day at midnight.
    days = [dt.datetime(2025, 6, 21 + k // 3, tzinfo=dt.timezone.utc) for k in range(9)]
    why = clock.orderless(days)
    assert why is not None and "9 of 9 frames" in why and "3 different times" in why
    # Each capture repeated over consecutive frames (Marseille, January)
    # still orders the clip; the same times jumbled do not.
    repeated = [s for s in step for _ in range(13)]
    assert clock.orderless(repeated) is None
    jumbled = step * 3
    assert "in 30 runs of 10 different times" in clock.orderless(jumbled)
