// The scene's coarse 3D model as an Embree BVH, with batched ray queries.
//
// Thesis §3.3 casts a ray from the camera through every pixel to find its 3D
// point and normal, and from every light toward that point to decide whether
// the light reaches it. Both are batches of rays here, run in parallel (TBB).
// All positions are world frame (Blender's, metres), float32 as Embree stores.
#pragma once

#include <cstdint>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "sunlapse/scene/camera.h"

namespace sunlapse {

// Where the first-hit results go: caller-owned arrays of n (or n x 3) values,
// so that numpy arrays are filled without copies. Null members are skipped.
// On a miss: distance = +inf, object_id = triangle_id = -1, point and normal
// are NaN.
struct HitBuffers {
  float* point_in_world = nullptr;   // n x 3
  float* normal_in_world = nullptr;  // n x 3, unit, facing the ray origin
  float* distance = nullptr;         // n, along the unit ray direction (m)
  int32_t* object_id = nullptr;      // n
  int32_t* triangle_id = nullptr;    // n
};

// Owns copies of the results, for C++ callers.
struct Hits {
  explicit Hits(int64_t n = 0);
  HitBuffers buffers();
  bool hit(int64_t i) const { return object_id[i] >= 0; }
  Eigen::Vector3f point(int64_t i) const;
  Eigen::Vector3f normal(int64_t i) const;
  std::vector<float> point_in_world, normal_in_world, distance;
  std::vector<int32_t> object_id, triangle_id;
};

class Scene {
 public:
  // vertices: num_vertices x 3; triangles: num_triangles x 3 vertex indices;
  // object_ids: one per triangle (any int32 >= 0 chosen by the caller).
  // The data is copied. Throws std::invalid_argument naming the bad argument
  // (empty mesh, index out of range, non-finite vertex, negative object id).
  Scene(const float* vertices, int64_t num_vertices, const int32_t* triangles,
        int64_t num_triangles, const int32_t* object_ids);
  Scene(const std::vector<Eigen::Vector3f>& vertices,
        const std::vector<Eigen::Vector3i>& triangles,
        const std::vector<int32_t>& object_ids);
  ~Scene();
  Scene(Scene&&) noexcept;
  Scene& operator=(Scene&&) noexcept;

  int64_t num_triangles() const;
  int64_t num_vertices() const;
  // Axis-aligned bounds of all vertices (world frame).
  Eigen::AlignedBox3f bounds() const;
  // How far (m) a ray that leaves the model's surface starts off it, along
  // the normal, so that it does not hit the surface it leaves: 1 mm plus
  // 1e-5 of the model's diagonal, well above float32's error on the hit
  // points. No more: 2e-4 of the diagonal (4.5 cm under the suite's 160 m
  // ground plane) shortened every predicted shadow of a 2.5 m caster by 2%
  // and put the Sun 0.45 deg too low on the median scene
  // (docs/accuracy.md, "The surface offset's bias").
  float surface_offset() const;
  // The elevation (rad above the horizontal) above which nothing of the
  // model stands as seen from `point`: a ray from it steeper than that is
  // not occluded. Bounded from the objects' boxes (pi/2 under one), with
  // 1e-4 rad to spare for the rays' float arithmetic.
  float OpenSkyAbove(const Eigen::Vector3f& point) const;
  int32_t object_id_of_triangle(int64_t t) const;
  // The model's data as given (world frame).
  Eigen::Vector3f vertex(int64_t v) const;
  Eigen::Vector3i triangle(int64_t t) const;

  // First hits of n rays (origins/directions n x 3; directions need not be
  // unit, distance is reported along the normalised direction). Rays start at
  // t_near and stop at t_far (metres).
  void Intersect(int64_t n, const float* origins, const float* directions,
                 float t_near, float t_far, HitBuffers out) const;
  // First hits of the camera's viewing rays through n pixels (n x 2, OpenCV
  // pixels, recorded i.e. distorted if the camera has a distortion).
  void IntersectPixels(const Camera& camera, int64_t n, const double* pixels,
                       HitBuffers out) const;
  Hits IntersectPixels(const Camera& camera,
                       const std::vector<Eigen::Vector2d>& pixels) const;
  // occluded[i] = 1 if anything lies on ray i between t_near and t_far.
  void Occluded(int64_t n, const float* origins, const float* directions,
                float t_near, float t_far, uint8_t* occluded) const;
  // The same toward one shared direction (e.g. a candidate Sun).
  void OccludedToward(int64_t n, const float* origins,
                      const Eigen::Vector3f& direction, float t_near,
                      float t_far, uint8_t* occluded) const;
  // The same for the rays from origins[3 * which[k]], k < n: a subset of
  // the origins, not copied (the sky's table casts from most of them, 3,000
  // times).
  void OccludedTowardSubset(int64_t n, const int32_t* which,
                            const float* origins,
                            const Eigen::Vector3f& direction, float t_near,
                            float t_far, uint8_t* occluded) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sunlapse
