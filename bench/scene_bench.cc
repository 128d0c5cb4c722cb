// Scene benchmark: BVH build time for ~1M triangles, primary-ray throughput at
// 1920x1080, occlusion-ray throughput. Prints figures; never gates anything.
//   build/bench/bench_scene
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sunlapse/scene/scene.h"

using namespace sunlapse;
using Clock = std::chrono::steady_clock;

static double Seconds(Clock::time_point a, Clock::time_point b) {
  return std::chrono::duration<double>(b - a).count();
}

int main() {
  // A bumpy 100 m x 100 m terrain of 708x708 quads (~1.0M triangles) with
  // 400 boxes standing on it.
  const int n = 708;
  std::vector<float> v;
  std::vector<int32_t> t, ids;
  for (int j = 0; j <= n; ++j) {
    for (int i = 0; i <= n; ++i) {
      const float x = -50.f + 100.f * i / n, y = -50.f + 100.f * j / n;
      v.insert(v.end(), {x, y, 0.2f * std::sin(0.3f * x) * std::cos(0.2f * y)});
    }
  }
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const int a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
      t.insert(t.end(), {a, b, d, a, d, c});
      ids.insert(ids.end(), {0, 0});
    }
  }
  for (int k = 0; k < 400; ++k) {
    const float cx = -45.f + 4.5f * (k % 20), cy = -45.f + 4.5f * (k / 20.f);
    const int base = static_cast<int>(v.size() / 3);
    for (int q = 0; q < 8; ++q) {
      v.insert(v.end(), {cx + ((q & 1) ? 0.5f : -0.5f),
                         cy + ((q & 2) ? 0.5f : -0.5f), (q & 4) ? 2.f : 0.f});
    }
    const int f[12][3] = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5},
                          {0, 4, 5}, {0, 5, 1}, {2, 3, 7}, {2, 7, 6},
                          {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};
    for (const auto& tri : f) {
      t.insert(t.end(), {base + tri[0], base + tri[1], base + tri[2]});
      ids.push_back(1 + k);
    }
  }
  const int64_t nv = v.size() / 3, nt = t.size() / 3;

  auto t0 = Clock::now();
  Scene scene(v.data(), nv, t.data(), nt, ids.data());
  auto t1 = Clock::now();
  std::setvbuf(stdout, nullptr, _IONBF, 0);
  std::printf("bvh_build: %lld triangles in %.3f s\n",
              static_cast<long long>(nt), Seconds(t0, t1));

  BlenderCameraParams p;
  p.lens_mm = 24;
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  const Eigen::Vector3d eye(0, -60, 25),
      back = (eye - Eigen::Vector3d(0, 0, 0)).normalized();
  const Eigen::Vector3d right =
      Eigen::Vector3d::UnitZ().cross(back).normalized();
  m.block<3, 1>(0, 0) = right;
  m.block<3, 1>(0, 1) = back.cross(right);
  m.block<3, 1>(0, 2) = back;
  m.block<3, 1>(0, 3) = eye;
  p.world_from_camera_local = m;
  const Camera cam = Camera::FromBlender(p);
  std::vector<double> pixels;
  pixels.reserve(2 * 1920 * 1080);
  for (int y = 0; y < 1080; ++y) {
    for (int x = 0; x < 1920; ++x)
      pixels.insert(pixels.end(), {double(x), double(y)});
  }
  const int64_t nr = 1920 * 1080;
  Hits hits(nr);
  double best = 1e9;
  for (int rep = 0; rep < 3; ++rep) {
    auto a = Clock::now();
    scene.IntersectPixels(cam, nr, pixels.data(), hits.buffers());
    best = std::min(best, Seconds(a, Clock::now()));
  }
  int64_t hit = 0;
  for (int64_t i = 0; i < nr; ++i) hit += hits.hit(i);
  std::printf("primary_rays: 1920x1080 in %.3f s = %.2f Mrays/s (%.0f%% hit)\n",
              best, nr / best / 1e6, 100.0 * hit / nr);

  // Occlusion rays from every hit point toward a fixed Sun.
  std::vector<float> dirs(3 * nr);
  const Eigen::Vector3f sun = Eigen::Vector3f(0.4f, -0.5f, 0.77f).normalized();
  for (int64_t i = 0; i < nr; ++i) {
    for (int k = 0; k < 3; ++k) dirs[3 * i + k] = sun[k];
  }
  std::vector<uint8_t> occ(nr);
  best = 1e9;
  for (int rep = 0; rep < 3; ++rep) {
    auto a = Clock::now();
    scene.Occluded(nr, hits.point_in_world.data(), dirs.data(), 1e-3f, INFINITY,
                   occ.data());
    best = std::min(best, Seconds(a, Clock::now()));
  }
  std::printf("occlusion_rays: %lld in %.3f s = %.2f Mrays/s\n",
              static_cast<long long>(nr), best, nr / best / 1e6);
  return 0;
}
