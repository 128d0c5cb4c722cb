#include "sunlapse/scene/scene.h"
#include "sunlapse/common/require.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <stdexcept>
#include <string>

namespace sunlapse {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
// Rays per task: large enough to amortise scheduling, small enough to balance.
constexpr int64_t kGrain = 256;

std::string EmbreeErrorName(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE:
      return "none";
    case RTC_ERROR_INVALID_ARGUMENT:
      return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION:
      return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY:
      return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU:
      return "unsupported CPU";
    case RTC_ERROR_CANCELLED:
      return "cancelled";
    default:
      return "unknown";
  }
}

// Embree asserts on rays with non-finite origins or directions (Debian builds
// it with assertions on), so such rays are answered here as misses.
bool ValidRay(const float* o, const float* d, float* norm) {
  *norm = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  return *norm > 0 && std::isfinite(*norm) && std::isfinite(o[0]) &&
         std::isfinite(o[1]) && std::isfinite(o[2]);
}

// A ray query from o along unit direction d (Embree's fields in one place).
RTCRayHit MakeRayHit(const float o[3], const float d[3], float t_near,
                     float t_far) {
  RTCRayHit rh;
  rh.ray.org_x = o[0];
  rh.ray.org_y = o[1];
  rh.ray.org_z = o[2];
  rh.ray.dir_x = d[0];
  rh.ray.dir_y = d[1];
  rh.ray.dir_z = d[2];
  rh.ray.tnear = t_near;
  rh.ray.tfar = t_far;
  rh.ray.time = 0.f;
  rh.ray.mask = 0xFFFFFFFFu;
  rh.ray.id = 0;
  rh.ray.flags = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  return rh;
}

void WriteMiss(int64_t i, const HitBuffers& out) {
  if (out.point_in_world) {
    for (int k = 0; k < 3; ++k) out.point_in_world[3 * i + k] = kNaN;
  }
  if (out.normal_in_world) {
    for (int k = 0; k < 3; ++k) out.normal_in_world[3 * i + k] = kNaN;
  }
  if (out.distance) out.distance[i] = kInf;
  if (out.object_id) out.object_id[i] = -1;
  if (out.triangle_id) out.triangle_id[i] = -1;
}

}  // namespace

struct Scene::Impl {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<int32_t> object_ids;
  std::vector<float> vertices;  // copies, for callers that need the mesh
  std::vector<int32_t> triangles;
  int64_t num_vertices = 0;
  Eigen::AlignedBox3f bounds;
  // Bounding boxes of the objects (of the whole model when there are many),
  // for OpenSkyAbove.
  std::vector<Eigen::AlignedBox3f> boxes;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }

  void CheckDevice(const char* what) const {
    const RTCError e = rtcGetDeviceError(device);
    if (e != RTC_ERROR_NONE) {
      throw std::runtime_error(std::string("Embree failed in ") + what + ": " +
                               EmbreeErrorName(e));
    }
  }

  // Fills slot i of `out` from a finished ray query.
  void WriteHit(int64_t i, const RTCRayHit& rh, float dir_norm,
                const HitBuffers& out) const {
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
      WriteMiss(i, out);
      return;
    }
    const float t = rh.ray.tfar;
    if (out.point_in_world) {
      out.point_in_world[3 * i + 0] = rh.ray.org_x + t * rh.ray.dir_x;
      out.point_in_world[3 * i + 1] = rh.ray.org_y + t * rh.ray.dir_y;
      out.point_in_world[3 * i + 2] = rh.ray.org_z + t * rh.ray.dir_z;
    }
    if (out.normal_in_world) {
      Eigen::Vector3f n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
      const Eigen::Vector3f d(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z);
      if (n.dot(d) > 0) n = -n;  // face the ray's origin (the camera)
      n.normalize();
      for (int k = 0; k < 3; ++k) out.normal_in_world[3 * i + k] = n[k];
    }
    if (out.distance) out.distance[i] = t * dir_norm;
    if (out.object_id) out.object_id[i] = object_ids[rh.hit.primID];
    if (out.triangle_id) {
      out.triangle_id[i] = static_cast<int32_t>(rh.hit.primID);
    }
  }
};

Hits::Hits(int64_t n)
    : point_in_world(3 * n),
      normal_in_world(3 * n),
      distance(n),
      object_id(n),
      triangle_id(n) {}

HitBuffers Hits::buffers() {
  return {point_in_world.data(), normal_in_world.data(), distance.data(),
          object_id.data(), triangle_id.data()};
}

