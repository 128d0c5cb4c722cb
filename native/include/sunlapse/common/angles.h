// The Sun's angles and its direction, one helper for all stages (docs/design.md
// §4). World frame: Blender's, +X east, +Y north (of the scene), +Z up. Zenith
// from +Z toward the Sun; azimuth clockwise from +Y toward +X. A geographic
// azimuth is measured from true north; a scene whose +Y is turned from north
// by north_offset (Blender's Sun Position add-on) has
// azimuth_world = azimuth_geographic + north_offset.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace sunlapse {

inline constexpr double kRadPerDeg = M_PI / 180.0;

// An angle in degrees wrapped to [0, 360).
inline double WrapAzimuthDeg(double azimuth_deg) {
  const double a = std::fmod(azimuth_deg, 360.0);
  // fmod keeps the sign; -1e-15 + 360 rounds to 360, which is 0.
  const double wrapped = a < 0 ? a + 360.0 : a;
  return wrapped >= 360.0 ? 0.0 : wrapped;
}

// Unit vector toward the Sun in the world frame:
// (sin z sin a, sin z cos a, cos z).
inline Eigen::Vector3d SunInWorldFromAngles(double zenith_deg,
                                            double azimuth_world_deg) {
  const double z = zenith_deg * kRadPerDeg, a = azimuth_world_deg * kRadPerDeg;
  return {std::sin(z) * std::sin(a), std::sin(z) * std::cos(a), std::cos(z)};
}

// Inverse of SunInWorldFromAngles for a vector of any non-zero length:
// zenith in [0, 180], world azimuth in [0, 360) (0 straight up or down).
inline void AnglesFromSunInWorld(const Eigen::Vector3d& sun_in_world,
                                 double* zenith_deg,
                                 double* azimuth_world_deg) {
  const Eigen::Vector3d d = sun_in_world.normalized();
  *zenith_deg = std::acos(std::clamp(d.z(), -1.0, 1.0)) / kRadPerDeg;
  *azimuth_world_deg = WrapAzimuthDeg(std::atan2(d.x(), d.y()) / kRadPerDeg);
}

// A geographic azimuth (from true north) in a scene whose +Y is turned from
// north by north_offset_deg; [0, 360).
inline double AzimuthWorldFromGeographic(double azimuth_geographic_deg,
                                         double north_offset_deg) {
  return WrapAzimuthDeg(azimuth_geographic_deg + north_offset_deg);
}

// Inverse of AzimuthWorldFromGeographic; [0, 360).
inline double AzimuthGeographicFromWorld(double azimuth_world_deg,
                                         double north_offset_deg) {
  return WrapAzimuthDeg(azimuth_world_deg - north_offset_deg);
}

// Angle between two directions of any non-zero length, degrees.
// atan2(|a x b|, a.b) stays exact for tiny angles, where acos does not.
inline double AngleBetweenDeg(const Eigen::Vector3d& a,
                              const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kRadPerDeg;
}

// The width of a planar face's normal cell (NormalBin), degrees: the sky's
// planar groups (SkyEvidenceOptions::normal_bin_deg) and the tracker's faces.
constexpr double kFaceNormalBinDeg = 12.0;

// A surface normal's cell, bin_deg wide in zenith and in azimuth (one cell
// about the zenith): the faces of a model that share one cell and one
// object are one plane, lit alike by the Sun.
inline std::pair<int, int> NormalBin(const Eigen::Vector3f& n, double bin_deg) {
  const double bin = bin_deg * kRadPerDeg;
  const double nz = std::acos(std::clamp(double(n.z()), -1.0, 1.0));
  const int zbin = static_cast<int>(std::floor(nz / bin));
  const int abin =
      zbin == 0 ? 0
                : static_cast<int>(std::floor(
                      (std::atan2(double(n.x()), double(n.y())) + M_PI) / bin));
  return {zbin, abin};
}

// About n nearly uniform directions over the sky from the zenith down to
// max_zenith_deg (a Fibonacci spiral), world frame.
inline std::vector<Eigen::Vector3d> FibonacciSky(int n, double max_zenith_deg) {
  std::vector<Eigen::Vector3d> out;
  const double zmin = std::cos(max_zenith_deg * kRadPerDeg);
  const double golden = M_PI * (3.0 - std::sqrt(5.0));
  for (int k = 0; k < n; ++k) {
    const double z = 1.0 - (k + 0.5) / n * (1.0 - zmin);
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    out.emplace_back(r * std::cos(golden * k), r * std::sin(golden * k), z);
  }
  return out;
}

}  // namespace sunlapse
