"""Draws the stored Sun track over the clip in the Movie Clip Editor.

On the current frame: the tracked shadow (caster foot to shadow tip), its
ends, and the confidence; in the lower-left corner, a small plot of zenith
(orange) and azimuth (blue) over the clip with the current frame marked.
"""

import bpy

from . import results

_handle = None
_cache = {"key": None, "track": None}


def clip_to_region(region, width, height, x_px, y_px):
    """OpenCV pixel of the clip (0,0 = centre of the top-left pixel, y down)
    -> region pixel. The clip editor's view2d works in normalised clip
    coordinates (0..1, y up)."""
    u = (x_px + 0.5) / width
    v = 1.0 - (y_px + 0.5) / height
    return region.view2d.view_to_region(u, v, clip=False)


def invalidate(*_):
    _cache["key"] = None


def _track():
    text = bpy.data.texts.get(results.TEXT_NAME)
    if text is None:
        return None
    key = (text.as_pointer(), len(text.lines), text.lines[0].body if text.lines else "",
           text.lines[-1].body if text.lines else "")
    if _cache["key"] != key:
        _cache["key"], _cache["track"] = key, results.load_track()
    return _cache["track"]


def _series_plot(track, frame, x0, y0, w, h):
    """Polylines of the plot: (points, colour) pairs, in region pixels."""
    est = [f for f in track.frames if f.has_estimate]
    if len(est) < 2:
        return []
    f0, f1 = track.frames[0].frame, track.frames[-1].frame
    span = max(1, f1 - f0)
    out = []
    for key, color in (("zenith_deg", (1.0, 0.6, 0.1, 1.0)), ("azimuth_deg", (0.3, 0.6, 1.0, 1.0))):
        vals = [getattr(f, key) for f in est]
        lo, hi = min(vals), max(vals)
        rng = max(1e-6, hi - lo)
        pts = [(x0 + w * (f.frame - f0) / span, y0 + h * (getattr(f, key) - lo) / rng) for f in est]
        out.append((pts, color))
    xm = x0 + w * (frame - f0) / span
    out.append(([(xm, y0), (xm, y0 + h)], (1, 1, 1, 0.8)))
    return out


def _draw():
    import blf
    import gpu
    from gpu_extras.batch import batch_for_shader

    context = bpy.context
    space = context.space_data
    region = context.region
    if space is None or space.type != "CLIP_EDITOR" or space.clip is None or region is None:
        return
    track = _track()
    if track is None:
        return
    width, height = space.clip.size
    if width <= 0 or height <= 0:
        return
    frame = context.scene.frame_current
    est = track.frame(frame)
    shader = gpu.shader.from_builtin("2D_UNIFORM_COLOR")
    gpu.state.blend_set("ALPHA")
    gpu.state.line_width_set(2.0)
    if est is not None and est.shadow_start_px and est.shadow_end_px:
        a = clip_to_region(region, width, height, *est.shadow_start_px)
        b = clip_to_region(region, width, height, *est.shadow_end_px)
        good = est.confidence >= 0.5 and est.raw_zenith_deg is not None
        shader.bind()
        shader.uniform_float("color", (1.0, 0.9, 0.1, 1.0) if good else (1.0, 0.3, 0.2, 1.0))
        batch_for_shader(shader, "LINES", {"pos": [a, b]}).draw(shader)
        gpu.state.point_size_set(7.0)
        batch_for_shader(shader, "POINTS", {"pos": [a, b]}).draw(shader)
        blf.position(0, b[0] + 8, b[1] + 8, 0)
        blf.size(0, 12)
        blf.draw(0, f"{est.confidence:.2f}" if est.reason is None else est.reason[:40])
    lines = _series_plot(track, frame, 20, 45, min(260, region.width * 0.3), 70)
    for pts, color in lines:
        shader.bind()
        shader.uniform_float("color", color)
        batch_for_shader(shader, "LINE_STRIP", {"pos": pts}).draw(shader)
    gpu.state.line_width_set(1.0)
    gpu.state.blend_set("NONE")


def register():
    global _handle
    if _handle is None and not bpy.app.background:
        _handle = bpy.types.SpaceClipEditor.draw_handler_add(_draw, (), "WINDOW", "POST_PIXEL")
    if invalidate not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(invalidate)


def unregister():
    global _handle
    if _handle is not None:
        bpy.types.SpaceClipEditor.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    if invalidate in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(invalidate)
