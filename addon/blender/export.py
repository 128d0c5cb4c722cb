"""Exports of the Sun: the track as CSV, and the animated Sun lamp as glTF
(the track file itself: core.trackfile.write_track)."""

import csv
import os

import bpy

from ..core import trackfile


# Each export format's file extension (the track's has two parts).
EXTENSIONS = {"JSON": ".sun.json", "CSV": ".csv", "GLB": ".glb"}


def file_name(path: str, fmt: str) -> str:
    """`path` with the extension of `fmt` in place of any export extension
    it has: the track's two-part .sun.json is one extension (splitting at the
    last dot made 'scene.sun.json' 'scene.sun.sun.json')."""
    lower = path.lower()
    for ext in sorted(EXTENSIONS.values(), key=len, reverse=True) + [".json"]:
        if lower.endswith(ext):
            path = path[:-len(ext)]
            break
    return path + EXTENSIONS[fmt]


def export_csv(track, path):
    """frame, zenith_deg, azimuth_deg, confidence (one row per frame),
    written atomically (a temporary file in the same folder, renamed)."""
    import io
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(["frame", "zenith_deg", "azimuth_deg", "confidence"])
    for f in track.frames:
        w.writerow([f.frame,
                    "" if f.zenith_deg is None else f"{f.zenith_deg:.6f}",
                    "" if f.azimuth_deg is None else f"{f.azimuth_deg:.6f}",
                    f"{f.confidence:.4f}"])
    trackfile.write_text_atomic(path, buf.getvalue(), suffix=".csv", newline="")


def export_gltf(context, sun_obj, path):
    """The animated Sun lamp as glTF binary (.glb). Blender's bundled glTF
    exporter writes a light as a KHR_lights_punctual node and its rotation
    F-curves as node animation, which other tools (three.js, Unity, Unreal,
    Godot, Blender) read; FBX would also keep it, but glTF is the open one."""
    if sun_obj is None:
        raise ValueError("no Sun lamp to export: apply the track to a lamp first")
    view_layer = context.view_layer
    previous = [o for o in view_layer.objects if o.select_get()]
    active = view_layer.objects.active
    try:
        for o in previous:
            o.select_set(False)
        sun_obj.select_set(True)
        view_layer.objects.active = sun_obj
        # Through a temporary file in the same folder, renamed: a failed
        # export leaves an existing file as it was.
        import uuid
        tmp = os.path.join(os.path.dirname(os.path.abspath(path)),
                           f".sunlapse-{uuid.uuid4().hex}.glb")
        kwargs = dict(filepath=tmp, export_format="GLB", use_selection=True,
                      export_animations=True, export_force_sampling=True)
        # The option that turns lights on was renamed across Blender versions.
        props = bpy.ops.export_scene.gltf.get_rna_type().properties
        for name in ("export_lights", "export_punctual_lights"):
            if name in props:
                kwargs[name] = True
        try:
            result = bpy.ops.export_scene.gltf(**kwargs)
            if result == {"FINISHED"} and os.path.exists(tmp):
                os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    finally:
        sun_obj.select_set(False)
        for o in previous:
            o.select_set(True)
        view_layer.objects.active = active
    if result != {"FINISHED"}:
        raise RuntimeError(f"glTF export failed: {result}")