Eigen::Vector3f Hits::point(int64_t i) const {
  return Eigen::Vector3f(&point_in_world[3 * i]);
}

Eigen::Vector3f Hits::normal(int64_t i) const {
  return Eigen::Vector3f(&normal_in_world[3 * i]);
}

namespace {
// Each object's bounding box; a model of more objects than OpenSkyAbove
// should test against, per point, is bounded by its own box alone (merging
// boxes is no better: a wide ground merged with anything standing on it
// bounds every point by that thing's height).
std::vector<Eigen::AlignedBox3f> ObjectBoxes(
    const std::vector<float>& vertices, const std::vector<int32_t>& triangles,
    const std::vector<int32_t>& object_ids, const Eigen::AlignedBox3f& bounds) {
  constexpr size_t kMaxBoxes = 256;
  std::map<int32_t, Eigen::AlignedBox3f> by_object;
  for (size_t t = 0; t < object_ids.size(); ++t) {
    Eigen::AlignedBox3f& box = by_object[object_ids[t]];
    for (int k = 0; k < 3; ++k) {
      const float* v =
          vertices.data() + 3 * static_cast<size_t>(triangles[3 * t + k]);
      box.extend(Eigen::Vector3f(v[0], v[1], v[2]));
    }
    if (by_object.size() > kMaxBoxes) return {bounds};
  }
  std::vector<Eigen::AlignedBox3f> boxes;
  for (const auto& [id, box] : by_object) boxes.push_back(box);
  return boxes;
}
}  // namespace

Scene::Scene(const float* vertices, int64_t num_vertices,
             const int32_t* triangles, int64_t num_triangles,
             const int32_t* object_ids)
    : impl_(std::make_unique<Impl>()) {
  Require(num_vertices > 0 && vertices != nullptr,
          "vertices: the model has no vertices (is the collection empty?)");
  Require(num_triangles > 0 && triangles != nullptr,
          "triangles: the model has no triangles (is the collection empty?)");
  Require(object_ids != nullptr, "object_ids: missing");
  Require(num_vertices <= std::numeric_limits<int32_t>::max(),
          "vertices: more than 2^31 vertices");
  Require(num_triangles <= std::numeric_limits<int32_t>::max(),
          "triangles: more than 2^31 triangles");

  Eigen::AlignedBox3f bounds;
  for (int64_t v = 0; v < num_vertices; ++v) {
    const Eigen::Vector3f p(vertices + 3 * v);
    Require(p.allFinite(),
            "vertices: vertex " + std::to_string(v) + " is not finite");
    bounds.extend(p);
  }
  for (int64_t t = 0; t < num_triangles; ++t) {
    for (int k = 0; k < 3; ++k) {
      const int32_t idx = triangles[3 * t + k];
      Require(idx >= 0 && idx < num_vertices,
              "triangles: index " + std::to_string(idx) + " of triangle " +
                  std::to_string(t) + " is out of range [0, " +
                  std::to_string(num_vertices) + ")");
    }
    Require(object_ids[t] >= 0,
            "object_ids: id of triangle " + std::to_string(t) + " is negative");
  }

  Impl& s = *impl_;
  s.device = rtcNewDevice(nullptr);
  if (!s.device) {
    throw std::runtime_error("Embree: cannot create a device: " +
                             EmbreeErrorName(rtcGetDeviceError(nullptr)));
  }
  s.scene = rtcNewScene(s.device);
  rtcSetSceneBuildQuality(s.scene, RTC_BUILD_QUALITY_MEDIUM);
  RTCGeometry geom = rtcNewGeometry(s.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  // Embree may read 16 bytes past a vertex buffer's last element; buffers it
  // allocates itself are padded, so copy into those.
  auto* vbuf = static_cast<float*>(rtcSetNewGeometryBuffer(
      geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float),
      num_vertices));
  auto* ibuf = static_cast<uint32_t*>(
      rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(uint32_t), num_triangles));
  if (!vbuf || !ibuf) {
    rtcReleaseGeometry(geom);
    s.CheckDevice("buffer allocation");
    throw std::runtime_error("Embree: buffer allocation failed");
  }
  std::memcpy(vbuf, vertices, sizeof(float) * 3 * num_vertices);
  std::memcpy(ibuf, triangles, sizeof(uint32_t) * 3 * num_triangles);
  rtcCommitGeometry(geom);
  rtcAttachGeometry(s.scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(s.scene);
  s.CheckDevice("the BVH build");
  s.object_ids.assign(object_ids, object_ids + num_triangles);
  s.vertices.assign(vertices, vertices + 3 * num_vertices);
  s.triangles.assign(triangles, triangles + 3 * num_triangles);
  s.num_vertices = num_vertices;
  s.bounds = bounds;
  s.boxes = ObjectBoxes(s.vertices, s.triangles, s.object_ids, bounds);
}

