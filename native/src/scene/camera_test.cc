#include "sunlapse/scene/camera.h"

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>

namespace sunlapse {
namespace {

Eigen::Matrix4d LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& at) {
  // Blender camera local frame: looks along -Z, +Y up.
  const Eigen::Vector3d back = (eye - at).normalized();
  const Eigen::Vector3d right =
      Eigen::Vector3d::UnitZ().cross(back).normalized();
  const Eigen::Vector3d up = back.cross(right);
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  m.block<3, 1>(0, 0) = right;
  m.block<3, 1>(0, 1) = up;
  m.block<3, 1>(0, 2) = back;
  m.block<3, 1>(0, 3) = eye;
  return m;
}

TEST(Camera, DefaultBlenderCameraHasExpectedIntrinsics) {
  BlenderCameraParams p;  // 50 mm, 36 mm sensor, 1920x1080, AUTO fit
  const Camera cam = Camera::FromBlender(p);
  EXPECT_NEAR(cam.K()(0, 0), 50.0 * 1920 / 36.0, 1e-9);
  EXPECT_NEAR(cam.K()(1, 1), 50.0 * 1920 / 36.0, 1e-9);
  EXPECT_NEAR(cam.K()(0, 2), 959.5, 1e-9);
  EXPECT_NEAR(cam.K()(1, 2), 539.5, 1e-9);
}

TEST(Camera, VerticalFitUsesSensorHeightAlongImageHeight) {
  BlenderCameraParams p;
  p.sensor_fit = SensorFit::kVertical;
  p.sensor_height_mm = 20.0;
  p.width = 640;
  p.height = 480;
  const Camera cam = Camera::FromBlender(p);
  EXPECT_NEAR(cam.K()(1, 1), 50.0 * 480 / 20.0, 1e-9);
}

TEST(Camera, AutoFitOnPortraitImageUsesSensorWidthAlongHeight) {
  BlenderCameraParams p;
  p.width = 480;
  p.height = 640;
  const Camera cam = Camera::FromBlender(p);
  EXPECT_NEAR(cam.K()(1, 1), 50.0 * 640 / 36.0, 1e-9);
}

TEST(Camera, LooksAlongLocalMinusZWithYUp) {
  BlenderCameraParams p;  // identity pose: looks down world -Z
  const Camera cam = Camera::FromBlender(p);
  Eigen::Vector2d px;
  ASSERT_TRUE(cam.WorldToPixel({0, 0, -10}, &px));
  EXPECT_NEAR(px.x(), 959.5, 1e-9);
  EXPECT_NEAR(px.y(), 539.5, 1e-9);
  ASSERT_TRUE(cam.WorldToPixel({1, 1, -10}, &px));
  EXPECT_GT(px.x(), 959.5);  // +X is right
  EXPECT_LT(px.y(), 539.5);  // +Y is up, so fewer rows from the top
  EXPECT_FALSE(cam.WorldToPixel({0, 0, 10}, &px));  // behind
}

TEST(Camera, PositiveShiftMovesTheImageOfAPointLeftAndDown) {
  BlenderCameraParams p;
  p.shift_x = 0.1;
  p.shift_y = 0.05;
  const Camera cam = Camera::FromBlender(p);
  EXPECT_NEAR(cam.K()(0, 2), 959.5 - 0.1 * 1920, 1e-9);
  EXPECT_NEAR(cam.K()(1, 2), 539.5 + 0.05 * 1920, 1e-9);
}

TEST(Camera, PixelRayAndProjectionRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (SensorFit fit :
       {SensorFit::kAuto, SensorFit::kHorizontal, SensorFit::kVertical}) {
    BlenderCameraParams p;
    p.sensor_fit = fit;
    p.width = 1000;
    p.height = 700;
    p.pixel_aspect_x = 1.0;
    p.pixel_aspect_y = 1.2;
    p.shift_x = -0.07;
    p.world_from_camera_local = LookAt({4, -6, 3}, {0, 0, 0.5});
    const Camera cam = Camera::FromBlender(p);
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector2d px(u(rng) * 999, u(rng) * 699);
      const Eigen::Vector3d ray = cam.PixelToRayInWorld(px);
      EXPECT_NEAR(ray.norm(), 1.0, 1e-12);
      const Eigen::Vector3d point =
          cam.center_in_world() + (1 + 9 * u(rng)) * ray;
      Eigen::Vector2d back;
      ASSERT_TRUE(cam.WorldToPixel(point, &back));
      EXPECT_NEAR((back - px).norm(), 0.0, 1e-8);
    }
  }
}

