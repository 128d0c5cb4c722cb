"""Long messages in the sidebar: several labels broken at the region's
width (one label is cut after a few words). bpy and blf only, so that the
notice of an add-on that cannot load (broken.py) uses it too."""

from . import compat


def _wrap(text, width_px, measure):
    """Words of `text` in lines no wider than width_px by `measure`."""
    lines, line = [], ""
    for word in text.split():
        trial = f"{line} {word}" if line else word
        if line and measure(trial) > width_px:
            lines.append(line)
            line = word
        else:
            line = trial
    if line:
        lines.append(line)
    return lines


def wrapped(layout, context, text, icon="NONE", max_lines=6, width_px=None):
    """A long message as several labels, broken at the panel's width (a
    single label would be cut after a few words); past max_lines, a button
    opens the whole of it."""
    import blf
    region = getattr(context, "region", None)
    scale = context.preferences.system.ui_scale or 1.0  # 0 with no window (blender -b)
    width = width_px if width_px is not None else \
        (region.width if region is not None else 300) - 72 * scale \
        - (20 * scale if icon != "NONE" else 0)
    compat.font_size(compat.label_points(context) * scale)
    lines = _wrap(text, width, lambda t: blf.dimensions(0, t)[0])
    col = layout.column(align=True)
    for k, line in enumerate(lines[:max_lines]):
        col.label(text=line, icon=icon if k == 0 else "BLANK1" if icon != "NONE" else "NONE")
    if len(lines) > max_lines:
        # The rest is a click away, not cut off.
        op = col.operator("clip.sunlapse_show_text", text=f"Read All ({len(lines)} lines)",
                          icon="TEXT")
        op.text = text
    return col
