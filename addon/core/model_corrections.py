"""The model's corrections a run refined by the clip (--refine-model), read
from a track, and what applying them does to an object's and the camera's
world matrices (bpy-free; blender/model_fix.py applies them)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import List, Optional, Sequence

import numpy as np

from .trackfile import Track


@dataclass
class ObjectCorrection:
    name: str                 # the model object's name (method.options.model_objects)
    transform: np.ndarray     # 4x4 world transform p -> p'


@dataclass
class Corrections:
    objects: List[ObjectCorrection] = field(default_factory=list)
    camera_name: Optional[str] = None
    camera_turn_in_world: np.ndarray = field(default_factory=lambda: np.eye(3))
    camera_turn_deg: float = 0.0
    focal_factor: float = 1.0
    applied: bool = False     # already applied to this .blend (a second time would double them)


def corrections_of(track: Track) -> Optional[Corrections]:
    """The corrections the estimate used, or None when the run did not
    refine the model or did not use the refinement."""
    r = track.extra.get("model_refinement")
    if not isinstance(r, dict) or not r.get("used"):
        return None
    # The run's record of its scene (blender/job.py) is kept in the method's
    # options.
    record = track.method.get("options") or {}
    names: Sequence[str] = record.get("model_objects") or []
    out = Corrections(camera_name=record.get("camera"), applied=bool(r.get("applied")))
    cam = r.get("camera") or {}
    out.camera_turn_in_world = np.asarray(cam.get("turn_in_world", np.eye(3)), dtype=float)
    out.camera_turn_deg = float(cam.get("turn_deg", 0.0))
    out.focal_factor = float(cam.get("focal_factor", 1.0))
    for o in r.get("objects", []):
        i = int(o.get("object_id", -1))
        if not o.get("refined") or not 0 <= i < len(names):
            continue
        out.objects.append(ObjectCorrection(
            name=names[i], transform=np.asarray(o["transform"], dtype=float)))
    return out


def corrected_object_matrix(transform: np.ndarray, matrix_world: np.ndarray) -> np.ndarray:
    """An object's matrix_world with its correction applied (the correction
    is a world transform: it left-multiplies)."""
    return np.asarray(transform, dtype=float) @ np.asarray(matrix_world, dtype=float)


def corrected_camera_matrix(turn_in_world: np.ndarray, matrix_world: np.ndarray) -> np.ndarray:
    """The camera's matrix_world turned about its own centre."""
    m = np.asarray(matrix_world, dtype=float).copy()
    m[:3, :3] = np.asarray(turn_in_world, dtype=float) @ m[:3, :3]
    return m