namespace {
template <typename V>
std::vector<float> Flatten3(const std::vector<V>& v) {
  std::vector<float> out(3 * v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    for (int k = 0; k < 3; ++k) out[3 * i + k] = static_cast<float>(v[i][k]);
  }
  return out;
}
template <typename V>
std::vector<int32_t> Flatten3i(const std::vector<V>& v) {
  std::vector<int32_t> out(3 * v.size());
  for (size_t i = 0; i < v.size(); ++i) {
    for (int k = 0; k < 3; ++k) out[3 * i + k] = v[i][k];
  }
  return out;
}
}  // namespace

Scene::Scene(const std::vector<Eigen::Vector3f>& vertices,
             const std::vector<Eigen::Vector3i>& triangles,
             const std::vector<int32_t>& object_ids)
    : Scene(Flatten3(vertices).data(), static_cast<int64_t>(vertices.size()),
            Flatten3i(triangles).data(), static_cast<int64_t>(triangles.size()),
            (Require(object_ids.size() == triangles.size(),
                     "object_ids: need one per triangle"),
             object_ids.data())) {}

Scene::~Scene() = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;

int64_t Scene::num_triangles() const {
  return static_cast<int64_t>(impl_->object_ids.size());
}
int64_t Scene::num_vertices() const { return impl_->num_vertices; }
Eigen::AlignedBox3f Scene::bounds() const { return impl_->bounds; }

float Scene::surface_offset() const {
  return 1e-3f + 1e-5f * impl_->bounds.diagonal().norm();
}

float Scene::OpenSkyAbove(const Eigen::Vector3f& point) const {
  double steepest = -std::numeric_limits<double>::infinity();  // a tangent
  for (const Eigen::AlignedBox3f& box : impl_->boxes) {
    const double rise = double(box.max().z()) - point.z();
    if (rise <= 0) continue;
    const double dx =
        std::max({box.min().x() - point.x(), 0.f, point.x() - box.max().x()});
    const double dy =
        std::max({box.min().y() - point.y(), 0.f, point.y() - box.max().y()});
    const double run = std::hypot(dx, dy);
    if (!(run > 0)) return static_cast<float>(M_PI / 2);
    steepest = std::max(steepest, rise / run);
  }
  return static_cast<float>(std::min(M_PI / 2, std::atan(steepest) + 1e-4));
}
int32_t Scene::object_id_of_triangle(int64_t t) const {
  return impl_->object_ids.at(t);
}
Eigen::Vector3f Scene::vertex(int64_t v) const {
  Require(v >= 0 && v < impl_->num_vertices, "vertex index out of range");
  return Eigen::Vector3f(&impl_->vertices[3 * v]);
}
Eigen::Vector3i Scene::triangle(int64_t t) const {
  Require(t >= 0 && t < num_triangles(), "triangle index out of range");
  return Eigen::Vector3i(&impl_->triangles[3 * t]);
}

void Scene::Intersect(int64_t n, const float* origins, const float* directions,
                      float t_near, float t_far, HitBuffers out) const {
  Require(n >= 0, "n must be >= 0");
  Require(t_near >= 0 && t_far >= t_near, "need 0 <= t_near <= t_far");
  const Impl& s = *impl_;
  tbb::parallel_for(
      tbb::blocked_range<int64_t>(0, n, kGrain),
      [&](const tbb::blocked_range<int64_t>& r) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        for (int64_t i = r.begin(); i < r.end(); ++i) {
          const float* o = origins + 3 * i;
          const float* d = directions + 3 * i;
          float norm;
          if (!ValidRay(o, d, &norm)) {
            WriteMiss(i, out);
            continue;
          }
          const float unit[3] = {d[0] / norm, d[1] / norm, d[2] / norm};
          RTCRayHit rh = MakeRayHit(o, unit, t_near, t_far);
          rtcIntersect1(s.scene, &ctx, &rh);
          s.WriteHit(i, rh, 1.f, out);
        }
      });
}

