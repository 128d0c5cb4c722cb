"""Draws the stored Sun track over the clip in the Movie Clip Editor.

On the current frame: the tracked shadow (caster foot to shadow tip), its
ends, and its labelled confidence; at the bottom, on a dark box, a plot over
the clip: elevation and azimuth (each on its own axis, in degrees, titled
with what the azimuth is measured from) and the confidence, with the current
frame marked and its values written on a line of their own above it. Both
are turned on and off in the editor's Overlays popover (Display in 3.x).
"""

import bpy

from .blender import compat, store
from .core import angles, trackfile

_handle = None


def clip_to_region(region, width, height, x_px, y_px):
    """OpenCV pixel of the clip (0,0 = centre of the top-left pixel, y down)
    -> region pixel. The clip editor's view2d works in normalised clip
    coordinates (0..1, y up)."""
    u = (x_px + 0.5) / width
    v = 1.0 - (y_px + 0.5) / height
    return region.view2d.view_to_region(u, v, clip=False)


# Plot colours: elevation orange, azimuth blue, confidence grey-green.
ELEVATION_COLOR = (1.0, 0.6, 0.1, 1.0)
AZIMUTH_COLOR = (0.35, 0.65, 1.0, 1.0)
CONFIDENCE_COLOR = (0.55, 0.85, 0.55, 1.0)
PLOT_BACK = (0.0, 0.0, 0.0, 0.6)
UNLIT_SHADE = (0.25, 0.3, 0.55, 0.35)  # frames without direct sunlight
PLOT_GAP = 16  # pixels between strips, for their titles


def nice_range(lo, hi, min_span=2.0):
    """Axis limits around [lo, hi] on round degrees, at least min_span wide."""
    import math
    mid, span = (lo + hi) / 2, max(hi - lo, min_span)
    step = 10 ** math.floor(math.log10(span / 2))
    for m in (1, 2, 5, 10):
        if span / (m * step) <= 4:
            step *= m
            break
    return math.floor((mid - span / 2) / step) * step, math.ceil((mid + span / 2) / step) * step


def _text_width(text, size):
    """A text's width without the font (tests): the UI font's digits and
    letters average about 0.6 of its size."""
    return 0.6 * size * len(text)


