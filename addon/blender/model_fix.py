"""The model's corrections (--refine-model) applied to the .blend's objects
and camera, once, on the user's request (the Apply Model Corrections
operator, run_estimate.py --apply-model-corrections). Objects whose
transform something else drives (keys, drivers, constraints) or that are
parts of an instance are left alone and named."""

from typing import List, Tuple

import bpy
import numpy as np
from mathutils import Matrix

from ..core import model_corrections
from ..core.trackfile import Track
from . import gather, store


def apply_corrections(context, track: Track) -> Tuple[str, List[str]]:
    """Applies the stored track's corrections to the objects and camera.
    Returns (what was done, in a sentence; what was skipped, one entry
    each). Raises ValueError when the track has none to apply, or they were
    applied already."""
    c = model_corrections.corrections_of(track)
    if c is None and "model_refinement" in track.extra:
        raise ValueError("The clip left the model as it was (the estimate used it as "
                         "modelled): there are no model corrections to apply")
    if c is None:
        raise ValueError("The track holds no model corrections: run the estimate with "
                         "Refine Model on (--refine-model); corrections are kept only where "
                         "the clip showed the model clearly off")
    if c.applied:
        raise ValueError("The model corrections were applied already; applying them again "
                         "would move the model twice (Edit > Undo takes them back)")
    skipped: List[str] = []
    moved = 0
    for o in c.objects:
        obj = bpy.data.objects.get(o.name)
        if obj is None:
            skipped.append(f"'{o.name}': not an object of this file (a part of an "
                           f"instance, or renamed)")
            continue
        if gather.driven(obj):
            skipped.append(f"'{o.name}': keys, drivers or constraints drive its transform")
            continue
        m = np.array(obj.matrix_world, dtype=float)
        obj.matrix_world = Matrix(model_corrections.corrected_object_matrix(
            o.transform, m).tolist())
        moved += 1
    cam = bpy.data.objects.get(c.camera_name) if c.camera_name else context.scene.camera
    camera_done = False
    if cam is None or cam.type != "CAMERA":
        skipped.append("the camera: not found in this file")
    elif gather.driven(cam) or cam.data.animation_data is not None:
        skipped.append(f"the camera '{cam.name}': keys, drivers or constraints drive it")
    else:
        m = np.array(cam.matrix_world, dtype=float)
        cam.matrix_world = Matrix(model_corrections.corrected_camera_matrix(
            c.camera_turn_in_world, m).tolist())
        cam.data.lens *= c.focal_factor
        camera_done = True
    # Kept in the track, so that a second click does not move them again.
    track.extra["model_refinement"]["applied"] = True
    store.store_track(track)
    said = (f"Applied the clip's corrections to {moved} object(s)"
            + (f" and the camera (turned {c.camera_turn_deg:.2f}°, focal length "
               f"x{c.focal_factor:.3f})" if camera_done else ""))
    return said, skipped
