"""Gathers what the native core needs from the current Blender scene.

Everything here reads bpy; nothing writes it. Arrays are filled with
``foreach_get`` (no per-vertex Python loops) in the conventions of
docs/design.md §4: world frame = Blender's, OpenCV pixels, degrees at every boundary.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Dict, List, Optional, Sequence, Tuple

import bpy
import numpy as np

from ..estimate import native_loader


# The sample virtual object the AR setup drops in; objects with the custom
# property INSERT_PROP are inserts too: never part of the model.
INSERT_NAME = "sunlapse_insert"
INSERT_PROP = "sunlapse_insert"


def is_insert(obj) -> bool:
    return obj.name == INSERT_NAME or bool(obj.get(INSERT_PROP))


def insert_names():
    return [o.name for o in bpy.data.objects if is_insert(o)]


class SceneError(Exception):
    """Something the user must fix in the scene; the message says what."""


@dataclass
class Model:
    vertices: np.ndarray        # (V, 3) float32, world frame
    triangles: np.ndarray       # (T, 3) int32
    object_ids: np.ndarray      # (T,) int32, index into names
    names: List[str]            # object name per id

    @property
    def num_triangles(self) -> int:
        return int(self.triangles.shape[0])

    def bounds(self):
        return self.vertices.min(axis=0), self.vertices.max(axis=0)

    def ids_of(self, names: Sequence[str]) -> List[int]:
        return [i for i, n in enumerate(self.names) if n in set(names)]


@dataclass
class CameraInfo:
    name: str
    params: dict                 # keyword arguments of _native.Camera.from_blender
    distortion: Optional[dict] = None   # keyword arguments of set_distortion
    warnings: List[str] = field(default_factory=list)


@dataclass
class ClipInfo:
    name: str
    filepath: str                # absolute
    source: str                  # 'MOVIE' or 'SEQUENCE'
    frame_start: int             # scene frame of the clip's first frame
    frame_duration: int
    width: int
    height: int
    # What the file itself held when probed (native VideoReader), and what
    # the user should hear about it (a shorter file than Blender's cache).
    frames_in_file: Optional[int] = None
    warnings: List[str] = field(default_factory=list)

    @property
    def frame_end(self) -> int:
        return self.frame_start + self.frame_duration - 1


# --------------------------------------------------------------------------
# Model

def _mesh_arrays(obj_eval, matrix_world):
    """World-space vertices and loop triangles of one evaluated object."""
    mesh = obj_eval.to_mesh()
    try:
        mesh.calc_loop_triangles()
        nv, nt = len(mesh.vertices), len(mesh.loop_triangles)
        if nv == 0 or nt == 0:
            return None
        co = np.empty(nv * 3, dtype=np.float32)
        mesh.vertices.foreach_get("co", co)
        tri = np.empty(nt * 3, dtype=np.int32)
        mesh.loop_triangles.foreach_get("vertices", tri)
    finally:
        obj_eval.to_mesh_clear()
    m = np.array(matrix_world, dtype=np.float64)
    world = co.reshape(-1, 3).astype(np.float64) @ m[:3, :3].T + m[:3, 3]
    return world.astype(np.float32), tri.reshape(-1, 3)


def gather_model(context, collection: Optional[bpy.types.Collection] = None,
                 exclude: Sequence[str] = ()) -> Model:
    """Triangles of the evaluated meshes of `collection` (and its children),
    or of every visible mesh in the view layer when `collection` is None.

    Modifiers, geometry nodes and collection instances are honoured (the
    depsgraph's object instances). Raises SceneError when nothing is found.
    """
    depsgraph = context.evaluated_depsgraph_get()
    view_layer = context.view_layer
    members = None
    if collection is not None:
        members = {o.name for o in collection.all_objects}
    exclude = set(exclude)

    verts, tris, ids, names = [], [], [], []
    offset = 0
    for inst in depsgraph.object_instances:
        obj = inst.object
        if obj.type != "MESH":
            continue
        original = obj.original
        parent = inst.parent.original if inst.is_instance and inst.parent else None
        owner = parent if parent is not None else original
        if owner.name in exclude or original.name in exclude:
            continue
        if members is not None:
            if owner.name not in members and original.name not in members:
                continue
        elif not owner.visible_get(view_layer=view_layer):
            continue
        arrays = _mesh_arrays(obj, inst.matrix_world)
        if arrays is None:
            continue
        world, tri = arrays
        name = original.name if parent is None else f"{parent.name}/{original.name}"
        # Blender clamps an infinite transform to 3.4e38, finite but no place.
        usable = np.all(np.isfinite(world) & (np.abs(world) < 1e9), axis=1)
        if not np.all(usable):
            # Embree and the estimators cannot use such a vertex; say where it is.
            bad = int(np.count_nonzero(~usable))
            raise SceneError(f"Object '{name}' has {bad} vertex/vertices with a NaN, "
                             "infinite or absurd (beyond 1e9 m) coordinate, or an object "
                             "transform that makes one: "
                             "fix or delete them (Mesh › Clean Up), or leave the object out "
                             "of the model collection.")
        ids.append(np.full(len(tri), len(names), dtype=np.int32))
        names.append(name)
        verts.append(world)
        tris.append(tri + offset)
        offset += len(world)

    where = f"collection '{collection.name}'" if collection else "the visible scene"
    if not tris:
        raise SceneError(f"The model is empty: no mesh with faces in {where}. "
                         "Model the scene (ground and main objects) as meshes.")
    return Model(vertices=np.ascontiguousarray(np.concatenate(verts)),
                 triangles=np.ascontiguousarray(np.concatenate(tris)),
                 object_ids=np.ascontiguousarray(np.concatenate(ids)),
                 names=names)


def _triangle_areas(model: Model):
    """Per triangle: area, whether it is horizontal (normal within 18 deg of
    vertical, whichever way it is wound) and mean height; None for no
    triangles or a non-finite vertex."""
    v = model.vertices.astype(np.float64)
    t = model.triangles
    if len(t) == 0 or not np.all(np.isfinite(v)):
        return None
    a, b, c = v[t[:, 0]], v[t[:, 1]], v[t[:, 2]]
    cross = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(cross, axis=1)
    flat = np.abs(cross[:, 2]) / np.maximum(2 * area, 1e-12) > 0.95
    return area, flat, (a[:, 2] + b[:, 2] + c[:, 2]) / 3.0


def guess_ground(model: Model, camera=None) -> List[str]:
    """The ground the shadows fall on (overridable by the user): the lowest
    large horizontal surface, below the camera when it is given (a
    CameraInfo, or its position in the world frame), since a camera sees a
    surface's upper face only from above.

    Horizontal means the triangle's normal is within 18 deg of vertical,
    whichever way it is wound: a thin slab's two faces count once each, so
    height, not which face points up, must tell a floor from a ceiling (a
    room with floor, walls and ceiling gets the floor). Candidates must have
    at least a quarter of the largest horizontal area (a step or a kerb
    below the ground does not win), the lowest of them by area-weighted
    height is chosen, and other mostly-flat objects about as low and at
    least half as large (tiles, lawns) are kept with it."""
    triangles = _triangle_areas(model)
    if triangles is None:
        return []
    area, flat, height = triangles
    v = model.vertices.astype(np.float64)
    if isinstance(camera, CameraInfo):
        camera = np.asarray(camera.params["matrix_world"], dtype=np.float64)[:3, 3]
    if camera is not None and np.all(np.isfinite(camera)):
        flat &= height < float(camera[2])
    n = len(model.names)
    up_area = np.bincount(model.object_ids, weights=area * flat, minlength=n)
    total = np.bincount(model.object_ids, weights=area, minlength=n)
    if up_area.max() <= 0:
        return []
    level = np.bincount(model.object_ids, weights=area * flat * height, minlength=n) / \
        np.maximum(up_area, 1e-12)
    candidates = [i for i in range(n) if up_area[i] >= 0.25 * up_area.max()]
    best = min(candidates, key=lambda i: (level[i], -up_area[i]))
    # Extent of the model, for "about as low" (10 cm, or 1% of its height).
    tolerance = max(0.1, 0.01 * float(np.ptp(v[:, 2])))
    keep = [i for i in range(n)
            if i == best or (up_area[i] >= 0.5 * up_area[best] and up_area[i] >= 0.8 * total[i]
                             and abs(level[i] - level[best]) <= tolerance)]
    return [model.names[i] for i in keep]


def ground_doubts(model: Model, names: Sequence[str]) -> List[str]:
    """Warnings, one per ground object that cannot be much of a ground: most
    of its surface is not horizontal (a box's or a bollard's top taken for
    the ground, when the real ground is not modelled)."""
    triangles = _triangle_areas(model)
    if triangles is None:
        return []
    area, flat, _ = triangles
    n = len(model.names)
    flat_area = np.bincount(model.object_ids, weights=area * flat, minlength=n)
    total = np.maximum(np.bincount(model.object_ids, weights=area, minlength=n), 1e-12)
    out = []
    for name in names:
        if name not in model.names:
            continue
        share = flat_area[model.names.index(name)] / total[model.names.index(name)]
        if share < GROUND_MIN_FLAT_SHARE:
            out.append(f"'{name}' is taken for the ground, but only {100 * share:.0f}% of it is "
                       f"horizontal (the top of an object?): model the surface the shadows fall "
                       f"on (a plane under the objects) and pick it as Ground")
    return out


# A ground is mostly horizontal: a box's top and bottom are a third of it.
GROUND_MIN_FLAT_SHARE = 0.6


# --------------------------------------------------------------------------
# Camera

def _render_size(scene):
    r = scene.render
    pct = r.resolution_percentage / 100.0
    return max(1, int(r.resolution_x * pct)), max(1, int(r.resolution_y * pct))


def gather_camera(context, camera_obj=None, clip: Optional[ClipInfo] = None,
                  movieclip=None) -> CameraInfo:
    """Blender's camera as native parameters, sized to the clip's frames.

    The image size is the clip's when a clip is given (the estimator works on
    its frames); the render resolution must then have the same aspect, since
    Blender's view frame follows the render settings.
    """
    scene = context.scene
    obj = camera_obj or scene.camera
    if obj is None:
        raise SceneError("The scene has no camera: add one matched to the "
                         "footage (Scene Properties › Camera).")
    if obj.type != "CAMERA":
        raise SceneError(f"'{obj.name}' is not a camera object.")
    cam = obj.data
    if cam.type != "PERSP":
        raise SceneError(f"Camera '{obj.name}' is {cam.type}; only perspective "
                         "cameras are supported.")
    # The clip's own warnings travel with the camera's: both are shown
    # before a run (Check Scene, Estimate Sun, the scripted run).
    warnings = list(clip.warnings) if clip is not None else []
    rw, rh = _render_size(scene)
    width, height = rw, rh
    if clip is not None:
        render_aspect = rw * scene.render.pixel_aspect_x / (rh * scene.render.pixel_aspect_y)
        clip_aspect = (clip.width * scene.render.pixel_aspect_x
                       / (clip.height * scene.render.pixel_aspect_y))
        if abs(render_aspect / clip_aspect - 1.0) > 0.01:
            raise SceneError(
                f"Render resolution {rw}x{rh} does not have the clip's aspect "
                f"({clip.width}x{clip.height}): set Output Properties › "
                "Resolution to the clip's size, as the camera was matched to it.")
        width, height = clip.width, clip.height
    depsgraph = context.evaluated_depsgraph_get()
    matrix = np.array(obj.evaluated_get(depsgraph).matrix_world, dtype=np.float64)
    params = dict(
        lens_mm=float(cam.lens), sensor_width_mm=float(cam.sensor_width),
        sensor_height_mm=float(cam.sensor_height), sensor_fit=cam.sensor_fit,
        shift_x=float(cam.shift_x), shift_y=float(cam.shift_y),
        width=int(width), height=int(height),
        pixel_aspect_x=float(scene.render.pixel_aspect_x),
        pixel_aspect_y=float(scene.render.pixel_aspect_y),
        matrix_world=matrix)
    distortion = None
    if movieclip is not None:
        distortion = _clip_distortion(movieclip, warnings)
    return CameraInfo(name=obj.name, params=params, distortion=distortion,
                      warnings=warnings)


# A camera moving more than this over the frames is a moving camera (a
# camera solve's jitter is a few mm and hundredths of a degree); sampled on
# at most CAMERA_MOTION_SAMPLES frames.
CAMERA_MOVE_M = 0.02
CAMERA_TURN_DEG = 0.2
CAMERA_LENS_SHARE = 0.005
CAMERA_MOTION_SAMPLES = 24


# Blender's camera solve is trusted below this average reprojection error
# (pixels): its manual calls under 0.3 px good, and past a pixel the
# tracks or the lens settings are wrong.
SOLVE_ERROR_PX = 1.0


def camera_solve(context, obj) -> Optional[Tuple[str, bool]]:
    """How the camera's Camera Solver constraint is solved, in words, and
    whether that is a doubt (no solve, or its error over SOLVE_ERROR_PX);
    None without such a constraint."""
    if obj is None:
        return None
    con = next((c for c in obj.constraints if c.type == "CAMERA_SOLVER"), None)
    if con is None:
        return None
    clip = context.scene.active_clip if con.use_active_clip else con.clip
    if clip is None:
        return (f"the camera '{obj.name}' has a Camera Solver constraint with no clip: "
                f"pick the clip it was solved on", True)
    rec = clip.tracking.reconstruction   # the camera's (objects have their own)
    if not rec.is_valid:
        return (f"the camera '{obj.name}' follows clip '{clip.name}', which has no camera "
                f"solve yet: Solve Camera Motion in the Movie Clip Editor", True)
    error = float(rec.average_error)
    words = (f"camera solved by Blender's tracker on clip '{clip.name}': {len(rec.cameras)} "
             f"frame(s), average error {error:.2f} px")
    if error > SOLVE_ERROR_PX:
        return (words + f" (over {SOLVE_ERROR_PX:g} px: check the tracks and the lens)", True)
    return words, False


def driven(obj) -> bool:
    """Whether anything could move the camera: keys, drivers or constraints
    on it or a parent, or keys on its lens."""
    while obj is not None:
        if obj.animation_data is not None or len(obj.constraints) > 0:
            return True
        obj = obj.parent
    return False


def camera_motion(context, obj, frames) -> Optional[str]:
    """How far the camera moves over the frames (first, last), in words, or
    None when it stays put: evaluated (keys, constraints, parents, a
    camera solve) on frames spread over them; the current frame is put back."""
    if obj is None or obj.type != "CAMERA" or not (
            driven(obj) or obj.data.animation_data is not None):
        return None
    scene = context.scene
    now = scene.frame_current
    lo, hi = frames
    count = min(CAMERA_MOTION_SAMPLES, hi - lo + 1)
    sampled = sorted({lo + round(i * (hi - lo) / max(1, count - 1)) for i in range(count)})
    poses = []
    try:
        for f in sampled:
            scene.frame_set(f)
            depsgraph = context.evaluated_depsgraph_get()
            m = np.array(obj.evaluated_get(depsgraph).matrix_world, dtype=np.float64)
            poses.append((f, m[:3, 3].copy(), m[:3, :3] / np.linalg.norm(m[:3, :3], axis=0),
                          float(obj.data.lens)))
    finally:
        scene.frame_set(now)
    f0, t0, r0, lens0 = poses[0]
    move = max(float(np.linalg.norm(t - t0)) for _, t, _, _ in poses)
    turn = max(float(np.degrees(np.arccos(np.clip((np.trace(r0.T @ r) - 1.0) / 2.0, -1, 1))))
               for _, _, r, _ in poses)
    zoom = max(abs(lens / lens0 - 1.0) for _, _, _, lens in poses)
    if move <= CAMERA_MOVE_M and turn <= CAMERA_TURN_DEG and zoom <= CAMERA_LENS_SHARE:
        return None
    return (f"up to {move:.2f} m and {turn:.1f} deg from frame {f0}"
            + (f", its lens by {100 * zoom:.1f}%" if zoom > CAMERA_LENS_SHARE else ""))


def _solved_frames(context, obj) -> Optional[set]:
    """The scene frames the camera's Camera Solver constraint has a
    reconstructed camera for, or None when nothing says (no constraint, or
    no solve: camera_solve reports that)."""
    con = next((c for c in obj.constraints if c.type == "CAMERA_SOLVER"), None)
    if con is None:
        return None
    clip = context.scene.active_clip if con.use_active_clip else con.clip
    if clip is None or not clip.tracking.reconstruction.is_valid:
        return None
    # Tracking counts the clip's own frames from 1 (with its offset).
    shift = clip.frame_start - 1 - clip.frame_offset
    return {int(c.frame) + shift for c in clip.tracking.reconstruction.cameras}


def camera_path(context, obj, info: CameraInfo, frames: Sequence[int]
                ) -> Dict[int, Optional[CameraInfo]]:
    """The camera on each of `frames` (scene frames), evaluated through the
    depsgraph (keys, constraints, parents, a camera solve; lens, shift and
    sensor too): `info` with that frame's matrix and lens. None on a frame
    the camera's solve has no reconstructed camera for (the constraint
    would hold a guess there). The current frame is put back."""
    scene = context.scene
    now = scene.frame_current
    solved = _solved_frames(context, obj)
    out: Dict[int, Optional[CameraInfo]] = {}
    try:
        for f in frames:
            if solved is not None and f not in solved:
                out[f] = None
                continue
            scene.frame_set(f)
            depsgraph = context.evaluated_depsgraph_get()
            cam = obj.data
            params = dict(info.params,
                          matrix_world=np.array(obj.evaluated_get(depsgraph).matrix_world,
                                                dtype=np.float64),
                          lens_mm=float(cam.lens), sensor_width_mm=float(cam.sensor_width),
                          sensor_height_mm=float(cam.sensor_height),
                          shift_x=float(cam.shift_x), shift_y=float(cam.shift_y))
            out[f] = CameraInfo(name=info.name, params=params, distortion=info.distortion)
    finally:
        scene.frame_set(now)
    return out


def _clip_distortion(movieclip, warnings) -> Optional[dict]:
    """The clip's tracking-camera lens distortion, when the user set one."""
    tc = movieclip.tracking.camera
    model = getattr(tc, "distortion_model", "POLYNOMIAL")
    if model != "POLYNOMIAL":
        warnings.append(f"Lens distortion model {model} is not supported yet; "
                        "frames are used as recorded.")
        return None
    k = (float(tc.k1), float(tc.k2), float(tc.k3))
    if not any(k):
        return None
    w, h = movieclip.size
    # Blender 3.x: principal (pixels from the bottom-left corner);
    # 3.5+: principal_point_pixels. Convert to OpenCV pixel centres.
    if hasattr(tc, "principal_point_pixels"):
        px, py = tc.principal_point_pixels
    else:
        px, py = tc.principal
    focal = float(tc.focal_length_pixels)
    aspect = float(getattr(tc, "pixel_aspect", 1.0)) or 1.0
    return dict(focal_x_px=focal, focal_y_px=focal * aspect,
                principal_x_px=float(px) - 0.5,
                principal_y_px=float(h) - float(py) - 0.5,
                k1=k[0], k2=k[1], k3=k[2])