def plot_layout(track, frame, x0, y0, w, h, size=11.0, text_width=_text_width):
    """What the plot draws, in region pixels, as plain data (tested without
    a GPU): strips of (title, colour, (lo, hi), points), the frame marker x,
    the current frame's values, and the text labels below and above the
    strips as (text, x, y) with `size`-pixel text measured by `text_width`.
    Elevation and azimuth (as the panel shows them) each get a strip with
    its own degree axis; confidence 0..1. The frame range sits under the
    plot, the current frame's readout on its own line over it, so that
    neither covers the other at any frame."""
    est = [f for f in track.frames if f.has_estimate]
    if len(est) < 2:
        return None
    f0, f1 = track.frames[0].frame, track.frames[-1].frame
    span = max(1, f1 - f0)
    north = track.north_known()

    def az(f):
        return angles.wrap_azimuth_deg(f.azimuth_deg) if north else \
            angles.azimuth_world_from_geographic(f.azimuth_deg, track.north_offset_deg)
    series = (("Elevation", ELEVATION_COLOR, [90.0 - f.zenith_deg for f in est]),
              ("Azimuth " + ("from north" if north else "from +Y"), AZIMUTH_COLOR,
               [az(f) for f in est]))
    gap = PLOT_GAP
    strip_h = (h - 3 * gap) / 3  # each strip's title sits in the gap above it
    strips = []
    for k, (title, color, vals) in enumerate(series):
        lo, hi = nice_range(min(vals), max(vals))
        sy = y0 + h - (k + 1) * (strip_h + gap)
        pts = [(x0 + w * (f.frame - f0) / span, sy + strip_h * (v - lo) / (hi - lo))
               for f, v in zip(est, vals)]
        strips.append((title + " (°)", color, (lo, hi), pts, sy, strip_h))
    sy = y0
    conf = [(x0 + w * (f.frame - f0) / span, sy + strip_h * max(0.0, min(1.0, f.confidence)))
            for f in track.frames]
    strips.append(("Confidence (0-1)", CONFIDENCE_COLOR, (0.0, 1.0), conf, sy, strip_h))
    # Runs of frames without direct sunlight, shaded across the strips
    # (half a frame's width past either end, within the plot).
    half = 0.5 * w / span
    unlit = [(max(x0, x0 + w * (a - f0) / span - half),
              min(x0 + w, x0 + w * (b - f0) / span + half))
             for a, b in trackfile.frame_runs(track.without_sunlight())]
    cur = track.frame(frame)
    values = None
    if cur is not None and cur.has_estimate:
        values = (90.0 - cur.zenith_deg, az(cur), cur.confidence)
    below = y0 - 1.45 * size
    labels = [(f"frame {f0}", x0, below)]
    last = f"frame {f1}"
    labels.append((last, x0 + w - text_width(last, size), below))
    if values is not None:
        el, azimuth, conf = values
        text = f"frame {frame}: elevation {el:.1f}°  azimuth {azimuth:.1f}°  confidence {conf:.2f}"
        if cur.predicted:
            text += "  (predicted: no sunlight)" if cur.sunlight == trackfile.Sunlight.NO \
                else "  (predicted)"
        labels.append((text, x0, y0 + h + 0.6 * size))
    return {"strips": strips, "marker_x": x0 + w * (min(max(frame, f0), f1) - f0) / span,
            "frames": (f0, f1), "values": values, "labels": labels, "box": (x0, y0, w, h),
            "unlit": unlit}


def _draw_plot(track, frame, region, shader, batch_for_shader, blf, gpu):
    scale = bpy.context.preferences.system.ui_scale
    left = 46 * scale                       # room for the degree labels
    w = min(520 * scale, region.width - left - 30 * scale)
    h = 190 * scale
    size = int(11 * scale)
    x0, y0 = left + 10 * scale, 30 * scale
    compat.font_size(size)
    plot = plot_layout(track, frame, x0, y0, w, h, size,
                       lambda text, _: blf.dimensions(0, text)[0])
    if plot is None or w < 80:
        return
    # A dark box behind the plot keeps it readable over any footage; its top
    # line holds the current frame's readout.
    bx0, by0 = x0 - left, y0 - 22 * scale
    bx1, by1 = x0 + w + 12 * scale, y0 + h + 2.2 * size
    shader.bind()
    shader.uniform_float("color", PLOT_BACK)
    batch_for_shader(shader, "TRIS", {"pos": [(bx0, by0), (bx1, by0), (bx1, by1), (bx0, by0),
                                              (bx1, by1), (bx0, by1)]}).draw(shader)
    if plot["unlit"]:  # frames without direct sunlight: their Sun is the path's
        shader.uniform_float("color", UNLIT_SHADE)
        batch_for_shader(shader, "TRIS", {"pos": [
            p for a, b in plot["unlit"] for p in ((a, y0), (b, y0), (b, y0 + h), (a, y0),
                                                  (b, y0 + h), (a, y0 + h))]}).draw(shader)
    for title, color, (lo, hi), pts, sy, sh in plot["strips"]:
        shader.uniform_float("color", (1, 1, 1, 0.25))
        batch_for_shader(shader, "LINES", {"pos": [(x0, sy), (x0 + w, sy), (x0, sy + sh),
                                                   (x0 + w, sy + sh), (x0, sy), (x0, sy + sh)]}
                         ).draw(shader)
        shader.uniform_float("color", color)
        batch_for_shader(shader, "LINE_STRIP", {"pos": pts}).draw(shader)
        blf.color(0, *color)
        blf.position(0, x0 + 2 * scale, sy + sh + 4, 0)
        blf.draw(0, title)
        blf.color(0, 0.85, 0.85, 0.85, 1.0)
        for v, y in ((lo, sy), (hi, sy + sh - size * 0.75)):
            label = f"{v:.1f}" if hi <= 1.0 else f"{v:.0f}°"
            blf.position(0, x0 - left + 4 * scale, y, 0)
            blf.draw(0, label)
    xm = plot["marker_x"]
    shader.uniform_float("color", (1, 1, 1, 0.9))
    batch_for_shader(shader, "LINES", {"pos": [(xm, y0), (xm, y0 + h)]}).draw(shader)
    for k, (text, x, y) in enumerate(plot["labels"]):
        blf.color(0, *((1, 1, 1, 1) if k == 2 else (0.85, 0.85, 0.85, 1.0)))
        blf.position(0, x, y, 0)
        blf.draw(0, text)


