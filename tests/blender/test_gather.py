"""Gathering the model from Blender and casting rays against it."""
import bpy
import numpy as np
from mathutils import Vector

import scenes
from sunlapse.blender import gather


def blender_triangles_and_bounds(objects):
    depsgraph = bpy.context.evaluated_depsgraph_get()
    count, lo, hi = 0, np.full(3, np.inf), np.full(3, -np.inf)
    for ob in objects:
        ev = ob.evaluated_get(depsgraph)
        me = ev.to_mesh()
        me.calc_loop_triangles()
        count += len(me.loop_triangles)
        for v in me.vertices:
            w = np.array(ev.matrix_world @ v.co)
            lo, hi = np.minimum(lo, w), np.maximum(hi, w)
        ev.to_mesh_clear()
    return count, lo, hi


def test_gathered_triangles_and_bounds_equal_blenders(empty_scene):
    coll, ground, box, pole = scenes.add_box_on_plane(empty_scene)
    box.modifiers.new("bevel", "BEVEL").segments = 2   # modifiers are honoured
    ground.modifiers.new("sub", "SUBSURF").levels = 2
    bpy.context.view_layer.update()
    model = gather.gather_model(bpy.context, coll)
    count, lo, hi = blender_triangles_and_bounds([ground, box, pole])
    assert model.num_triangles == count
    mlo, mhi = model.bounds()
    assert np.allclose(mlo, lo, atol=1e-5) and np.allclose(mhi, hi, atol=1e-5)
    assert sorted(model.names) == ["Box", "Ground", "Pole"]
    assert model.vertices.dtype == np.float32 and model.triangles.dtype == np.int32
    assert model.object_ids.shape == (model.num_triangles,)
    assert gather.guess_ground(model) == ["Ground"]


def test_default_model_is_every_visible_mesh(empty_scene):
    coll, ground, box, pole = scenes.add_box_on_plane(empty_scene)
    pole.hide_set(True)
    other = bpy.data.objects.new("Other", bpy.data.meshes.new("empty-mesh"))
    empty_scene.collection.objects.link(other)  # no faces: skipped
    model = gather.gather_model(bpy.context)
    assert sorted(model.names) == ["Box", "Ground"]


def test_collection_instances_are_gathered(empty_scene):
    coll, ground, box, pole = scenes.add_box_on_plane(empty_scene)
    inst = bpy.data.objects.new("BoxCopy", None)
    inst.instance_type = "COLLECTION"
    src = bpy.data.collections.new("Props")
    src.objects.link(box.copy())
    inst.instance_collection = src
    inst.location = (5, 5, 0)
    coll.objects.link(inst)
    bpy.context.view_layer.update()
    model = gather.gather_model(bpy.context, coll)
    assert any(n.startswith("BoxCopy/") for n in model.names)


def test_native_hits_agree_with_blender_ray_cast(empty_scene, native):
    scene = empty_scene
    scene.render.resolution_x, scene.render.resolution_y = 320, 240
    coll, ground, box, pole = scenes.add_box_on_plane(scene)
    scenes.add_camera(scene, (7, -11, 6), (0, 0, 0.5), lens=30)
    model = gather.gather_model(bpy.context, coll)
    nscene = gather.build_scene(model)
    cam = gather.build_camera(gather.gather_camera(bpy.context))
    rng = np.random.default_rng(3)
    pixels = np.column_stack([rng.uniform(0, 319, 400), rng.uniform(0, 239, 400)])
    hits = nscene.intersect_pixels(cam, pixels)
    rays = cam.pixel_rays(pixels)
    origin = Vector(cam.center_in_world)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    agree = 0
    for i in range(len(pixels)):
        ok, loc, normal, _, obj, _ = scene.ray_cast(depsgraph, origin, Vector(rays[i]))
        assert ok == bool(hits["hit"][i]), f"pixel {pixels[i]}"
        if not ok:
            continue
        assert np.linalg.norm(np.array(loc) - hits["point"][i]) < 1e-3
        assert model.names[hits["object_id"][i]] == obj.name
        n = np.array(normal)
        n = n if n @ rays[i] < 0 else -n
        assert np.linalg.norm(n - hits["normal"][i]) < 1e-3
        agree += 1
    assert agree > 100  # most pixels see the model


def test_occlusion_from_ground_toward_sun(empty_scene, native):
    coll, ground, box, pole = scenes.add_box_on_plane(empty_scene)
    nscene = gather.build_scene(gather.gather_model(bpy.context, coll))
    # Pole at (3,-2), 3 m tall; Sun from the south-west at 45 deg elevation:
    # the ground 1.5 m north-east of the pole is in its shadow.
    to_sun = np.array([-1.0, -1.0, np.sqrt(2.0)], dtype=np.float32)
    to_sun /= np.linalg.norm(to_sun)
    d = 1.5 / np.sqrt(2)
    origins = np.array([[3 + d, -2 + d, 0.0], [3 - d, -2 - d, 0.0]], dtype=np.float32)
    occ = nscene.occluded(origins, np.tile(to_sun, (2, 1)))
    assert occ.tolist() == [True, False]
