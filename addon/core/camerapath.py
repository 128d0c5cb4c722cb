"""A moving camera's poses over a clip, as a solve delivers them: the frames
where the solve jumps off its own path (bpy-free).

A camera solve jitters by millimetres and hundredths of a degree; a bad one
jumps off its path on a few frames. A motion-control move is smooth: over
a few frames its position and its turn follow a cubic in time (an eased
start or stop is one). Each frame's pose is compared with the cubic that
the JUMP_WINDOW frames either side of it follow, found robustly, so that a
jump of up to three frames stands out on each of them. A frame
further off than JUMP_M or JUMP_DEG, and than JUMP_SPREAD times the clip's
own spread, is off the path. (A consensus over sets of four neighbours,
as RANSAC's, since a least-squares cubic bends toward the jumped ones.)
"""

from __future__ import annotations

from functools import lru_cache
from itertools import combinations
from typing import Dict, Sequence, Tuple

import numpy as np

JUMP_WINDOW = 4
# About a pixel's worth at the working size on a scene tens of metres away.
JUMP_M = 0.05
JUMP_DEG = 0.3
JUMP_SPREAD = 8.0
# Neighbours within this share of the floor lie on a cubic (a solve's
# jitter is a tenth of it).
CONSENSUS_SHARE = 0.3


def rotation_vector_deg(rotation: np.ndarray) -> np.ndarray:
    """The axis times the angle (deg) of a 3x3 rotation."""
    cos = np.clip((np.trace(rotation) - 1.0) / 2.0, -1.0, 1.0)
    angle = np.arccos(cos)
    skew = np.array([rotation[2, 1] - rotation[1, 2], rotation[0, 2] - rotation[2, 0],
                     rotation[1, 0] - rotation[0, 1]])
    if angle < 1e-9:
        return np.degrees(skew / 2.0)
    return np.degrees(angle * skew / (2.0 * np.sin(angle)))


@lru_cache(maxsize=64)
def _cubics(offsets: Tuple[int, ...]) -> np.ndarray:
    """For neighbours at these frame offsets: per set of 4 of them, the
    weights that give the cubic through those 4 at every neighbour and at
    offset 0 (the frame itself), (sets, neighbours + 1, neighbours)."""
    t = np.array(offsets, dtype=np.float64)
    at = np.vander(np.append(t, 0.0), 4)
    sets = list(combinations(range(len(t)), 4))
    weights = np.zeros((len(sets), len(t) + 1, len(t)))
    for i, four in enumerate(sets):
        weights[i][:, list(four)] = at @ np.linalg.inv(np.vander(t[list(four)], 4))
    return weights


def _off_path(values: np.ndarray, floor: float) -> np.ndarray:
    """How far each row (a frame) is from the cubic through its neighbours:
    the cubic through 4 of them that most of the others lie on (within
    CONSENSUS_SHARE of `floor`), refitted on those, so that up to half of
    them may be off."""
    n, w = len(values), JUMP_WINDOW
    off = np.zeros(n)
    for k in range(n):
        lo = min(max(0, k - w), max(0, n - 2 * w - 1))
        near = [j for j in range(lo, min(n, lo + 2 * w + 1)) if j != k]
        weights = _cubics(tuple(j - k for j in near))
        v = values[near]
        apart = np.linalg.norm(np.einsum("smn,nd->smd", weights[:, :-1], v) - v, axis=2)
        on = apart <= CONSENSUS_SHARE * floor
        best = int(np.argmax(on.sum(axis=1) - 1e-6 * np.where(on, apart, 0).sum(axis=1)))
        keep = [j for j, ok in zip(near, on[best]) if ok]
        coef = np.polyfit(np.array(keep, dtype=np.float64) - k, values[keep], 3)
        off[k] = float(np.linalg.norm(values[k] - coef[-1]))
    return off


def solve_jumps(frames: Sequence[int], locations: np.ndarray,
                rotations: np.ndarray) -> Dict[int, str]:
    """{frame: why its pose is not believed} for the frames a solve jumped
    off its path on. locations (n, 3) m and rotations (n, 3, 3), world from
    camera, in frame order."""
    n = len(frames)
    if n < 2 * JUMP_WINDOW + 1:
        return {}
    locations = np.asarray(locations, dtype=np.float64)
    rotations = np.asarray(rotations, dtype=np.float64)
    middle = rotations[n // 2]
    turned = np.array([rotation_vector_deg(middle.T @ r) for r in rotations])
    off: Dict[int, str] = {}
    for values, floor, unit in ((locations, JUMP_M, "m"), (turned, JUMP_DEG, "deg")):
        apart = _off_path(values, floor)
        limit = max(floor, JUMP_SPREAD * float(np.median(apart)))
        for f, d in zip(frames, apart):
            if d > limit:
                off.setdefault(f, f"the camera solve jumps off its path here ({d:.2f} {unit} "
                                  f"from its neighbours')")
    return off
