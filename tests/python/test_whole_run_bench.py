"""bench/whole_run.py's helpers that need no Blender: the ping-pong frame
order of its long clips and its flag parsing."""
import argparse
import os
import sys

import pytest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "bench"))

import whole_run  # noqa: E402


@pytest.mark.parametrize("count,length", [(90, 10000), (90, 1000), (2, 7), (5, 5), (3, 1)])
def test_pingpong_never_jumps_and_covers_the_source(count, length):
    order = whole_run.pingpong(count, length)
    assert len(order) == length
    assert order[0] == 0
    assert all(0 <= k < count for k in order)
    # Neighbouring frames of the clip are neighbours in the source: the Sun
    # moves on by one frame's step, never jumps back to the start.
    assert all(abs(a - b) == 1 for a, b in zip(order, order[1:]))
    if length >= count:
        assert sorted(set(order)) == list(range(count))


def test_pingpong_turns_at_both_ends():
    assert whole_run.pingpong(4, 12) == [0, 1, 2, 3, 2, 1, 0, 1, 2, 3, 2, 1]


def test_pingpong_of_one_frame_repeats_it():
    assert whole_run.pingpong(1, 4) == [0, 0, 0, 0]


def test_pingpong_refuses_no_source():
    with pytest.raises(ValueError):
        whole_run.pingpong(0, 3)


def test_sizes_and_lengths_parse_and_refuse_clearly():
    assert whole_run.parse_sizes("2160,720") == [720, 2160]
    assert whole_run.parse_sizes("1080p,4k") == [1080, 2160]
    assert whole_run.parse_lengths("") == []
    assert whole_run.parse_lengths("10000,1000") == [1000, 10000]
    with pytest.raises(argparse.ArgumentTypeError, match="720,1080,2160"):
        whole_run.parse_sizes("480")
    with pytest.raises(argparse.ArgumentTypeError, match=">= 2"):
        whole_run.parse_lengths("1000,x")
