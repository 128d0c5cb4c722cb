"""gather.guess_ground: the lowest large horizontal surface the camera looks
down on, never a ceiling (issue 14)."""
import numpy as np

from sunlapse.blender import gather


def boxes(*specs):
    """A Model of axis-aligned boxes: (name, (x0, y0, z0), (x1, y1, z1)),
    each box's 12 triangles wound outward."""
    verts, tris, ids, names = [], [], [], []
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    for k, (name, lo, hi) in enumerate(specs):
        base = len(verts)
        verts += [(x, y, z) for z in (lo[2], hi[2]) for y in (lo[1], hi[1]) for x in (lo[0], hi[0])]
        for a, b, c, d in quads:
            tris += [(base + a, base + b, base + c), (base + a, base + c, base + d)]
        ids += [k] * 12
        names.append(name)
    return gather.Model(np.array(verts, np.float32), np.array(tris, np.int32),
                        np.array(ids, np.int32), names)


ROOM = [("Floor", (-5, -5, -0.2), (5, 5, 0.0)),
        ("Ceiling", (-5, -5, 3.0), (5, 5, 3.2)),
        ("WallN", (-5, 5, 0), (5, 5.2, 3)), ("WallS", (-5, -5.2, 0), (5, -5, 3)),
        ("WallE", (5, -5, 0), (5.2, 5, 3)), ("WallW", (-5.2, -5, 0), (-5, 5, 3))]


def test_a_room_gets_its_floor_not_its_ceiling():
    # Floor and ceiling are slabs of one size: both faces of each count as
    # horizontal, so only their height tells them apart.
    assert gather.guess_ground(boxes(*ROOM)) == ["Floor"]
    assert gather.guess_ground(boxes(*ROOM), camera=(0, 0, 1.6)) == ["Floor"]
    # Listed ceiling first, a larger ceiling: still the floor.
    big = [("Ceiling", (-6, -6, 3.0), (6, 6, 3.2))] + [r for r in ROOM if r[0] != "Ceiling"]
    assert gather.guess_ground(boxes(*big)) == ["Floor"]


def test_a_ceiling_slab_above_the_camera_is_never_the_ground():
    # Under a canopy, a small patch of ground in view: the canopy is larger
    # but the camera cannot see its upper face.
    model = boxes(("Canopy", (-10, -10, 4.0), (10, 10, 4.2)),
                  ("Ground", (-3, -3, -0.1), (3, 3, 0.0)))
    assert gather.guess_ground(model, camera=(0, -2, 2.0)) == ["Ground"]


def test_a_small_pit_does_not_beat_the_plaza():
    model = boxes(("Plaza", (-20, -20, -0.1), (20, 20, 0.0)),
                  ("Drain", (0, 0, -0.6), (0.5, 0.5, -0.5)),
                  ("Roof", (-4, -4, 6.0), (4, 4, 6.2)))
    assert gather.guess_ground(model, camera=(0, -30, 10)) == ["Plaza"]


def test_lawn_and_tiles_at_the_ground_level_are_kept_together():
    model = boxes(("Tiles", (-10, -10, -0.1), (0, 10, 0.0)),
                  ("Lawn", (0, -10, -0.1), (10, 10, 0.02)),
                  ("Table", (-1, -1, 0.9), (1, 1, 1.0)))
    assert sorted(gather.guess_ground(model, camera=(0, -20, 5))) == ["Lawn", "Tiles"]


def test_no_horizontal_surface_gives_no_guess():
    wall = gather.Model(np.array([[-5, 0, 0], [5, 0, 0], [5, 0, 3]], np.float32),
                        np.array([[0, 1, 2]], np.int32), np.zeros(1, np.int32), ["Wall"])
    assert gather.guess_ground(wall) == []