_draw_failed = []


def _draw():
    """Draw handler: a failure is said once, never a traceback per redraw."""
    try:
        _draw_overlay()
    except Exception as e:  # noqa: BLE001 -- an overlay must never break the editor
        if not _draw_failed:
            _draw_failed.append(e)
            print(f"sunlapse: the overlay over the clip could not be drawn "
                  f"({type(e).__name__}: {e}); it stays off until Blender restarts")


def _draw_overlay():
    if _draw_failed:
        return
    import blf
    import gpu
    from gpu_extras.batch import batch_for_shader

    context = bpy.context
    space = context.space_data
    region = context.region
    if space is None or space.type != "CLIP_EDITOR" or space.clip is None or region is None:
        return
    track = store.load_track()
    if track is None:
        return
    width, height = space.clip.size
    if width <= 0 or height <= 0:
        return
    frame = context.scene.frame_current
    est = track.frame(frame)
    shader = compat.uniform_color_shader()
    gpu.state.blend_set("ALPHA")
    gpu.state.line_width_set(2.0)
    settings = getattr(context.scene, "sunlapse", None)
    if est is not None and est.shadow_start_px and est.shadow_end_px and \
            (settings is None or settings.show_shadow):
        a = clip_to_region(region, width, height, *est.shadow_start_px)
        b = clip_to_region(region, width, height, *est.shadow_end_px)
        good = est.confidence >= 0.5 and est.raw_zenith_deg is not None
        shader.bind()
        shader.uniform_float("color", (1.0, 0.9, 0.1, 1.0) if good else (1.0, 0.3, 0.2, 1.0))
        batch_for_shader(shader, "LINES", {"pos": [a, b]}).draw(shader)
        gpu.state.point_size_set(7.0)
        batch_for_shader(shader, "POINTS", {"pos": [a, b]}).draw(shader)
        blf.position(0, b[0] + 8, b[1] + 8, 0)
        compat.font_size(12)
        blf.color(0, 1, 1, 1, 1)
        blf.draw(0, f"shadow tracked, confidence {est.confidence:.2f}" if est.reason is None
                 else est.reason[:60])
    if settings is None or settings.show_plot:
        gpu.state.line_width_set(1.5)
        _draw_plot(track, frame, region, shader, batch_for_shader, blf, gpu)
    gpu.state.line_width_set(1.0)
    gpu.state.blend_set("NONE")


def register():
    global _handle
    if _handle is None and not bpy.app.background:
        _handle = bpy.types.SpaceClipEditor.draw_handler_add(_draw, (), "WINDOW", "POST_PIXEL")
    if store.invalidate not in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.append(store.invalidate)


def unregister():
    global _handle
    if _handle is not None:
        bpy.types.SpaceClipEditor.draw_handler_remove(_handle, "WINDOW")
        _handle = None
    if store.invalidate in bpy.app.handlers.load_post:
        bpy.app.handlers.load_post.remove(store.invalidate)
