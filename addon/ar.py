"""AR render setup (bpy side): inserts lit by the tracked Sun, over the clip.

Cycles renders the virtual objects with a transparent film; the model (ground
and every modelled object) becomes a shadow catcher, so it shows only the
shadows the inserts cast and hides inserts behind real objects; the
compositor lays the render over the clip's frames.
"""

import bpy
import numpy as np
from mathutils import Vector

from . import bridge, results

INSERT_NAME = "sunlapse_insert"


def _model_objects(context):
    settings = context.scene.sunlapse
    if settings.model_collection is not None:
        objs = settings.model_collection.all_objects
    else:
        objs = [o for o in context.view_layer.objects if o.visible_get()]
    return [o for o in objs if o.type == "MESH" and o.name != INSERT_NAME]


def _compositor(scene, clip):
    scene.use_nodes = True
    nt = scene.node_tree
    for n in list(nt.nodes):
        if n.bl_idname in ("CompositorNodeAlphaOver", "CompositorNodeMovieClip") and \
                n.name.startswith("sunlapse"):
            nt.nodes.remove(n)
    rl = next((n for n in nt.nodes if n.bl_idname == "CompositorNodeRLayers"), None) \
        or nt.nodes.new("CompositorNodeRLayers")
    comp = next((n for n in nt.nodes if n.bl_idname == "CompositorNodeComposite"), None) \
        or nt.nodes.new("CompositorNodeComposite")
    mc = nt.nodes.new("CompositorNodeMovieClip")
    mc.name = "sunlapse clip"
    mc.clip = clip
    over = nt.nodes.new("CompositorNodeAlphaOver")
    over.name = "sunlapse over clip"
    nt.links.new(mc.outputs["Image"], over.inputs[1])
    nt.links.new(rl.outputs["Image"], over.inputs[2])
    nt.links.new(over.outputs["Image"], comp.inputs["Image"])
    rl.location, mc.location, over.location, comp.location = (0, 200), (0, -100), (300, 100), (550, 100)


def _place_insert(context, camera_obj, ground_objs):
    """A sample object on the ground near the middle of the view."""
    scene = context.scene
    depsgraph = context.evaluated_depsgraph_get()
    origin = camera_obj.matrix_world.translation
    forward = camera_obj.matrix_world.to_3x3() @ Vector((0, -0.25, -1))
    hit, loc, *_ = scene.ray_cast(depsgraph, origin, forward.normalized())
    if not hit:
        loc = Vector((0, 0, 0))
    size = max(0.2, 0.05 * (loc - origin).length)
    mesh = bpy.data.meshes.new(INSERT_NAME)
    h = size / 2
    verts = [(x, y, z) for z in (0, size) for y in (-h, h) for x in (-h, h)]
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    mesh.from_pydata(verts, [], faces)
    obj = bpy.data.objects.new(INSERT_NAME, mesh)
    obj.location = loc
    mat = bpy.data.materials.new(INSERT_NAME)
    mat.diffuse_color = (0.8, 0.15, 0.1, 1.0)
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = (0.8, 0.15, 0.1, 1)
    mesh.materials.append(mat)
    scene.collection.objects.link(obj)
    return obj


def setup(context, add_sample_object=True):
    """Configures the scene for AR renders; returns a one-line summary."""
    scene = context.scene
    settings = scene.sunlapse
    sun = settings.sun_lamp
    if sun is None or not (sun.animation_data and sun.animation_data.action):
        raise ValueError("no animated Sun lamp: run Estimate Sun, then Apply to Sun Lamp")
    camera_obj = settings.camera or scene.camera
    if camera_obj is None:
        raise bridge.SceneError("The scene has no camera.")
    clip = bridge.active_movieclip(context)
    if clip is None:
        raise bridge.SceneError("No clip: open the footage in the Movie Clip Editor.")
    scene.render.engine = "CYCLES"
    scene.render.film_transparent = True
    model = _model_objects(context)
    for obj in model:
        obj.is_shadow_catcher = True
    if scene.world is None:  # skylight for the inserts, following the Sun
        world = bpy.data.worlds.new("sunlapse sky")
        world.use_nodes = True
        sky = world.node_tree.nodes.new("ShaderNodeTexSky")
        sky.sky_type = "NISHITA"
        sky.sun_disc = False
        world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.15
        world.node_tree.links.new(sky.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
        scene.world = world
        track = results.load_track()
        if track is not None:
            results.apply_track(context, track, sun, sync_sky=True)
    _compositor(scene, clip)
    cam = camera_obj.data
    cam.show_background_images = True
    if not any(bg.source == "MOVIE_CLIP" and bg.clip == clip for bg in cam.background_images):
        bg = cam.background_images.new()
        bg.source = "MOVIE_CLIP"
        bg.clip = clip
    inserted = ""
    if add_sample_object and INSERT_NAME not in bpy.data.objects:
        _place_insert(context, camera_obj, model)
        inserted = f", added '{INSERT_NAME}'"
    return f"AR render set up: {len(model)} model objects catch shadows{inserted}"


def render_frames(context, folder, frames):
    """Renders the composited AR frames to folder/ar_####.png."""
    scene = context.scene
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGB"
    scene.render.filepath = bpy.path.abspath(folder).rstrip("/") + "/ar_"
    scene.frame_start, scene.frame_end = frames
    bpy.ops.render.render(animation=True)
