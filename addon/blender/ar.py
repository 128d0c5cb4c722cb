"""AR render setup (bpy side): inserts lit by the tracked Sun, over the clip.

Cycles renders the virtual objects with a transparent film; the model (ground
and every modelled object) becomes a shadow catcher, so it shows only the
shadows the inserts cast and hides inserts behind real objects. The
compositor multiplies the clip by the Shadow Catcher pass (a per-channel
ratio, so shadows keep the footage's tint) and lays the inserts over it.

The Sun lamp's strength and colour and a uniform sky's are keyed from the
footage's own shadows (core.arlight): the inserts' shadows come out as dark,
and as blue, as the real ones beside them. A small check render of the
model's own shadows then corrects what the formula leaves out.
"""

import os

import bpy
import numpy as np
from mathutils import Vector

from . import compat, gather, job, keys, store
from ..core import angles, arlight
from ..core.trackfile import Sunlight
from ..estimate import errors, frames as clip_frames, native_loader, notes

WORLD_NAME = "sunlapse sky"
# A long clip's light is measured on this many frames spread over it (and
# around each change of sunlight); Blender interpolates between them.
LIGHT_FRAMES = 48
# Frames are measured reduced to about this width: the shadows worth
# measuring are tens of pixels wide there, and 24 MP frames cost seconds.
LIGHT_WIDTH = 640
AR_KEYS_PROP = "sunlapse_ar_frames"
# Real shadows that see less of the sky than this are indoors or walled in:
# their light is bounced, which the open-sky balance does not model.
ENCLOSED_SKY_SEEN = 0.5
# Viewport samples for the AR preview: enough to judge the inserts' light.
PREVIEW_SAMPLES = 32


def _model_objects(context):
    settings = context.scene.sunlapse
    if settings.model_collection is not None:
        objs = settings.model_collection.all_objects
    else:
        objs = [o for o in context.view_layer.objects if o.visible_get()]
    return [o for o in objs if o.type == "MESH" and not gather.is_insert(o)]


def _compositor(scene, clip):
    """clip x Shadow Catcher pass, inserts alpha-over it, to the Composite
    and a Viewer (the backdrop shows the composite)."""
    nt = compat.compositor_tree(scene)
    for n in list(nt.nodes):
        if n.name.startswith("sunlapse"):
            nt.nodes.remove(n)
    rl = next((n for n in nt.nodes if n.bl_idname == "CompositorNodeRLayers"), None) \
        or nt.nodes.new("CompositorNodeRLayers")
    comp, comp_in = compat.composite_input(nt)
    mc = nt.nodes.new("CompositorNodeMovieClip")
    mc.name = "sunlapse clip"
    mc.clip = clip
    mul, mul_clip, mul_catcher, mul_out = compat.multiply_node(nt)
    mul.name = "sunlapse shadows"
    over = nt.nodes.new("CompositorNodeAlphaOver")
    over.name = "sunlapse over clip"
    over_back, over_front = compat.alpha_over_inputs(over)
    viewer = nt.nodes.new("CompositorNodeViewer")
    viewer.name = "sunlapse viewer"
    nt.links.new(mc.outputs["Image"], mul_clip)
    catcher = rl.outputs.get("Shadow Catcher")
    if catcher is not None:
        nt.links.new(catcher, mul_catcher)
    nt.links.new(mul_out, over_back)
    nt.links.new(rl.outputs["Image"], over_front)
    nt.links.new(over.outputs["Image"], comp_in)
    nt.links.new(over.outputs["Image"], viewer.inputs["Image"])
    for node, xy in ((rl, (0, 300)), (mc, (0, -100)), (mul, (300, 0)), (over, (500, 150)),
                     (comp, (750, 250)), (viewer, (750, 50))):
        node.location = xy


def _place_insert(context, camera_obj):
    """A sample object on the ground near the middle of the view."""
    scene = context.scene
    depsgraph = context.evaluated_depsgraph_get()
    origin = camera_obj.matrix_world.translation
    forward = camera_obj.matrix_world.to_3x3() @ Vector((0, -0.25, -1))
    hit, loc, *_ = scene.ray_cast(depsgraph, origin, forward.normalized())
    if not hit:
        loc = Vector((0, 0, 0))
    size = max(0.2, 0.05 * (loc - origin).length)
    mesh = bpy.data.meshes.new(gather.INSERT_NAME)
    h = size / 2
    verts = [(x, y, z) for z in (0, size) for y in (-h, h) for x in (-h, h)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(gather.INSERT_NAME, mesh)
    obj[gather.INSERT_PROP] = True
    obj.location = loc
    mat = bpy.data.materials.new(gather.INSERT_NAME)
    mat.diffuse_color = (0.8, 0.15, 0.1, 1.0)
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.15, 0.1, 1)
    mesh.materials.append(mat)
    scene.collection.objects.link(obj)
    return obj


