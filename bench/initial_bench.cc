// Initial-Sun benchmark: time of EstimateInitialSun on a 1920x1080 frame
// (ray casting + fit), both methods. Prints figures; never gates anything.
//   build/bench/bench_initial
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>

#include "sunlapse/initial/initial_sun.h"

using namespace sunlapse;

int main() {
  // Ground, a box, three poles and a wall.
  std::vector<Eigen::Vector3f> v;
  std::vector<Eigen::Vector3i> t;
  std::vector<int32_t> ids;
  auto box = [&](Eigen::Vector3f lo, Eigen::Vector3f hi, int id) {
    const int b = static_cast<int>(v.size());
    for (int i = 0; i < 8; ++i) {
      v.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
    }
    const int q[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
    for (const auto& f : q) {
      t.emplace_back(b + f[0], b + f[1], b + f[2]);
      t.emplace_back(b + f[0], b + f[2], b + f[3]);
      ids.insert(ids.end(), {id, id});
    }
  };
  box({-20, -20, -0.1f}, {20, 20, 0}, 0);
  box({-1.5f, -1, 0}, {0.5f, 1.2f, 1.6f}, 1);
  box({2.5f, -2.6f, 0}, {2.65f, -2.45f, 3}, 2);
  box({-3, 2, 0}, {-2.85f, 2.15f, 2.5f}, 3);
  box({-4, 5, 0}, {1, 5.3f, 2}, 4);
  const Scene scene(v, t, ids);

  BlenderCameraParams p;
  p.lens_mm = 24;
  const Eigen::Vector3d eye(3, -11, 8), back = eye.normalized();
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(back).normalized();
  p.world_from_camera_local.block<3, 1>(0, 0) = right;
  p.world_from_camera_local.block<3, 1>(0, 1) = back.cross(right);
  p.world_from_camera_local.block<3, 1>(0, 2) = back;
  p.world_from_camera_local.block<3, 1>(0, 3) = eye;
  const Camera cam = Camera::FromBlender(p);  // 1920x1080

  // Render the frame with our Lambertian model (not timed).
  const Eigen::Vector3d sun = SunVector(45, 210);
  std::vector<double> px;
  for (int y = 0; y < 1080; ++y) {
    for (int x = 0; x < 1920; ++x) px.insert(px.end(), {double(x), double(y)});
  }
  const int64_t n = 1920 * 1080;
  Hits hits(n);
  scene.IntersectPixels(cam, n, px.data(), hits.buffers());
  std::vector<float> origins(3 * n, 0.f);
  for (int64_t i = 0; i < n; ++i) {
    if (!hits.hit(i)) continue;
    const Eigen::Vector3f o = hits.point(i) + 1e-3f * hits.normal(i);
    for (int k = 0; k < 3; ++k) origins[3 * i + k] = o[k];
  }
  std::vector<uint8_t> occ(n);
  scene.OccludedToward(n, origins.data(), sun.cast<float>(), 0.f, INFINITY, occ.data());
  cv::Mat img(1080, 1920, CV_32F);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.f, 0.01f);
  const double albedo[] = {0.35, 0.8, 0.15, 0.15, 0.6};
  for (int64_t i = 0; i < n; ++i) {
    float value = 0.6f;
    if (hits.hit(i)) {
      const double nl = std::max(0.0, hits.normal(i).cast<double>().dot(sun));
      value = static_cast<float>(albedo[hits.object_id[i]] * (0.08 + 0.7 * nl * (occ[i] ? 0 : 1)));
    }
    img.at<float>(static_cast<int>(i / 1920), static_cast<int>(i % 1920)) =
        std::clamp(value + noise(rng), 0.f, 1.f);
  }

  for (auto method : {InitialSunMethod::kDefault, InitialSunMethod::kThesis}) {
    InitialSunOptions o;
    o.method = method;
    double best = 1e9;
    InitialSunResult r;
    for (int rep = 0; rep < 3; ++rep) {
      r = EstimateInitialSun(scene, cam, img, o);
      best = std::min(best, r.seconds);
    }
    const double err = std::acos(std::min(1.0, r.sun_in_world.dot(sun))) * 180 / M_PI;
    std::printf("initial_sun[%s]: 1920x1080 in %.3f s (%d pixels used), error %.2f deg\n",
                method == InitialSunMethod::kDefault ? "default" : "thesis", best,
                r.num_pixels, err);
  }
  return 0;
}
