"""The track kept in the .blend: a Text datablock, saved with the file and
read back validated, one parsed copy shared by the panels, the overlay and
the operators (no JSON parsed per redraw)."""

import json

import bpy

from ..core import trackfile

TEXT_NAME = "sunlapse.sun.json"
_cache = {"key": None, "track": None}


def store_track(track: trackfile.Track) -> bpy.types.Text:
    text = bpy.data.texts.get(TEXT_NAME) or bpy.data.texts.new(TEXT_NAME)
    text.clear()
    text.write(json.dumps(trackfile.to_json(track), indent=1))
    invalidate()
    return text


def invalidate(*_):
    """Forget the parsed copy (a file loaded, the track stored again)."""
    _cache["key"] = None


def _key(text):
    """What changes when the text does (an edit in the Text Editor too),
    cheap enough for every redraw."""
    lines = text.lines
    return (text.as_pointer(), len(lines), lines[0].body if lines else "",
            lines[-1].body if lines else "", text.is_dirty)


def load_track():
    """The track stored in this .blend, or None. Validated once here
    (trackfile.loads): the panel, overlay, Apply and Export may trust what
    they get. A track edited into nonsense in the Text Editor reads as no
    track."""
    text = bpy.data.texts.get(TEXT_NAME)
    if text is None:
        return None
    key = _key(text)
    if _cache["key"] != key:
        try:
            track = trackfile.loads(text.as_string(), source=TEXT_NAME)
        except trackfile.TrackFileError as e:
            print(f"sunlapse: warning: the stored track is unusable: {e}")
            track = None
        _cache["key"], _cache["track"] = key, track
    return _cache["track"]


def has_track() -> bool:
    return TEXT_NAME in bpy.data.texts
