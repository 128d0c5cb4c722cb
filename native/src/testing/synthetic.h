// Test support: small models, cameras and a Lambertian renderer with cast
// shadows, for tests and benchmarks that need frames with a known Sun.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "sunlapse/common/angles.h"
#include "sunlapse/scene/camera.h"
#include "sunlapse/scene/scene.h"

namespace sunlapse::testing {

struct Mesh {
  std::vector<Eigen::Vector3f> v;
  std::vector<Eigen::Vector3i> t;
  std::vector<int32_t> ids;
  // Axis-aligned box.
  void Box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, int id);
  // Square at z = 0 of half-size `half`.
  void Ground(float half, int id);
  Scene Build() const { return Scene(v, t, ids); }
};

// Ground (id 0), a box (1) and a pole (2).
Mesh BoxAndPole();
// A ground (0) `ground_half` m each way and a 0.2 m square pole (1),
// `height` m tall, at the origin.
Mesh PoleOnGround(float ground_half, float height);
// BoxAndPole plus a second pole (3) and a wall (4): the benchmarks' scene.
Mesh BenchScene();
// The benchmarks' camera on BenchScene at 1920x1080.
Camera BenchCamera();

// A Blender-style camera at `eye` looking at `target` (+Z up).
Camera LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
              int width, int height, double lens_mm = 24.0);

struct RenderOptions {
  double ambient = 0.08;  // times albedo
  double sun = 0.7;       // times albedo x max(0, N.L) x visible
  double noise = 0.01;    // Gaussian, intensity units
  float sky = 0.6f;       // where no model is seen
  uint32_t seed = 1;
  // Rays per pixel along each axis, averaged: a sensor integrates over the
  // pixel's area (1 = point sampling at pixel centres).
  int supersample = 1;
  // Albedo of object `id` at world point p.
  std::function<double(int id, const Eigen::Vector3f& p)> albedo =
      [](int, const Eigen::Vector3f&) { return 0.5; };
};

// A tiled, gently varying ground (object 0; the others 0.5) under 1% noise
// and 15% ambient light, like real paving.
RenderOptions TexturedGround(uint32_t seed);

// I = albedo (ambient + sun max(0, N.L) visible) + noise, clamped to [0, 1];
// CV_32F of the camera's size.
cv::Mat RenderLambertian(const Scene& scene, const Camera& camera,
                         const Eigen::Vector3d& toward_sun,
                         const RenderOptions& options);

}  // namespace sunlapse::testing
