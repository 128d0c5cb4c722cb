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
