"""bench/whole_run.py's helpers that need no Blender: the ping-pong frame
order of its long clips and its flag parsing."""
import argparse
import importlib.util
import os

import pytest

# Loaded by path: putting bench/ on sys.path would let its modules shadow others.
_PATH = os.path.join(os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__)))), "bench", "whole_run.py")
_spec = importlib.util.spec_from_file_location("whole_run", _PATH)
whole_run = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(whole_run)


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


class _Reader:
    """A stand-in for _native.VideoReader: `frames` frames, then StopIteration."""
    frames = 3

    def __init__(self, path):
        self.left = self.frames

    def read(self):
        if self.left == 0:
            raise StopIteration
        self.left -= 1
        return object()


class _GrayReader(_Reader):
    read_gray = _Reader.read


class _Native:
    def __init__(self, reader):
        self.VideoReader = reader


def test_decode_only_reads_gray_too_when_the_reader_has_it():
    assert list(whole_run.measure_decode(_Native(_Reader), "x.mp4")) == ["bgr"]
    decode = whole_run.measure_decode(_Native(_GrayReader), "x.mp4")
    assert sorted(decode) == ["bgr", "gray"]
    assert all(d["frames"] == 3 for d in decode.values())
    assert whole_run.reference_mode(decode) == "gray"


def test_figures_take_the_ratio_against_the_reference_mode():
    decode = {"bgr": {"frames": 100, "seconds": 1.0, "fps": 100.0},
              "gray": {"frames": 100, "seconds": 0.5, "fps": 200.0}}
    est = {"frames": 100, "estimated": 100, "wall_s": 5.0, "max_rss_mb": 500.0,
           "timing": {"table_s": 0.5, "reference_s": 0.5, "total_s": 4.0, "samples": 10}}
    f = whole_run.figures_of(decode, est)
    assert f["decode_mode"] == "gray"
    assert f["fps"] == 25.0
    assert f["ratio"] == 25.0 / 200.0
    assert f["ratios_by_mode"]["bgr"] == 0.25
    assert f["precompute_s"] == 1.0
    assert abs(f["per_frame_ms"] - 30.0) < 1e-9
    assert abs(f["ratio_steady"] - 0.5 / 3.0) < 1e-9
    # A track without the timing keys still gives the process's figures.
    bare = whole_run.figures_of(decode, dict(est, timing={}))
    assert "ratio" not in bare and bare["wall_fps"] == 20.0


def test_the_small_clip_row_judges_the_whole_estimate_against_three_seconds():
    def row(total_s):
        fig = {"sizes": {"800x450, 120 frames": {"height": 450, "total_s": total_s}},
               "long": {}}
        return [r for r in whole_run.summary_lines(fig) if "800x450" in r[0]]
    assert row(2.5) == [("estimate <= 3 s, 800x450, 120 frames (issue 14)", "2.50 s", "met")]
    assert row(3.5)[0][2] == "not met"
    assert whole_run.parse_sizes("450") == [450]
    assert 450 not in whole_run.DEFAULT_SIZES


def test_1080p_is_judged_against_ffmpegs_decode_by_its_length():
    """Issue 28: >= 0.4x ffmpeg's decode over 300 frames, >= 0.6x over 1,000."""
    def rows(frames, ffmpeg_s, total_s):
        f = {"height": 1080, "frames": frames, "wall_s": total_s + 1.0, "total_s": total_s}
        whole_run.ffmpeg_figures(f, {"seconds": ffmpeg_s})
        fig = {"sizes": {}, "long": {f"1920x1080, {frames} frames": f}}
        return [r for r in whole_run.summary_lines(fig) if "ffmpeg" in r[0]]
    assert rows(300, 1.25, 5.7) == [("estimate >= 0.4x ffmpeg's decode (issue 28), "
                                     "1920x1080, 300 frames", "0.22x (wall 0.19x)", "not met")]
    assert rows(1000, 4.0, 6.0)[0][0].startswith("estimate >= 0.6x") and \
        rows(1000, 4.0, 6.0)[0][2] == "met"
    assert rows(100, 1.0, 2.0) == []           # no target below 300 frames
    bare = {"frames": 10, "wall_s": 2.0}
    whole_run.ffmpeg_figures(bare, None)       # no ffmpeg: no figure, no row
    assert "ffmpeg" not in bare