void Scene::IntersectPixels(const Camera& camera, int64_t n,
                            const double* pixels, HitBuffers out) const {
  Require(n >= 0, "n must be >= 0");
  const Impl& s = *impl_;
  const Eigen::Vector3f center = camera.center_in_world().cast<float>();
  // Neighbouring pixels' rays share an origin and nearly a direction:
  // packets of 16 traverse the BVH together (the tracker's ground map, a
  // ray per pixel of the frame, took 0.14 s at 1080p with single rays).
  constexpr int kPacket = 16;
  tbb::parallel_for(
      tbb::blocked_range<int64_t>(0, (n + kPacket - 1) / kPacket,
                                  kGrain / kPacket),
      [&](const tbb::blocked_range<int64_t>& r) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        alignas(64) RTCRayHit16 packet;
        alignas(64) int valid[kPacket];
        for (int64_t p = r.begin(); p < r.end(); ++p) {
          const int64_t base = p * kPacket;
          for (int k = 0; k < kPacket; ++k) {
            const int64_t i = base + k;
            const Eigen::Vector2d px =
                i < n ? Eigen::Vector2d(pixels[2 * i], pixels[2 * i + 1])
                      : Eigen::Vector2d(kNaN, kNaN);
            valid[k] = px.allFinite() ? -1 : 0;
            const Eigen::Vector3f d =
                valid[k] ? camera.PixelToRayInWorld(px).cast<float>()
                         : Eigen::Vector3f(0.f, 0.f, 1.f);
            packet.ray.org_x[k] = center.x();
            packet.ray.org_y[k] = center.y();
            packet.ray.org_z[k] = center.z();
            packet.ray.dir_x[k] = d.x();
            packet.ray.dir_y[k] = d.y();
            packet.ray.dir_z[k] = d.z();
            packet.ray.tnear[k] = 0.f;
            packet.ray.tfar[k] = kInf;
            packet.ray.time[k] = 0.f;
            packet.ray.mask[k] = 0xFFFFFFFFu;
            packet.ray.id[k] = 0;
            packet.ray.flags[k] = 0;
            packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
            packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
          }
          rtcIntersect16(valid, s.scene, &ctx, &packet);
          for (int k = 0; k < kPacket && base + k < n; ++k) {
            const int64_t i = base + k;
            if (!valid[k]) {
              WriteMiss(i, out);
              continue;
            }
            const float o[3] = {center.x(), center.y(), center.z()};
            const float d[3] = {packet.ray.dir_x[k], packet.ray.dir_y[k],
                                packet.ray.dir_z[k]};
            RTCRayHit rh = MakeRayHit(o, d, 0.f, packet.ray.tfar[k]);
            rh.hit.Ng_x = packet.hit.Ng_x[k];
            rh.hit.Ng_y = packet.hit.Ng_y[k];
            rh.hit.Ng_z = packet.hit.Ng_z[k];
            rh.hit.primID = packet.hit.primID[k];
            rh.hit.geomID = packet.hit.geomID[k];
            s.WriteHit(i, rh, 1.f, out);
          }
        }
      });
}

Hits Scene::IntersectPixels(const Camera& camera,
                            const std::vector<Eigen::Vector2d>& pixels) const {
  Hits hits(static_cast<int64_t>(pixels.size()));
  std::vector<double> flat(2 * pixels.size());
  for (size_t i = 0; i < pixels.size(); ++i) {
    flat[2 * i] = pixels[i].x();
    flat[2 * i + 1] = pixels[i].y();
  }
  IntersectPixels(camera, static_cast<int64_t>(pixels.size()), flat.data(),
                  hits.buffers());
  return hits;
}

namespace {
// Occlusion tests of n rays whose direction for ray i is dir_at(i) (a
// pointer to 3 floats, need not be unit); shared by both public forms.
template <typename DirAt>
void OccludedBatch(RTCScene scene, int64_t n, const float* origins,
                   DirAt dir_at, float t_near, float t_far, bool coherent,
                   uint8_t* occluded) {
  Require(n >= 0, "n must be >= 0");
  Require(t_near >= 0 && t_far >= t_near, "need 0 <= t_near <= t_far");
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n, kGrain),
                    [&](const tbb::blocked_range<int64_t>& r) {
                      RTCIntersectContext ctx;
                      rtcInitIntersectContext(&ctx);
                      if (coherent)
                        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
                      for (int64_t i = r.begin(); i < r.end(); ++i) {
                        const float* o = origins + 3 * i;
                        const float* d = dir_at(i);
                        float norm;
                        if (!ValidRay(o, d, &norm)) {
                          occluded[i] = 0;
                          continue;
                        }
                        RTCRay ray;
                        ray.org_x = o[0];
                        ray.org_y = o[1];
                        ray.org_z = o[2];
                        ray.dir_x = d[0] / norm;
                        ray.dir_y = d[1] / norm;
                        ray.dir_z = d[2] / norm;
                        ray.tnear = t_near;
                        ray.tfar = t_far;
                        ray.time = 0.f;
                        ray.mask = 0xFFFFFFFFu;
                        ray.id = 0;
                        ray.flags = 0;
                        rtcOccluded1(scene, &ctx, &ray);
                        occluded[i] =
                            ray.tfar < 0 ? 1 : 0;  // Embree sets -inf on a hit
                      }
                    });
}
}  // namespace

