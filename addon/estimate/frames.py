"""Frames of the clip: one seeking reader, the size check, linear gray."""

from __future__ import annotations

from typing import Optional, Union

import numpy as np

from . import native_loader
from .errors import EstimateError
from .options import gamma

# A frame as float32 linear gray, or a sentence saying why there is none
# (None: no reason known).
Gray = Union[np.ndarray, str, None]


def open_clip(path: str, index: int):
    """A VideoReader positioned at 0-based frame `index`."""
    native = native_loader.require()
    try:
        reader = native.VideoReader(path)
    except ValueError as e:
        raise EstimateError(f"cannot read the clip: {e}")
    if not reader.seek(index):
        raise EstimateError(f"the clip has no frame {index + 1}")
    return reader


def read_frame(path: str, index: int):
    """Frame `index` (0-based) of a clip as uint8 BGR, or raise EstimateError."""
    try:
        frame = open_clip(path, index).read()
    except StopIteration:
        frame = None
    if frame is None:
        raise EstimateError(f"frame {index + 1} of the clip cannot be decoded")
    return frame


class FrameSource:
    """Frames of a clip by scene frame number, read with one seeking reader:
    sequential reads cost nothing extra, out-of-order ones seek."""

    def __init__(self, reader, clip_frame_start: int, next_index: int):
        self._reader, self.start, self.next = reader, clip_frame_start, next_index
        self._path: Optional[str] = None
        # The first 0-based index past the clip's end, once known.
        self.end: Optional[int] = None

    @classmethod
    def opened_when_read(cls, path: str, clip_frame_start: int) -> "FrameSource":
        """A source whose reader is opened by its first read: the whole-clip
        estimate streams its frames and reads few or none this way, and
        opening a 4K clip costs a decoded frame."""
        source = cls(None, clip_frame_start, 0)
        source._path = path
        return source

    @property
    def reader(self):
        if self._reader is None:
            assert self._path is not None
            self._reader = open_clip(self._path, 0)
        return self._reader

    def why_not(self) -> str:
        """Why the last read() gave no frame (the reader's own report)."""
        report = getattr(self.reader, "last_frame", None)
        message = getattr(report, "message", "") if report is not None else ""
        return message or "frame not decodable"

    def read(self, frame: int):
        """uint8 BGR, or None when the frame cannot be decoded; raises
        StopIteration when the clip has no such frame."""
        i = frame - self.start
        if self.end is not None and i >= self.end:
            raise StopIteration
        try:
            if i != self.next and not self.reader.seek(i):
                raise StopIteration
            self.next = i + 1
            return self.reader.read()
        except StopIteration:
            self.end = i if self.end is None else min(self.end, i)
            raise


def check_clip_size(width, height, camera):
    if (width, height) != (camera.width, camera.height):
        raise EstimateError(f"clip frames are {width}x{height} but the camera expects "
                            f"{camera.width}x{camera.height}: set the scene's resolution "
                            "to the clip's")


def gray(bgr, camera, method):
    native = native_loader.require()
    check_clip_size(bgr.shape[1], bgr.shape[0], camera)
    return native.to_linear_gray(bgr, gamma(method))


def wrong_size(image, camera) -> Optional[str]:
    if image.shape[0] != camera.height or image.shape[1] != camera.width:
        return (f"frame is {image.shape[1]}x{image.shape[0]}, not the camera's "
                f"{camera.width}x{camera.height}: not the scene's footage")
    return None
