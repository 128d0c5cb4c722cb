#include "sunlapse/initial/initial_sun.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace sunlapse {
namespace {

struct Mesh {
  std::vector<Eigen::Vector3f> v;
  std::vector<Eigen::Vector3i> t;
  std::vector<int32_t> ids;
  void Box(const Eigen::Vector3f& lo, const Eigen::Vector3f& hi, int id) {
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
      ids.push_back(id);
      ids.push_back(id);
    }
  }
  void Ground(float half, int id) {
    const int b = static_cast<int>(v.size());
    v.insert(v.end(), {{-half, -half, 0}, {half, -half, 0}, {half, half, 0}, {-half, half, 0}});
    t.emplace_back(b, b + 1, b + 2);
    t.emplace_back(b, b + 2, b + 3);
    ids.insert(ids.end(), {id, id});
  }
  Scene Build() const { return Scene(v, t, ids); }
};

// Ground (id 0), a box (1) and a pole (2).
Mesh BoxAndPole() {
  Mesh m;
  m.Ground(12, 0);
  m.Box({-1.5f, -1, 0}, {0.5f, 1.2f, 1.6f}, 1);
  m.Box({2.5f, -2.6f, 0}, {2.65f, -2.45f, 3.0f}, 2);
  return m;
}

Camera LookingDown(int w, int h) {
  BlenderCameraParams p;
  p.width = w;
  p.height = h;
  p.lens_mm = 24;
  const Eigen::Vector3d eye(3, -11, 8), back = eye.normalized();
  const Eigen::Vector3d right = Eigen::Vector3d::UnitZ().cross(back).normalized();
  p.world_from_camera_local.block<3, 1>(0, 0) = right;
  p.world_from_camera_local.block<3, 1>(0, 1) = back.cross(right);
  p.world_from_camera_local.block<3, 1>(0, 2) = back;
  p.world_from_camera_local.block<3, 1>(0, 3) = eye;
  return Camera::FromBlender(p);
}

// Our own Lambertian renderer with cast shadows:
// I = albedo (ambient + sun max(0, N.L) visible) + Gaussian noise.
cv::Mat Render(const Scene& scene, const Camera& cam, const Eigen::Vector3d& sun,
               const std::vector<double>& albedo, double noise, uint32_t seed = 1) {
  const int w = cam.width(), h = cam.height();
  std::vector<Eigen::Vector2d> px;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) px.emplace_back(x, y);
  }
  const Hits hits = scene.IntersectPixels(cam, px);
  std::vector<float> origins(3 * px.size());
  for (size_t i = 0; i < px.size(); ++i) {
    const Eigen::Vector3f o = hits.hit(i) ? Eigen::Vector3f(hits.point(i) + 1e-3f * hits.normal(i))
                                         : Eigen::Vector3f(0, 0, -100);
    for (int k = 0; k < 3; ++k) origins[3 * i + k] = o[k];
  }
  std::vector<uint8_t> occ(px.size());
  scene.OccludedToward(px.size(), origins.data(), sun.cast<float>(), 0.f, INFINITY, occ.data());
  std::mt19937 rng(seed);
  std::normal_distribution<float> gauss(0.f, static_cast<float>(noise));
  cv::Mat img(h, w, CV_32F);
  for (size_t i = 0; i < px.size(); ++i) {
    float value = 0.6f;  // sky
    if (hits.hit(i)) {
      const double nl = std::max(0.0, hits.normal(i).cast<double>().dot(sun));
      value = static_cast<float>(albedo[hits.object_id[i]] * (0.08 + 0.7 * nl * (occ[i] ? 0 : 1)));
    }
    img.at<float>(px[i].y(), px[i].x()) = std::clamp(value + gauss(rng), 0.f, 1.f);
  }
  return img;
}

struct SunCase {
  double zenith, azimuth;
};

class InitialSunRecovers : public ::testing::TestWithParam<SunCase> {};

TEST_P(InitialSunRecovers, KnownDirectionWithinHalfADegree) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(320, 240);
  const Eigen::Vector3d sun = SunVector(GetParam().zenith, GetParam().azimuth);
  const cv::Mat img = Render(scene, cam, sun, {0.35, 0.8, 0.15}, 0.01);
  InitialSunOptions o;
  const InitialSunResult r = EstimateInitialSun(scene, cam, img, o);
  ASSERT_TRUE(r.success) << r.message;
  const double err = std::atan2(r.sun_in_world.cross(sun).norm(), r.sun_in_world.dot(sun)) * 180 / M_PI;
  EXPECT_LT(err, 0.5) << "zenith " << r.zenith_deg << " azimuth " << r.azimuth_deg;
  EXPECT_GT(r.confidence, 0.3);
  // Albedo relative to the ground (the object with most pixels).
  EXPECT_NEAR(r.albedo_per_object[1] / r.albedo_per_object[0], 0.8 / 0.35, 0.15);
}

INSTANTIATE_TEST_SUITE_P(Directions, InitialSunRecovers,
                         ::testing::Values(SunCase{35, 200}, SunCase{60, 110},
                                           SunCase{20, 320}, SunCase{70, 250}));