void Scene::Occluded(int64_t n, const float* origins, const float* directions,
                     float t_near, float t_far, uint8_t* occluded) const {
  OccludedBatch(
      impl_->scene, n, origins, [&](int64_t i) { return directions + 3 * i; },
      t_near, t_far, false, occluded);
}

namespace {
// Rays toward one direction d (unit) from origin_of(i), i < n. Neighbouring
// origins and one direction: packets of 16 rays traverse the BVH together,
// several times faster than single rays here. Tasks of 16 packets: the
// tracker casts a few thousand rays at a time, which larger tasks split
// unevenly over the cores (1080p tracking benchmark: 1.9 -> 1.65 ms per
// frame, and steadier).
template <typename OriginOf>
void OccludedPackets(RTCScene scene, int64_t n, OriginOf origin_of,
                     const Eigen::Vector3f& d, float t_near, float t_far,
                     uint8_t* occluded) {
  constexpr int kPacket = 16;
  tbb::parallel_for(
      tbb::blocked_range<int64_t>(0, (n + kPacket - 1) / kPacket, 16),
      [&](const tbb::blocked_range<int64_t>& r) {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        alignas(64) RTCRay16 rays;
        alignas(64) int valid[kPacket];
        // What all rays share is set once per task; Embree writes only tfar.
        for (int k = 0; k < kPacket; ++k) {
          rays.dir_x[k] = d.x();
          rays.dir_y[k] = d.y();
          rays.dir_z[k] = d.z();
          rays.tnear[k] = t_near;
          rays.time[k] = 0.f;
          rays.mask[k] = 0xFFFFFFFFu;
          rays.id[k] = 0;
          rays.flags[k] = 0;
        }
        for (int64_t p = r.begin(); p < r.end(); ++p) {
          const int64_t base = p * kPacket;
          for (int k = 0; k < kPacket; ++k) {
            const int64_t i = base + k;
            const float* o = origin_of(std::min(i, n - 1));
            valid[k] = (i < n && std::isfinite(o[0]) && std::isfinite(o[1]) &&
                        std::isfinite(o[2]))
                           ? -1
                           : 0;
            rays.org_x[k] = valid[k] ? o[0] : 0.f;
            rays.org_y[k] = valid[k] ? o[1] : 0.f;
            rays.org_z[k] = valid[k] ? o[2] : 0.f;
            rays.tfar[k] = t_far;
          }
          rtcOccluded16(valid, scene, &ctx, &rays);
          for (int k = 0; k < kPacket && base + k < n; ++k) {
            occluded[base + k] = (valid[k] && rays.tfar[k] < 0) ? 1 : 0;
          }
        }
      });
}

Eigen::Vector3f CheckedToward(int64_t n, const Eigen::Vector3f& direction,
                              float t_near, float t_far) {
  Require(n >= 0, "n must be >= 0");
  Require(t_near >= 0 && t_far >= t_near, "need 0 <= t_near <= t_far");
  Require(direction.allFinite() && direction.norm() > 0,
          "direction must be finite and non-zero");
  return direction.normalized();
}
}  // namespace

void Scene::OccludedToward(int64_t n, const float* origins,
                           const Eigen::Vector3f& direction, float t_near,
                           float t_far, uint8_t* occluded) const {
  const Eigen::Vector3f d = CheckedToward(n, direction, t_near, t_far);
  OccludedPackets(
      impl_->scene, n, [origins](int64_t i) { return origins + 3 * i; }, d,
      t_near, t_far, occluded);
}

void Scene::OccludedTowardSubset(int64_t n, const int32_t* which,
                                 const float* origins,
                                 const Eigen::Vector3f& direction, float t_near,
                                 float t_far, uint8_t* occluded) const {
  const Eigen::Vector3f d = CheckedToward(n, direction, t_near, t_far);
  OccludedPackets(
      impl_->scene, n,
      [which, origins](int64_t i) { return origins + 3 * int64_t{which[i]}; },
      d, t_near, t_far, occluded);
}

}  // namespace sunlapse