def build_camera(info: CameraInfo):
    native = native_loader.require()
    cam = native.Camera.from_blender(**info.params)
    if info.distortion:
        cam.set_distortion(**info.distortion)
    return cam


def scene_north_offset_deg(context) -> float:
    """North offset of Blender's Sun Position add-on when it is enabled
    (world azimuth = azimuth + north offset, docs/design.md §4), else 0."""
    props = getattr(context.scene, "sun_pos_properties", None)
    if props is None:
        return 0.0
    import math
    return math.degrees(float(getattr(props, "north_offset", 0.0)))


# --------------------------------------------------------------------------
# Clip

def active_movieclip(context):
    """The clip being edited, else the scene's active clip, else the only one."""
    space = getattr(context, "space_data", None)
    clip = getattr(space, "clip", None) if space is not None else None
    if clip is None:
        clip = context.scene.active_clip
    if clip is None and len(bpy.data.movieclips) == 1:
        clip = bpy.data.movieclips[0]
    return clip


def gather_clip(context, movieclip=None) -> ClipInfo:
    clip = movieclip or active_movieclip(context)
    if clip is None:
        raise SceneError("No clip: open the footage in the Movie Clip Editor "
                         "(or set Scene Properties › Active Clip).")
    path = bpy.path.abspath(clip.filepath, library=clip.library)
    path = os.path.normpath(path)
    if not os.path.exists(path):
        raise SceneError(f"Clip '{clip.name}' not found on disk: {path}")
    w, h = clip.size
    if w <= 0 or h <= 0:
        raise SceneError(f"Clip '{clip.name}' cannot be read (size {w}x{h}): "
                         "the file may be corrupt or of an unsupported format.")
    info = ClipInfo(name=clip.name, filepath=path, source=clip.source,
                    frame_start=int(clip.frame_start),
                    frame_duration=int(clip.frame_duration),
                    width=int(w), height=int(h))
    probe_clip(info)
    return info