TEST(InitialSun, ObjectsMissingFromTheModelDoNotDragTheAnswer) {
  Mesh footage = BoxAndPole();
  footage.Box({-4, 2, 0}, {-3, 3, 1.2f}, 3);  // in the footage, not in the model
  footage.Box({4, 1, 0}, {4.6f, 1.6f, 0.9f}, 3);
  const Scene truth_scene = footage.Build();
  const Scene model = BoxAndPole().Build();
  const Camera cam = LookingDown(320, 240);
  const Eigen::Vector3d sun = SunVector(50, 150);
  const cv::Mat img = Render(truth_scene, cam, sun, {0.35, 0.8, 0.15, 0.5}, 0.01);
  const InitialSunResult r = EstimateInitialSun(model, cam, img, InitialSunOptions());
  ASSERT_TRUE(r.success);
  const double err = std::acos(std::min(1.0, r.sun_in_world.dot(sun))) * 180 / M_PI;
  EXPECT_LT(err, 1.0);
}

// An image made by exactly the thesis's model: one of its eight point lights
// (on the sphere around the model's bounds, 45 deg up) plus ambient. The fit
// must give that light back, and its direction as the Sun.
TEST(InitialSun, ThesisBaselineRecoversTheLightOfItsOwnModel) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(160, 120);
  const Eigen::AlignedBox3f b = scene.bounds();
  const Eigen::Vector3d center = b.center().cast<double>();
  const double radius = 0.5 * b.diagonal().norm();
  const int k = 5;
  const double az = 2 * M_PI * k / 8, el = M_PI / 4;
  const Eigen::Vector3d dir(std::cos(el) * std::sin(az), std::cos(el) * std::cos(az), std::sin(el));
  const Eigen::Vector3d light = center + radius * dir;
  cv::Mat img(cam.height(), cam.width(), CV_32F, 0.6f);
  for (int y = 0; y < cam.height(); ++y) {
    for (int x = 0; x < cam.width(); ++x) {
      const Hits h = scene.IntersectPixels(cam, {Eigen::Vector2d(x, y)});
      if (!h.hit(0)) continue;
      const Eigen::Vector3f o = h.point(0) + 1e-3f * h.normal(0);
      const Eigen::Vector3f to_light = (light.cast<float>() - o);
      uint8_t occ;
      scene.OccludedToward(1, o.data(), to_light, 0.f, INFINITY, &occ);
      const double nl = std::max(0.0, h.normal(0).cast<double>().dot(to_light.cast<double>().normalized()));
      img.at<float>(y, x) = static_cast<float>(0.1 + 0.5 * nl * (occ ? 0 : 1));
    }
  }
  InitialSunOptions o;
  o.method = InitialSunMethod::kThesis;
  const InitialSunResult r = EstimateInitialSun(scene, cam, img, o);
  ASSERT_TRUE(r.success) << r.message;
  ASSERT_EQ(r.light_intensities.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(r.light_intensities[i], i == k ? 0.5 : 0.0, 0.01) << "light " << i;
  }
  EXPECT_NEAR(r.ambient_intensity, 0.1, 0.01);
  EXPECT_LT(std::acos(std::min(1.0, r.sun_in_world.dot(dir))) * 180 / M_PI, 0.5);
}

TEST(InitialSun, FlatGroundWithoutShadowsSaysTheAzimuthIsUndetermined) {
  Mesh m;
  m.Ground(12, 0);
  const Scene scene = m.Build();
  const Camera cam = LookingDown(160, 120);
  const cv::Mat img = Render(scene, cam, SunVector(40, 90), {0.4}, 0.01);
  const InitialSunResult r = EstimateInitialSun(scene, cam, img, InitialSunOptions());
  EXPECT_FALSE(r.message.empty());
  EXPECT_LT(r.confidence, 0.3);
}

TEST(InitialSun, CancelsWhenProgressSaysSo) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(160, 120);
  const cv::Mat img = Render(scene, cam, SunVector(40, 200), {0.4, 0.4, 0.4}, 0.0);
  int calls = 0;
  const InitialSunResult r = EstimateInitialSun(scene, cam, img, InitialSunOptions(),
                                                [&](double) { return ++calls < 3; });
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.message, "cancelled");
}

TEST(InitialSun, RejectsBadInput) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(160, 120);
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(), InitialSunOptions()), std::invalid_argument);
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(10, 10, CV_32F, 0.5f), InitialSunOptions()),
               std::invalid_argument);
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(120, 160, CV_8U), InitialSunOptions()),
               std::invalid_argument);
  InitialSunOptions o;
  o.loss_scale = 0;
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(120, 160, CV_32F, 0.5f), o),
               std::invalid_argument);
  // Nothing of the model in view: a result that says so, not an exception.
  BlenderCameraParams p;
  p.width = 160;
  p.height = 120;
  p.world_from_camera_local(2, 3) = -50;  // under the ground, looking down
  const InitialSunResult r = EstimateInitialSun(scene, Camera::FromBlender(p),
                                                cv::Mat(120, 160, CV_32F, 0.5f), InitialSunOptions());
  EXPECT_FALSE(r.success);
  EXPECT_NE(r.message.find("too few"), std::string::npos);
}

TEST(InitialSun, AnglesRoundTrip) {
  double z, a;
  SunAngles(SunVector(33, 287), &z, &a);
  EXPECT_NEAR(z, 33, 1e-9);
  EXPECT_NEAR(a, 287, 1e-9);
}

}  // namespace
}  // namespace sunlapse
