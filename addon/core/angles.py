"""The Sun's angles and its direction, one helper for the Python side
(native/include/sunlapse/common/angles.h is the C++ one; docs/design.md §4).

World frame: Blender's, +X east, +Y north (of the scene), +Z up. Zenith from
+Z toward the Sun; azimuth clockwise from +Y toward +X; degrees. A geographic
azimuth is measured from true north; a scene whose +Y is turned from north by
north_offset (Blender's Sun Position add-on) has
azimuth_world = azimuth_geographic + north_offset.

Every function takes scalars or numpy arrays (vectors along the last axis).
"""

from __future__ import annotations

import math
from typing import Any, Tuple

import numpy as np

# A null vector reads as (90, 0), never NaN (smoothing's degenerate fits).
_TINY = float(np.finfo(float).tiny)


def wrap_azimuth_deg(azimuth_deg: Any) -> Any:
    """An angle wrapped to [0, 360); a float for one angle (in plain floats:
    it runs per Sun)."""
    # -1e-15 mod 360 rounds to 360.0, which is 0.
    if not np.ndim(azimuth_deg):
        one = float(azimuth_deg) % 360.0
        return 0.0 if one >= 360.0 else one
    a = np.mod(azimuth_deg, 360.0)
    return np.where(a >= 360.0, 0.0, a)


def wrap_signed_deg(angle_deg: Any) -> Any:
    """An angle wrapped to [-180, 180): the shorter way round."""
    return (np.asarray(angle_deg) + 180.0) % 360.0 - 180.0 if np.ndim(angle_deg) else \
        (float(angle_deg) + 180.0) % 360.0 - 180.0


def azimuth_difference_deg(a: float, b: float) -> float:
    """|a - b| wrapped to [0, 180]: how far apart two azimuths are."""
    return abs(float(wrap_signed_deg(a - b)))


def sun_in_world_from_angles(zenith_deg: Any, azimuth_world_deg: Any) -> np.ndarray:
    """Unit vector toward the Sun, (sin z sin a, sin z cos a, cos z); shape
    (..., 3) for array inputs."""
    z, a = np.radians(zenith_deg), np.radians(azimuth_world_deg)
    return np.stack(np.broadcast_arrays(np.sin(z) * np.sin(a), np.sin(z) * np.cos(a),
                                        np.cos(z)), axis=-1)


def angles_from_sun_in_world(sun_in_world: Any) -> Tuple[Any, Any]:
    """(zenith_deg in [0, 180], azimuth_world_deg in [0, 360)) of vectors of
    any non-zero length; floats for one vector, arrays for (..., 3)."""
    v = np.asarray(sun_in_world, dtype=float)
    # One vector in plain floats: it runs per frame and per Sun, where
    # numpy's per-call cost was most of it (57 us against 2.4).
    if v.shape == (3,):
        x, y, z = float(v[0]), float(v[1]), float(v[2])
        one = max(math.sqrt(x * x + y * y + z * z), _TINY)
        return (math.degrees(math.acos(min(1.0, max(-1.0, z / one)))),
                wrap_azimuth_deg(math.degrees(math.atan2(x, y))))
    norm = np.maximum(np.linalg.norm(v, axis=-1), _TINY)
    zenith = np.degrees(np.arccos(np.clip(v[..., 2] / norm, -1.0, 1.0)))
    azimuth = wrap_azimuth_deg(np.degrees(np.arctan2(v[..., 0], v[..., 1])))
    if v.ndim == 1:
        return float(zenith), float(azimuth)
    return zenith, azimuth


def azimuth_world_from_geographic(azimuth_geographic_deg: Any, north_offset_deg: Any) -> Any:
    """A geographic azimuth in a scene whose +Y is turned from north by
    north_offset_deg; [0, 360)."""
    return wrap_azimuth_deg(np.add(azimuth_geographic_deg, north_offset_deg))


def azimuth_geographic_from_world(azimuth_world_deg: Any, north_offset_deg: Any) -> Any:
    """Inverse of azimuth_world_from_geographic; [0, 360)."""
    return wrap_azimuth_deg(np.subtract(azimuth_world_deg, north_offset_deg))


def sun_in_world_from_geographic(zenith_deg: Any, azimuth_geographic_deg: Any,
                                 north_offset_deg: Any) -> np.ndarray:
    """Unit vector toward a Sun given as a track file gives it (geographic
    azimuth and the scene's north offset)."""
    return sun_in_world_from_angles(
        zenith_deg, azimuth_world_from_geographic(azimuth_geographic_deg, north_offset_deg))


def cross(u: Any, v: Any) -> np.ndarray:
    """u x v of two 3-vectors: numpy's cross to the bit (each product
    rounded, then the difference), without its per-call cost (60 us; the
    Sun circle's fits call it thousands of times a run)."""
    ux, uy, uz = float(u[0]), float(u[1]), float(u[2])
    vx, vy, vz = float(v[0]), float(v[1]), float(v[2])
    return np.array([uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx])


def angle_between_deg(u: Any, v: Any) -> float:
    """Angle between two 3-vectors of any non-zero length. atan2(|u x v|, u.v)
    stays exact for tiny angles, where acos of a dot of float32 vectors that
    are not quite unit reads 0.01 deg between a vector and itself. In plain
    floats: it runs per frame, where numpy's per-call cost was most of it."""
    ux, uy, uz = float(u[0]), float(u[1]), float(u[2])
    vx, vy, vz = float(v[0]), float(v[1]), float(v[2])
    across = math.sqrt((uy * vz - uz * vy) ** 2 + (uz * vx - ux * vz) ** 2
                       + (ux * vy - uy * vx) ** 2)
    return math.degrees(math.atan2(across, ux * vx + uy * vy + uz * vz))