def _out_of_shot(obj, camera_obj, distance=1.0):
    """Puts a helper (the Sun lamp: only its direction counts) just behind
    the camera, where it is never in the shot."""
    m = camera_obj.matrix_world
    obj.location = m.translation + m.to_3x3() @ Vector((0.0, 0.0, distance))


def _sky_world(scene):
    """A uniform sky (colour and strength keyed per frame) as the world."""
    world = bpy.data.worlds.get(WORLD_NAME) or bpy.data.worlds.new(WORLD_NAME)
    world.use_nodes = True
    nt = world.node_tree
    bg = next((n for n in nt.nodes if n.type == "BACKGROUND"), None) \
        or nt.nodes.new("ShaderNodeBackground")
    out = next((n for n in nt.nodes if n.type == "OUTPUT_WORLD"), None) \
        or nt.nodes.new("ShaderNodeOutputWorld")
    for link in list(bg.inputs["Color"].links):
        nt.links.remove(link)
    if not bg.outputs["Background"].links:
        nt.links.new(bg.outputs["Background"], out.inputs["Surface"])
    scene.world = world
    return world, bg


def _clear_keys(id_data, paths):
    curves = compat.fcurves(id_data)
    for fc in list(curves or ()):
        if fc.data_path in paths:
            curves.remove(fc)


def light_frames(track) -> list:
    """The frames whose light is measured: every keyed frame of a short
    clip; on a long one LIGHT_FRAMES spread over it, plus the frames on
    either side of each change of sunlight (where the lamp goes off)."""
    frames = track.keyable()
    numbers = [f.frame for f in frames]
    if len(numbers) <= LIGHT_FRAMES:
        return numbers
    picks = set(notes.spread(numbers, LIGHT_FRAMES))
    for a, b in zip(frames, frames[1:]):
        if (a.sunlight == Sunlight.NO) != (b.sunlight == Sunlight.NO):
            picks.update((a.frame, b.frame))
    return sorted(picks)


def measure_light(context, track, frames, progress=None):
    """The footage's light on `frames` (core.arlight.LightSample each): on a
    frame with direct sunlight, the model's cast shadow toward the tracked
    Sun against the lit ground beside it; on one without, the ground's
    brightness. Frames are read once, in order, reduced to about
    LIGHT_WIDTH. Returns (samples, sky seen in shadow, sky seen lit, ground
    names); the sky visibilities are the medians over the shadows measured
    (1 where none was)."""
    settings = context.scene.sunlapse
    model, cam, clip = job.gather_all(context, settings)
    names = job.ground_names(settings, model) or gather.guess_ground(model)
    ids = model.ids_of(names)
    if not ids or not frames:
        return [], 1.0, 1.0, names
    scene_n, camera_n = gather.build_scene(model), gather.build_camera(cam)
    native = native_loader.require()
    stride = max(1, round(camera_n.width / LIGHT_WIDTH))
    try:
        source = clip_frames.FrameSource(
            clip_frames.open_clip(clip.filepath, frames[0] - clip.frame_start),
            clip.frame_start, frames[0] - clip.frame_start)
    except errors.EstimateError:
        return [], 1.0, 1.0, names
    samples, seen_shadow, seen_lit = [], [], []
    for i, f in enumerate(frames):
        est = track.frame(f)
        if est is None or not est.has_estimate:
            continue
        if progress is not None:
            progress(i / len(frames), f"AR setup: the footage's light on frame {f}")
        try:
            bgr = source.read(f)
        except StopIteration:
            break
        if bgr is None or clip_frames.wrong_size(bgr, camera_n):
            continue
        sun = angles.sun_in_world_from_geographic(est.zenith_deg, est.azimuth_deg,
                                                  track.north_offset_deg)
        ground, shadow = notes.ground_and_model_shadow(scene_n, camera_n, ids, tuple(sun),
                                                       settings.ignore_top_rows, stride)
        # Each reduced pixel the mean of the block around the pixel the masks
        # cast through: a point sample kept a large still's grain.
        rgb = native.linear_block_means(bgr, stride, arlight.SRGB_TO_LINEAR_TABLE)[..., ::-1]
        sample = arlight.LightSample(f, est.zenith_deg, est.sunlight)
        if est.sunlight == Sunlight.NO:
            sample.ground_linear = arlight.ground_level(rgb, ground > 0)
        else:
            sample.balance = arlight.measure_shadow_balance(rgb, ground > 0, shadow > 0)
        if sample.balance is None and sample.ground_linear is None:
            continue
        if sample.balance is not None:
            for mask, seen in ((sample.balance.shadow_mask, seen_shadow),
                               (sample.balance.lit_mask, seen_lit)):
                rows, cols = np.nonzero(mask)
                _, origins = notes.ground_samples(scene_n, camera_n, ids, rows * stride,
                                                  cols * stride)
                seen.append(arlight.sky_seen(origins, lambda o, d: scene_n.occluded(o, d)))
        samples.append(sample)
    vs = float(np.median(seen_shadow)) if seen_shadow else 1.0
    vl = float(np.median(seen_lit)) if seen_lit else 1.0
    return samples, vs, vl, names