def sequence_gaps(first_path: str, limit: int = 100000) -> List[str]:
    """Files missing inside a numbered image sequence (frame_0001.png ...):
    names between the first file and the highest-numbered one present (the
    native reader's own reading of the names)."""
    sequence = native_loader.require().find_image_sequence(first_path)
    if sequence is None:
        return []
    paths = (sequence.path(k) for k in range(min(sequence.num_frames, limit)))
    return [os.path.basename(p) for p in paths if not os.path.exists(p)]


def probe_clip(info: ClipInfo) -> None:
    """Checks what the clip's file really holds (the native VideoReader, not
    Blender's cached length and size, which survive the file being replaced)
    and corrects `info` or raises SceneError:

    - a file that cannot be opened, or whose frames are of another size than
      Blender's clip (the camera was matched to that size): an error;
    - a file with fewer frames than Blender's clip says (a 1-frame file in
      place of a 120-frame one, or an image sequence missing a file): the
      clip is cut to what the file holds, with a warning, so no frame gets a
      Sun invented from frames that do not exist.

    Skipped when the native core is missing (the run itself then says so)."""
    try:
        native = native_loader.require()
    except RuntimeError:
        return
    try:
        reader = native.VideoReader(info.filepath)
    except (ValueError, RuntimeError) as e:
        raise SceneError(f"Clip '{info.name}' cannot be read from {info.filepath}: {e}")
    if (reader.width, reader.height) != (info.width, info.height):
        raise SceneError(
            f"Clip '{info.name}': the file's frames are {reader.width}x{reader.height} but "
            f"Blender's clip says {info.width}x{info.height} (the file was replaced?): "
            "reload the clip (Movie Clip Editor › Clip › Reload) and check the camera match.")
    count = int(reader.num_frames)
    info.frames_in_file = count if count > 0 else None
    gaps = sequence_gaps(info.filepath) if info.source == "SEQUENCE" else []
    if gaps:
        shown = ", ".join(gaps[:3]) + (" ..." if len(gaps) > 3 else "")
        info.warnings.append(
            f"Clip '{info.name}': the image sequence misses {len(gaps)} file(s) ({shown}); "
            f"those frames get no estimate")
    if 0 < count < info.frame_duration:
        info.warnings.append(
            f"Clip '{info.name}': the file holds {count} frame(s) but Blender's clip says "
            f"{info.frame_duration}; only frames {info.frame_start}-"
            f"{info.frame_start + count - 1} are estimated (reload the clip if the file "
            f"was replaced)")
        info.frame_duration = count


