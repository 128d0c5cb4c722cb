"""bench/paired.py: two commands timed in turn and their ratio pair by pair."""
import importlib.util
import os
import sys

# Loaded by path: putting bench/ on sys.path would let its modules shadow others.
_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "bench", "paired.py")
_spec = importlib.util.spec_from_file_location("paired", _PATH)
paired = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(paired)

PY = sys.executable


def test_the_slower_command_shows_in_the_ratio(capsys):
    slow = f"{PY} -c 'import time; time.sleep(0.3)'"
    fast = f"{PY} -c 'pass'"
    assert paired.main(["-n", "2", "--warmup", "0", "--a", slow, "--b", fast]) == 0
    rows = {line.split()[0]: line.split() for line in capsys.readouterr().out.splitlines()[1:]}
    # wall s  A min med max  B min med max  A/B min med max
    wall = rows["wall"]
    assert float(wall[-2]) > 1.5, wall           # the median ratio: A sleeps 0.3 s more
    assert 0.3 <= float(wall[4]) < 5.0, wall     # A's median wall time
    peak = rows["peak"]
    assert float(peak[3]) > 1.0, peak


def test_a_failing_or_missing_command_is_said_and_not_timed(capsys):
    assert paired.main(["-n", "1", "--warmup", "0", "--a", "false", "--b", "true"]) == 1
    assert "command A exited with 1" in capsys.readouterr().err
    assert paired.main(["-n", "1", "--warmup", "0", "--a", "true",
                        "--b", "/nonexistent/command"]) == 2
    assert "command B cannot be started" in capsys.readouterr().err


def _writer(path, table, reference):
    """A command that writes a track file with the given timing."""
    timing = {"table_s": table, "reference_s": reference, "tracker_start_s": 0.1}
    code = f"import json; json.dump({{'timing': {timing!r}}}, open({str(path)!r}, 'w'))"
    return f"{PY} -c \"{code}\""


def test_the_tracks_timing_keys_and_their_sum_are_paired(tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert paired.main(["-n", "2", "--warmup", "0", "--a", _writer(a, 0.2, 0.3),
                        "--b", _writer(b, 0.4, 0.3), "--tracks", str(a), str(b)]) == 0
    out = capsys.readouterr().out
    rows = {line.split()[0]: line.split() for line in out.splitlines()[1:]}
    # key  A min med max  B min med max  A/B min med max
    assert [float(v) for v in rows["table_s"][2:5]] == [0.2, 0.2, 0.2]
    assert float(rows["table_s"][-2]) == 0.5
    total = [line.split() for line in out.splitlines() if line.startswith("sum of keys")][0]
    assert float(total[4]) == 0.6 and float(total[8]) == 0.8, total


def test_a_track_without_the_key_is_said(tmp_path, capsys):
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert paired.main(["-n", "1", "--warmup", "0", "--a", _writer(a, 0.2, 0.3),
                        "--b", _writer(b, 0.4, 0.3), "--tracks", str(a), str(b),
                        "--keys", "table_s,decode_s"]) == 1
    err = capsys.readouterr().err
    assert "has no timing decode_s" in err and str(a) in err