def _sunlit(samples):
    return [s for s in samples if s.balance is not None and s.sunlight != Sunlight.NO]


def key_light(context, sun_obj, track, samples, vs, vl, corrections=None):
    """Keys the lamp's strength and colour and the sky's, frame by frame,
    from the measured light (core.arlight.light_per_frame; Blender
    interpolates between the frames measured and holds the ends). Frames of
    the track without direct sunlight that were not measured get the lamp
    off too. `corrections` (from match_render): the renderer's Sun
    response by zenith. Returns {frame: target shadow ratio RGB}."""
    scene = context.scene
    world, bg = _sky_world(scene)
    data = sun_obj.data
    _clear_keys(data, {"energy", "color"})
    _clear_keys(world.node_tree, {f'nodes["{bg.name}"].inputs[0].default_value',
                                  f'nodes["{bg.name}"].inputs[1].default_value'})
    lights = arlight.light_per_frame(samples, vs, vl, corrections)
    targets = {}
    for light in lights:
        strength, color = arlight.as_strength_and_color(light.sun_rgb)
        data.energy = strength if light.target_ratio is not None else 0.0
        data.keyframe_insert("energy", frame=light.frame)
        if light.target_ratio is not None:
            # The colour stays the Sun's last where the lamp is off.
            data.color = color
            data.keyframe_insert("color", frame=light.frame)
            targets[light.frame] = light.target_ratio
        strength, color = arlight.as_strength_and_color(light.sky_rgb)
        bg.inputs["Color"].default_value = color + (1.0,)
        bg.inputs["Strength"].default_value = strength
        bg.inputs["Color"].keyframe_insert("default_value", frame=light.frame)
        bg.inputs["Strength"].keyframe_insert("default_value", frame=light.frame)
    measured = {light.frame for light in lights}
    dark = [f for f in track.without_sunlight() if f not in measured]
    for f in dark:
        data.energy = 0.0
        data.keyframe_insert("energy", frame=f)
    keyed = sorted(measured.union(dark))
    data[AR_KEYS_PROP] = keyed
    # These are the lamp's strength keys now: Apply to Sun Lamp replaces them.
    data[keys.KEYED_FRAMES_PROP] = keyed
    return targets


# The check render: at most this wide, this many samples, on this many frames.
MATCH_WIDTH = 480
MATCH_SAMPLES = 16
MATCH_FRAMES = 3
MATCH_MIN_ELEVATION_DEG = 5.0