# --------------------------------------------------------------------------
# Native scene

def build_scene(model: Model):
    """The Embree scene of the model (the BVH build releases the GIL)."""
    native = native_loader.require()
    return native.Scene(model.vertices, model.triangles, model.object_ids)


# Camera rays cast to see what the camera sees of the model (a grid).
VIEW_GRID = (64, 36)


def objects_in_view(scene, camera, info: CameraInfo) -> Dict[int, float]:
    """The share of a grid of VIEW_GRID camera rays that hits each object,
    by id (empty: the camera sees none of the model)."""
    w, h = info.params["width"], info.params["height"]
    gx, gy = VIEW_GRID
    xs, ys = np.meshgrid((np.arange(gx) + 0.5) * w / gx - 0.5,
                         (np.arange(gy) + 0.5) * h / gy - 0.5)
    px = np.ascontiguousarray(np.stack([xs.ravel(), ys.ravel()], axis=1), dtype=np.float64)
    hits = scene.intersect_pixels(camera, px)
    ids = np.asarray(hits["object_id"])[np.asarray(hits["hit"], dtype=bool)]
    found, counts = np.unique(ids, return_counts=True)
    return {int(i): float(c) / len(px) for i, c in zip(found, counts)}


def marked_points(clip, frame):
    """(name, ground xyz, OpenCV pixel) of every track with a marker on
    `frame` whose name ends with its ground coordinates ("foot 0 0",
    "3.2,-1.5", "x y z"); tracks without numbers are listed apart."""
    import re

    def numbers(name):  # whole tokens only: "p0 1 2" is the point (1, 2)
        out = []
        for token in re.split(r"[\s,;]+", name):
            try:
                out.append(float(token))
            except ValueError:
                pass
        return out
    w, h = clip.size
    points, skipped = [], []
    for track in clip.tracking.tracks:
        marker = track.markers.find_frame(frame)
        nums = numbers(track.name)
        if marker is None or marker.mute:
            continue
        if len(nums) < 2:
            skipped.append(track.name)
            continue
        xyz = (nums[-3], nums[-2], nums[-1]) if len(nums) >= 3 else (nums[-2], nums[-1], 0.0)
        # Marker positions are 0..1 from the frame's bottom-left corner.
        px = (marker.co[0] * w - 0.5, (1.0 - marker.co[1]) * h - 0.5)
        points.append((track.name, xyz, px))
    return points, skipped