TEST(Camera, DistortionRoundTripsAndUndistortsRays) {
  PolynomialDistortion d;
  d.focal_x_px = d.focal_y_px = 800;
  d.principal_x_px = 319.5;
  d.principal_y_px = 239.5;
  d.k1 = -0.12;
  d.k2 = 0.03;
  d.k3 = -0.002;
  for (double x = 0; x < 640; x += 37) {
    for (double y = 0; y < 480; y += 41) {
      const Eigen::Vector2d ideal(x, y);
      const Eigen::Vector2d rec = d.Distort(ideal);
      EXPECT_NEAR((d.Undistort(rec) - ideal).norm(), 0.0, 1e-9);
    }
  }
  BlenderCameraParams p;
  p.width = 640;
  p.height = 480;
  Camera cam = Camera::FromBlender(p);
  const Camera ideal_cam = cam;
  cam.SetDistortion(d);
  const Eigen::Vector2d corner(10, 10);
  Eigen::Vector2d recorded;
  const Eigen::Vector3d point =
      ideal_cam.center_in_world() + 5.0 * ideal_cam.PixelToRayInWorld(corner);
  ASSERT_TRUE(cam.WorldToPixel(point, &recorded));
  EXPECT_GT((recorded - corner).norm(), 1.0);  // barrel moves it inward
  EXPECT_NEAR(
      (cam.PixelToRayInWorld(recorded) - ideal_cam.PixelToRayInWorld(corner))
          .norm(),
      0.0, 1e-9);
}

TEST(Camera, RejectsBadParametersNamingThem) {
  BlenderCameraParams p;
  p.lens_mm = 0;
  try {
    Camera::FromBlender(p);
    FAIL() << "expected invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("lens_mm"), std::string::npos);
  }
  p = BlenderCameraParams();
  p.width = 0;
  EXPECT_THROW(Camera::FromBlender(p), std::invalid_argument);
  p = BlenderCameraParams();
  p.world_from_camera_local(0, 0) = std::nan("");
  EXPECT_THROW(Camera::FromBlender(p), std::invalid_argument);
}

TEST(Camera, ResizedMapsPixelsAsOpenCvsResize) {
  BlenderCameraParams p;
  p.lens_mm = 28, p.sensor_width_mm = 36, p.sensor_height_mm = 24;
  p.width = 640, p.height = 480;
  p.world_from_camera_local(2, 3) = 5.0;  // 5 m up, looking down
  const Camera cam = Camera::FromBlender(p);
  const Camera half = cam.Resized(320, 240);
  EXPECT_EQ(half.width(), 320);
  for (const Eigen::Vector3d& point :
       {Eigen::Vector3d(0.3, -0.2, 0.0), Eigen::Vector3d(-1.0, 0.7, 1.0)}) {
    Eigen::Vector2d full, small;
    ASSERT_TRUE(cam.WorldToPixel(point, &full));
    ASSERT_TRUE(half.WorldToPixel(point, &small));
    EXPECT_NEAR(small.x(), (full.x() + 0.5) * 0.5 - 0.5, 1e-9);
    EXPECT_NEAR(small.y(), (full.y() + 0.5) * 0.5 - 0.5, 1e-9);
  }
}

}  // namespace
}  // namespace sunlapse