def render_model_shadows(context, frame, shadow_mask, lit_mask, casters, inserts):
    """Renders the Shadow Catcher pass of `frame` with the model's casters
    (not the ground) casting instead of catching, the inserts hidden, small;
    returns the pass's median RGB over `shadow_mask` against its median over
    `lit_mask` (the pixels measured in the footage, clip size): the casters
    hide some sky from the lit ground beside their shadows too, as the real
    ones do in the footage's ratio. None when it cannot be read. The pass
    goes through a temporary File Output node (the Viewer's pixels are not
    readable in background mode)."""
    import tempfile
    scene = context.scene
    nt = compat.compositor_tree(scene, create=False)
    if nt is None:
        return None
    rl = next((n for n in nt.nodes if n.bl_idname == "CompositorNodeRLayers"), None)
    catcher = rl.outputs.get("Shadow Catcher") if rl is not None else None
    if catcher is None:
        return None
    r = scene.render
    saved = dict(frame=scene.frame_current, samples=scene.cycles.samples,
                 pct=r.resolution_percentage, comp=r.use_compositing,
                 catch={o.name: o.is_shadow_catcher for o in casters},
                 hide={o.name: o.hide_render for o in inserts})
    out = None
    with tempfile.TemporaryDirectory(prefix="sunlapse_") as folder:
        try:
            scene.frame_set(frame)
            scene.cycles.samples = MATCH_SAMPLES
            r.resolution_percentage = max(1, min(100, int(100 * MATCH_WIDTH /
                                                          max(1, r.resolution_x))))
            r.use_compositing = True
            for o in casters:
                o.is_shadow_catcher = False
            for o in inserts:
                o.hide_render = True
            out, out_in, written = compat.file_output(nt, folder, "catcher")
            out.name = "sunlapse check"
            nt.links.new(catcher, out_in)
            bpy.ops.render.render()
            path = written(frame)
            if not os.path.exists(path):
                return None
            img = bpy.data.images.load(path)
            try:
                w, h = img.size
                px = np.array(img.pixels[:], dtype=np.float64).reshape(h, w, -1)[::-1, :, :3]
            finally:
                bpy.data.images.remove(img)
        finally:
            if out is not None:
                nt.nodes.remove(out)
            scene.frame_set(saved["frame"])
            scene.cycles.samples = saved["samples"]
            r.resolution_percentage = saved["pct"]
            r.use_compositing = saved["comp"]
            for o in casters:
                o.is_shadow_catcher = saved["catch"][o.name]
            for o in inserts:
                o.hide_render = saved["hide"][o.name]
    H, W = shadow_mask.shape
    rows = np.minimum(H - 1, (np.arange(h) * H / h).astype(int))
    cols = np.minimum(W - 1, (np.arange(w) * W / w).astype(int))
    shadow, lit = shadow_mask[rows][:, cols], lit_mask[rows][:, cols]
    if shadow.sum() < arlight.MIN_PIXELS or lit.sum() < arlight.MIN_PIXELS:
        return None
    beside = np.maximum(np.median(px[lit], axis=0), 1e-6)
    return tuple(float(v) for v in np.median(px[shadow], axis=0) / beside)


def match_render(context, sun_obj, track, samples, vs, vl, model_objects, ground_names):
    """Renders the model's own shadows (render_model_shadows) on up to
    MATCH_FRAMES frames with a measured shadow (the lowest Sun at least
    MATCH_MIN_ELEVATION_DEG up, the highest, one between) and re-keys the
    light so that they come out as dark, per channel, as the footage's:
    what the shading formula leaves out (specular, bounced light, a ground
    brighter under a grazing Sun than Lambert's) is corrected by the
    renderer itself, as a function of the Sun's height. Returns (rendered
    ratio, target ratio) of each check."""
    ground = set(ground_names)
    casters = [o for o in model_objects if o.name not in ground]
    sunlit = sorted(_sunlit(samples), key=lambda s: s.zenith_deg)
    if not casters or not sunlit:
        return []
    # A Sun a degree or two up lights the ground through its disc's edge
    # and long penumbrae: a check there says little of the frames above it.
    sunlit = [s for s in sunlit if s.zenith_deg <= 90.0 - MATCH_MIN_ELEVATION_DEG] or sunlit
    picks = [sunlit[round(i * (len(sunlit) - 1) / max(1, MATCH_FRAMES - 1))]
             for i in range(min(MATCH_FRAMES, len(sunlit)))]
    picks = list({s.frame: s for s in picks}.values())
    targets = key_light(context, sun_obj, track, samples, vs, vl)
    inserts = [o for o in bpy.data.objects if gather.is_insert(o)]
    checks, corrections = [], []
    for s in picks:
        got = render_model_shadows(context, s.frame, s.balance.shadow_mask,
                                   s.balance.lit_mask, casters, inserts)
        if got is None:
            continue
        corrections.append((s.zenith_deg, arlight.sun_response(got, targets[s.frame],
                                                               s.zenith_deg, vs, vl)))
        checks.append((got, targets[s.frame]))
    if corrections:
        key_light(context, sun_obj, track, samples, vs, vl, corrections)
    return checks


