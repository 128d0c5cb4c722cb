#include "sunlapse/initial/initial_sun.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "synthetic.h"

namespace sunlapse {
namespace {

using testing::BoxAndPole;
using testing::Mesh;

Camera LookingDown(int w, int h) {
  return testing::LookAt({3, -11, 8}, {0, 0, 0}, w, h);
}

cv::Mat Render(const Scene& scene, const Camera& cam,
               const Eigen::Vector3d& sun, const std::vector<double>& albedo,
               double noise) {
  testing::RenderOptions o;
  o.noise = noise;
  o.albedo = [albedo](int id, const Eigen::Vector3f&) { return albedo[id]; };
  return testing::RenderLambertian(scene, cam, sun, o);
}

struct SunCase {
  double zenith, azimuth;
};

class InitialSunRecovers : public ::testing::TestWithParam<SunCase> {};

TEST_P(InitialSunRecovers, KnownDirectionWithinHalfADegree) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(320, 240);
  const Eigen::Vector3d sun =
      SunInWorldFromAngles(GetParam().zenith, GetParam().azimuth);
  const cv::Mat img = Render(scene, cam, sun, {0.35, 0.8, 0.15}, 0.01);
  InitialSunOptions o;
  const InitialSunResult r = EstimateInitialSun(scene, cam, img, o);
  ASSERT_TRUE(r.ok()) << r.message;
  const double err = AngleBetweenDeg(r.sun_in_world, sun);
  EXPECT_LT(err, 0.5) << "zenith " << r.zenith_deg << " azimuth "
                      << r.azimuth_deg;
  EXPECT_GT(r.confidence, 0.3);
  // Albedo relative to the ground (the object with most pixels).
  EXPECT_NEAR(r.albedo_per_object[1] / r.albedo_per_object[0], 0.8 / 0.35,
              0.15);
}

INSTANTIATE_TEST_SUITE_P(Directions, InitialSunRecovers,
                         ::testing::Values(SunCase{35, 200}, SunCase{60, 110},
                                           SunCase{20, 320}, SunCase{70, 250}));

TEST(InitialSun, ObjectsMissingFromTheModelDoNotDragTheAnswer) {
  Mesh footage = BoxAndPole();
  footage.Box({-4, 2, 0}, {-3, 3, 1.2f},
              3);  // in the footage, not in the model
  footage.Box({4, 1, 0}, {4.6f, 1.6f, 0.9f}, 3);
  const Scene truth_scene = footage.Build();
  const Scene model = BoxAndPole().Build();
  const Camera cam = LookingDown(320, 240);
  const Eigen::Vector3d sun = SunInWorldFromAngles(50, 150);
  const cv::Mat img =
      Render(truth_scene, cam, sun, {0.35, 0.8, 0.15, 0.5}, 0.01);
  const InitialSunResult r =
      EstimateInitialSun(model, cam, img, InitialSunOptions());
  ASSERT_TRUE(r.ok());
  EXPECT_LT(AngleBetweenDeg(r.sun_in_world, sun), 1.0);
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
  // The thesis's light k of 8, 45 deg above the horizon.
  const Eigen::Vector3d dir = SunInWorldFromAngles(45, 360.0 * k / 8);
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
      const double nl = std::max(
          0.0,
          h.normal(0).cast<double>().dot(to_light.cast<double>().normalized()));
      img.at<float>(y, x) = static_cast<float>(0.1 + 0.5 * nl * (occ ? 0 : 1));
    }
  }
  InitialSunOptions o;
  o.method = InitialSunMethod::kThesis;
  const InitialSunResult r = EstimateInitialSun(scene, cam, img, o);
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_EQ(r.light_intensities.size(), 8u);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(r.light_intensities[i], i == k ? 0.5 : 0.0, 0.01)
        << "light " << i;
  }
  EXPECT_NEAR(r.ambient_intensity, 0.1, 0.01);
  EXPECT_LT(AngleBetweenDeg(r.sun_in_world, dir), 0.5);
}

TEST(InitialSun, FlatGroundWithoutShadowsSaysTheAzimuthIsUndetermined) {
  Mesh m;
  m.Ground(12, 0);
  const Scene scene = m.Build();
  const Camera cam = LookingDown(160, 120);
  const cv::Mat img =
      Render(scene, cam, SunInWorldFromAngles(40, 90), {0.4}, 0.01);
  const InitialSunResult r =
      EstimateInitialSun(scene, cam, img, InitialSunOptions());
  EXPECT_FALSE(r.message.empty());
  EXPECT_LT(r.confidence, 0.3);
}

TEST(InitialSun, CancelsWhenProgressSaysSo) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(160, 120);
  const cv::Mat img =
      Render(scene, cam, SunInWorldFromAngles(40, 200), {0.4, 0.4, 0.4}, 0.0);
  int calls = 0;
  const InitialSunResult r =
      EstimateInitialSun(scene, cam, img, InitialSunOptions(),
                         [&](double) { return ++calls < 3; });
  EXPECT_FALSE(r.ok());
  EXPECT_EQ(r.status, InitialSunResult::Status::kCancelled);
}

TEST(InitialSun, RejectsBadInput) {
  const Scene scene = BoxAndPole().Build();
  const Camera cam = LookingDown(160, 120);
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(), InitialSunOptions()),
               std::invalid_argument);
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(10, 10, CV_32F, 0.5f),
                                  InitialSunOptions()),
               std::invalid_argument);
  EXPECT_THROW(EstimateInitialSun(scene, cam, cv::Mat(120, 160, CV_8U),
                                  InitialSunOptions()),
               std::invalid_argument);
  InitialSunOptions o;
  o.loss_scale = 0;
  EXPECT_THROW(
      EstimateInitialSun(scene, cam, cv::Mat(120, 160, CV_32F, 0.5f), o),
      std::invalid_argument);
  // Nothing of the model in view: a result that says so, not an exception.
  BlenderCameraParams p;
  p.width = 160;
  p.height = 120;
  p.world_from_camera_local(2, 3) = -50;  // under the ground, looking down
  const InitialSunResult r =
      EstimateInitialSun(scene, Camera::FromBlender(p),
                         cv::Mat(120, 160, CV_32F, 0.5f), InitialSunOptions());
  EXPECT_EQ(r.status, InitialSunResult::Status::kTooFewPixels);
  EXPECT_NE(r.message.find("too few"), std::string::npos);
}

}  // namespace
}  // namespace sunlapse
