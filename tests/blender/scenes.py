"""Small scenes built in Blender for the tests."""
import math
import os

import bpy
import numpy as np
from mathutils import Vector


def add_camera(scene, location, target, lens=35.0, sensor_fit="AUTO",
               sensor_width=36.0, sensor_height=24.0, shift=(0.0, 0.0),
               name="Camera"):
    cam = bpy.data.cameras.new(name)
    cam.lens = lens
    cam.sensor_fit = sensor_fit
    cam.sensor_width = sensor_width
    cam.sensor_height = sensor_height
    cam.shift_x, cam.shift_y = shift
    obj = bpy.data.objects.new(name, cam)
    scene.collection.objects.link(obj)
    obj.location = location
    direction = Vector(target) - Vector(location)
    obj.rotation_euler = direction.to_track_quat("-Z", "Y").to_euler()
    scene.camera = obj
    bpy.context.view_layer.update()
    return obj


def add_box_on_plane(scene, collection_name="Model"):
    """A 20 m ground plane, a box and a pole, in a 'Model' collection."""
    coll = bpy.data.collections.new(collection_name)
    scene.collection.children.link(coll)

    def mesh_obj(name, verts, faces, location=(0, 0, 0)):
        me = bpy.data.meshes.new(name)
        me.from_pydata(verts, [], faces)
        me.update()
        ob = bpy.data.objects.new(name, me)
        ob.location = location
        coll.objects.link(ob)
        return ob

    ground = mesh_obj("Ground", [(-10, -10, 0), (10, -10, 0), (10, 10, 0), (-10, 10, 0)],
                      [(0, 1, 2, 3)])
    cube_v = [(x, y, z) for z in (0, 2) for y in (-1, 1) for x in (-1, 1)]
    cube_f = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    box = mesh_obj("Box", cube_v, cube_f, location=(-2, 1, 0))
    box.rotation_euler = (0, 0, math.radians(25))
    pole_v = [(x * 0.1, y * 0.1, z) for z in (0, 3) for y in (-1, 1) for x in (-1, 1)]
    pole = mesh_obj("Pole", pole_v, cube_f, location=(3, -2, 0))
    bpy.context.view_layer.update()
    return coll, ground, box, pole


def write_frames(folder, count=3, width=64, height=48):
    """A tiny PNG sequence; returns the first file's path."""
    os.makedirs(folder, exist_ok=True)
    paths = []
    for i in range(count):
        img = bpy.data.images.new(f"frame{i}", width, height)
        px = np.zeros((height, width, 4), dtype=np.float32)
        px[..., :3] = 0.2 + 0.6 * (i + 1) / count
        px[..., 3] = 1
        img.pixels.foreach_set(px.ravel())
        path = os.path.join(folder, f"frame_{i + 1:04d}.png")
        img.filepath_raw = path
        img.file_format = "PNG"
        img.save()
        bpy.data.images.remove(img)
        paths.append(path)
    return paths[0]


def load_clip(scene, first_frame_path):
    clip = bpy.data.movieclips.load(first_frame_path)
    scene.active_clip = clip
    return clip