def preview_in_viewports(context, camera_obj):
    """Every 3D View of the window looks through the camera, rendered: the
    footage behind (camera background, transparent film), the model as
    shadow catcher, the inserts lit by the keyed Sun. The 3D Views an area
    keeps while it shows another editor (the Movie Clip Editor the setup
    ran from) are set too: switching the area back shows the preview.
    Returns how many were set."""
    screen = getattr(context, "screen", None) or getattr(context.window, "screen", None)
    if screen is None:
        return 0
    n = 0
    for area in screen.areas:
        for space in area.spaces:
            if space.type != "VIEW_3D" or space.region_3d is None:
                continue
            space.shading.type = "RENDERED"
            space.region_3d.view_perspective = "CAMERA"
            if space.use_local_camera:
                space.camera = camera_obj
            n += 1
        area.tag_redraw()
    return n


def setup(context, add_sample_object=True, balance=True, preview=True, warnings=None,
          match_shadows=True, details=None, progress=None):
    """Configures the scene for AR renders; returns a one-line summary.
    Warnings go to `warnings` (a list) when given, else into the summary;
    likewise the light's measured figures to `details`. `progress(fraction,
    text)` is told each step (the check render takes seconds)."""
    def step(fraction, text):
        if progress is not None:
            progress(fraction, text)
    scene = context.scene
    settings = scene.sunlapse
    sun = settings.sun_lamp
    if sun is None or not (sun.animation_data and sun.animation_data.action):
        raise ValueError("no animated Sun lamp: run Estimate Sun, then Apply to Sun Lamp")
    camera_obj = settings.camera or scene.camera
    if camera_obj is None:
        raise gather.SceneError("The scene has no camera.")
    clip = gather.active_movieclip(context)
    if clip is None:
        raise gather.SceneError("No clip: open the footage in the Movie Clip Editor.")
    scene.camera = camera_obj
    scene.render.engine = "CYCLES"
    scene.render.film_transparent = True
    # The plate goes through the view transform with the render: Standard
    # shows it as it is in the file (Filmic would grade it a second time).
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    # Cycles' default viewport samples (1024, or 0: unlimited) keep a CPU
    # busy for minutes on a preview that needs a few dozen.
    if scene.cycles.preview_samples == 0 or scene.cycles.preview_samples > PREVIEW_SAMPLES:
        scene.cycles.preview_samples = PREVIEW_SAMPLES
    bounce_note = ""
    if scene.cycles.max_bounces == 0 or scene.cycles.diffuse_bounces == 0:
        # The footage's shadows hold light bounced off their casters: under
        # cloud, a tenth of it beside a kiosk (docs/accuracy.md).
        note = ("Render Properties > Light Paths: Max Bounces or Diffuse is 0, so the inserts "
                "bounce no light onto the ground and their shadows come out darker than the "
                "footage's, most under cloud and at dusk (4 or more is usual)")
        if warnings is None:
            bounce_note = ". Warning: " + note
        else:
            warnings.append(note)
    step(0.05, "AR setup: the scene and the compositor")
    model = _model_objects(context)
    for obj in model:
        obj.is_shadow_catcher = True
    cycles_vl = getattr(context.view_layer, "cycles", None)
    if cycles_vl is not None and hasattr(cycles_vl, "use_pass_shadow_catcher"):
        cycles_vl.use_pass_shadow_catcher = True
    track = store.load_track()
    comp_note = ""
    try:
        _compositor(scene, clip)
    except (AttributeError, KeyError, RuntimeError, TypeError) as e:
        # Blender 5 moved the compositor to node groups: the render and the
        # viewport preview still work; the composite is then left to the user.
        comp_note = f"; compositor not set up on Blender {bpy.app.version_string} ({e})"
        if warnings is not None:
            warnings.append("the compositor could not be set up: lay the render over the clip "
                            "with the Shadow Catcher pass yourself")
    cam = camera_obj.data
    cam.show_background_images = True
    bg = next((b for b in cam.background_images if b.source == "MOVIE_CLIP" and b.clip == clip),
              None)
    if bg is None:
        bg = cam.background_images.new()
        bg.source = "MOVIE_CLIP"
        bg.clip = clip
    bg.alpha = 1.0
    bg.display_depth = "BACK"
    if hasattr(bg, "clip_user"):
        bg.clip_user.proxy_render_size = "FULL"
    _out_of_shot(sun, camera_obj)
    inserted = ""
    if add_sample_object and not gather.insert_names():
        _place_insert(context, camera_obj)
        inserted = f", added '{gather.INSERT_NAME}'"
    light = ""
    samples, vs, vl, ground_names = [], 1.0, 1.0, []
    if balance and track is not None:
        picks = light_frames(track)
        step(0.2, f"AR setup: measuring the footage's light on {len(picks)} frames")
        samples, vs, vl, ground_names = measure_light(
            context, track, picks,
            progress=lambda x, text: step(0.2 + 0.3 * x, text))
    sunlit = _sunlit(samples)
    checked = []
    if sunlit:
        key_light(context, sun, track, samples, vs, vl)
        if match_shadows and not comp_note:  # the check render reads a compositor output
            step(0.5, "AR setup: rendering the model's shadows to match the footage's")
            try:
                checked = match_render(context, sun, track, samples, vs, vl, model,
                                       ground_names)
            except (AttributeError, KeyError, RuntimeError, TypeError) as e:
                if warnings is not None:
                    warnings.append(f"the check render of the model's shadows failed ({e}): "
                                    f"the light is set from the formula alone")
        if track is not None:
            # The lamp's strength is the light's now: only its direction is keyed.
            keys.apply_track(context, track, sun, sync_sky=False, key_strength=False)
        ratios = np.median([s.balance.shadow_ratio for s in sunlit], axis=0)
        dark = len(samples) - len(sunlit)
        figures = [f"light measured on {len(samples)} frame(s) of the footage: shadow/lit "
                   f"R {ratios[0]:.2f} G {ratios[1]:.2f} B {ratios[2]:.2f} (linear, median of "
                   f"{len(sunlit)}); their casters hide {100 * (1 - vs):.0f}% of the sky"]
        if dark:
            figures.append(f"{dark} frame(s) without direct sunlight: the lamp off, the sky "
                           f"as bright as their ground")
        if checked:
            pairs = ", ".join(f"{'/'.join(f'{v:.2f}' for v in got)} for "
                              f"{'/'.join(f'{v:.2f}' for v in want)}" for got, want in checked)
            figures.append(f"the model's shadows rendered (R/G/B, for the footage's): {pairs}: "
                           f"corrected")
        if details is None:
            light = "; " + "; ".join(figures)
        else:
            details.extend(figures)
            light = (f", lamp and sky lit as the footage shows, frame by frame "
                     f"({len(samples)} frames{', checked by renders' if checked else ''})")
        if vs < ENCLOSED_SKY_SEEN:
            note = ("the footage's shadows are enclosed (a room?): the light of an open sky is "
                    "assumed and the inserts' shadows will come out too dark")
            if warnings is None:
                light += ". Warning: " + note
            else:
                warnings.append(note)
    elif balance:
        light = "; no real shadow measurable in the footage: lamp and sky left as they were"
        if scene.world is None:
            world, bgn = _sky_world(scene)
            bgn.inputs["Color"].default_value = (0.55, 0.7, 1.0, 1.0)
            bgn.inputs["Strength"].default_value = 0.3
    step(0.95, "AR setup: the preview")
    scene.frame_set(scene.frame_current)
    shown = ""
    if preview and not bpy.app.background:
        shown = ("; previewed in the 3D View through the camera"
                 if preview_in_viewports(context, camera_obj) else
                 "; open a 3D View (it looks through the camera, rendered) or render (F12) "
                 "to see it")
    return (f"AR render set up: {len(model)} model objects catch shadows{inserted}{light}"
            f"{comp_note}{shown}{bounce_note}")


def render_frames(context, folder, frames):
    """Renders the composited AR frames to folder/ar_####.png."""
    scene = context.scene
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.filepath = bpy.path.abspath(folder).rstrip("/") + "/ar_"
    scene.frame_start, scene.frame_end = frames
    bpy.ops.render.render(animation=True)
