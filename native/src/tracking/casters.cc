#include "casters.h"

#include <cmath>
#include <limits>

namespace sunlapse::internal {

std::vector<Caster> FindCasters(const Scene& scene,
                                const std::vector<int32_t>& ground_ids) {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  std::vector<float> top(0), bottom(0);
  std::vector<std::vector<int64_t>> verts;
  for (int64_t t = 0; t < scene.num_triangles(); ++t) {
    const int32_t id = scene.object_id_of_triangle(t);
    if (IsGround(ground_ids, id)) continue;
    if (id >= static_cast<int32_t>(top.size())) {
      top.resize(id + 1, -kInf);
      bottom.resize(id + 1, kInf);
      verts.resize(id + 1);
    }
    const Eigen::Vector3i tri = scene.triangle(t);
    for (int k = 0; k < 3; ++k) {
      const float z = scene.vertex(tri[k]).z();
      top[id] = std::max(top[id], z);
      bottom[id] = std::min(bottom[id], z);
      verts[id].push_back(tri[k]);
    }
  }
  std::vector<Caster> out;
  for (int32_t id = 0; id < static_cast<int32_t>(top.size()); ++id) {
    if (!(top[id] > bottom[id])) continue;
    Caster c{{}, bottom[id], id};
    const float level = top[id] - 1e-3f * std::max(1.f, top[id] - bottom[id]);
    std::sort(verts[id].begin(), verts[id].end());
    verts[id].erase(std::unique(verts[id].begin(), verts[id].end()),
                    verts[id].end());
    for (int64_t v : verts[id]) {
      const Eigen::Vector3f p = scene.vertex(v);
      if (p.z() >= level) c.tops.push_back(p);
    }
    out.push_back(std::move(c));
  }
  return out;
}

bool ShadowTip(const Scene& scene, const Caster& c,
               const Eigen::Vector3d& toward_sun,
               const std::vector<int32_t>& ground_ids, Eigen::Vector3f* top,
               Eigen::Vector3f* tip) {
  const float d[3] = {static_cast<float>(-toward_sun.x()),
                      static_cast<float>(-toward_sun.y()),
                      static_cast<float>(-toward_sun.z())};
  double longest = -1;
  for (const Eigen::Vector3f& p : c.tops) {
    const float o[3] = {p.x(), p.y(), p.z()};
    Hits hit(1);
    scene.Intersect(1, o, d, 1e-3f, std::numeric_limits<float>::infinity(),
                    hit.buffers());
    if (!hit.hit(0) || !IsGround(ground_ids, hit.object_id[0])) continue;
    const double length = (hit.point(0) - c.FootBelow(p)).norm();
    if (length > longest) {
      longest = length;
      *top = p;
      *tip = hit.point(0);
    }
  }
  return longest >= 0;
}

}  // namespace sunlapse::internal
