#include "synthetic.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <opencv2/imgproc.hpp>

namespace sunlapse::testing {

void Mesh::Box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, int id) {
  const int b = static_cast<int>(v.size());
  for (int i = 0; i < 8; ++i) {
    v.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(),
                   (i & 4) ? hi.z() : lo.z());
  }
  const int q[6][4] = {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4},
                       {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}};
  for (const auto& f : q) {
    t.emplace_back(b + f[0], b + f[1], b + f[2]);
    t.emplace_back(b + f[0], b + f[2], b + f[3]);
    ids.insert(ids.end(), {id, id});
  }
}

void Mesh::Ground(float half, int id) {
  const int b = static_cast<int>(v.size());
  v.insert(
      v.end(),
      {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}});
  t.emplace_back(b, b + 1, b + 2);
  t.emplace_back(b, b + 2, b + 3);
  ids.insert(ids.end(), {id, id});
}

Mesh BoxAndPole() {
  Mesh m;
  m.Ground(12, 0);
  m.Box({-1.5f, -1, 0}, {0.5f, 1.2f, 1.6f}, 1);
  m.Box({2.5f, -2.6f, 0}, {2.65f, -2.45f, 3.0f}, 2);
  return m;
}

Mesh PoleOnGround(float ground_half, float height) {
  Mesh m;
  m.Ground(ground_half, 0);
  m.Box({-0.1f, -0.1f, 0.f}, {0.1f, 0.1f, height}, 1);
  return m;
}

Mesh BenchScene() {
  Mesh m = BoxAndPole();
  m.Box({-3, 2, 0}, {-2.85f, 2.15f, 2.5f}, 3);
  m.Box({-4, 5, 0}, {1, 5.3f, 2}, 4);
  return m;
}

Camera BenchCamera() { return LookAt({3, -11, 8}, {0, 0, 0}, 1920, 1080); }

Camera LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
              int width, int height, double lens_mm) {
  BlenderCameraParams p;
  p.width = width;
  p.height = height;
  p.lens_mm = lens_mm;
  const Eigen::Vector3d back = (eye - target).normalized();
  const Eigen::Vector3d right =
      Eigen::Vector3d::UnitZ().cross(back).normalized();
  p.world_from_camera_local.block<3, 1>(0, 0) = right;
  p.world_from_camera_local.block<3, 1>(0, 1) = back.cross(right);
  p.world_from_camera_local.block<3, 1>(0, 2) = back;
  p.world_from_camera_local.block<3, 1>(0, 3) = eye;
  return Camera::FromBlender(p);
}

RenderOptions TexturedGround(uint32_t seed) {
  RenderOptions o;
  o.noise = 0.01;
  o.seed = seed;
  o.ambient = 0.15;
  o.albedo = [](int id, const Eigen::Vector3f& p) {
    if (id != 0) return 0.5;
    const int tiles = (static_cast<int>(std::floor(p.x() * 2)) +
                       static_cast<int>(std::floor(p.y() * 2))) &
                      1;
    return 0.3 + 0.08 * tiles +
           0.04 * std::sin(7.3 * p.x()) * std::cos(5.1 * p.y());
  };
  return o;
}

cv::Mat RenderLambertian(const Scene& scene, const Camera& cam,
                         const Eigen::Vector3d& sun, const RenderOptions& o) {
  if (o.supersample > 1) {
    // Render k times larger without noise, average k x k blocks, add noise.
    const int k = o.supersample;
    Eigen::Matrix3d K = cam.K();
    K.row(0) *= k;
    K.row(1) *= k;
    K(0, 2) = (cam.K()(0, 2) + 0.5) * k - 0.5;
    K(1, 2) = (cam.K()(1, 2) + 0.5) * k - 0.5;
    const Camera big(K, cam.cam_from_world(), cam.width() * k,
                     cam.height() * k);
    RenderOptions clean = o;
    clean.supersample = 1;
    clean.noise = 0;
    cv::Mat hi = RenderLambertian(scene, big, sun, clean), img;
    cv::resize(hi, img, cv::Size(cam.width(), cam.height()), 0, 0,
               cv::INTER_AREA);
    if (o.noise > 0) {
      cv::Mat noise(img.size(), CV_32F);
      cv::RNG rng(o.seed);
      rng.fill(noise, cv::RNG::NORMAL, 0.0, o.noise);
      img = cv::min(cv::max(img + noise, 0.0), 1.0);
    }
    return img;
  }
  const int w = cam.width(), h = cam.height();
  const int64_t n = static_cast<int64_t>(w) * h;
  std::vector<double> px(2 * n);
  for (int64_t i = 0; i < n; ++i) {
    px[2 * i] = static_cast<double>(i % w);
    px[2 * i + 1] = static_cast<double>(i / w);
  }
  Hits hits(n);
  scene.IntersectPixels(cam, n, px.data(), hits.buffers());
  std::vector<float> origins(3 * n, 0.f);
  for (int64_t i = 0; i < n; ++i) {
    const Eigen::Vector3f p =
        hits.hit(i) ? Eigen::Vector3f(hits.point(i) + 1e-3f * hits.normal(i))
                    : Eigen::Vector3f(0, 0, -1e4f);
    for (int k = 0; k < 3; ++k) origins[3 * i + k] = p[k];
  }
  std::vector<uint8_t> occ(n);
  scene.OccludedToward(n, origins.data(), sun.normalized().cast<float>(), 0.f,
                       INFINITY, occ.data());
  std::mt19937 rng(o.seed);
  std::normal_distribution<float> gauss(0.f, static_cast<float>(o.noise));
  cv::Mat img(h, w, CV_32F);
  for (int64_t i = 0; i < n; ++i) {
    float value = o.sky;
    if (hits.hit(i)) {
      const double nl =
          std::max(0.0, hits.normal(i).cast<double>().dot(sun.normalized()));
      const double rho = o.albedo(hits.object_id[i], hits.point(i));
      value =
          static_cast<float>(rho * (o.ambient + o.sun * nl * (occ[i] ? 0 : 1)));
    }
    img.at<float>(static_cast<int>(i / w), static_cast<int>(i % w)) =
        std::clamp(value + (o.noise > 0 ? gauss(rng) : 0.f), 0.f, 1.f);
  }
  return img;
}

}  // namespace sunlapse::testing
