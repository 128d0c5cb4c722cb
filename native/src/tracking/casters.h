// The model's shadow casters, shared by the trackers.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "sunlapse/scene/scene.h"

namespace sunlapse::internal {

// A caster of the model: its vertices at its top level (a pole's four top
// corners) and its lowest level (where it stands).
struct Caster {
  std::vector<Eigen::Vector3f> tops;
  float bottom;
  int32_t object_id;
  Eigen::Vector3f FootBelow(const Eigen::Vector3f& top) const {
    return {top.x(), top.y(), bottom};
  }
};

inline bool IsGround(const std::vector<int32_t>& ground_ids, int32_t id) {
  return std::find(ground_ids.begin(), ground_ids.end(), id) !=
         ground_ids.end();
}

std::vector<Caster> FindCasters(const Scene& scene,
                                const std::vector<int32_t>& ground_ids);

// The tip of the caster's shadow on the ground toward the Sun `toward_sun`:
// of its top vertices, the one whose shadow lands on the ground furthest from
// the caster (the outer corner; the others' rays may clip the caster itself).
// Writes that vertex to *top and its shadow to *tip; false if none lands.
bool ShadowTip(const Scene& scene, const Caster& caster,
               const Eigen::Vector3d& toward_sun,
               const std::vector<int32_t>& ground_ids, Eigen::Vector3f* top,
               Eigen::Vector3f* tip);

}  // namespace sunlapse::internal
