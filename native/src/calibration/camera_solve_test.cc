#include "sunlapse/calibration/camera_solve.h"

#include <gtest/gtest.h>

#include <random>

#include "sunlapse/scene/camera.h"
#include "synthetic.h"

namespace sunlapse {
namespace {

Camera Truth() {
  return testing::LookAt({0.3, -4.0, 3.0}, {0, 0.5, 0}, 320, 240, 30);
}

void Marks(const Camera& cam, double noise, std::vector<Eigen::Vector3d>* w,
           std::vector<Eigen::Vector2d>* px) {
  std::mt19937 rng(1);
  std::normal_distribution<double> n(0, noise);
  for (double x = -1.5; x <= 1.5; x += 0.75) {
    for (double y = -0.5; y <= 1.5; y += 1.0) {
      Eigen::Vector2d p;
      ASSERT_TRUE(cam.WorldToPixel({x, y, 0}, &p));
      w->emplace_back(x, y, 0);
      px->push_back(p + Eigen::Vector2d(n(rng), n(rng)));
    }
  }
}

TEST(SolveCamera, RecoversFocalAndPoseFromExactGroundPoints) {
  const Camera truth = Truth();
  std::vector<Eigen::Vector3d> w;
  std::vector<Eigen::Vector2d> px;
  Marks(truth, 0.0, &w, &px);
  const CameraSolveResult r = SolveCamera(w, px, 320, 240);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.focal_px, truth.K()(0, 0), 1e-3 * truth.K()(0, 0));
  EXPECT_LT((r.blender_matrix_world.block<3, 1>(0, 3) - truth.center_in_world())
                .norm(),
            1e-3);
  EXPECT_LT(r.rms_px, 1e-3);
  // The Blender matrix builds the same camera again.
  BlenderCameraParams p;
  p.width = 320;
  p.height = 240;
  p.lens_mm = r.focal_px * 36.0 / 320;
  p.world_from_camera_local = r.blender_matrix_world;
  const Camera again = Camera::FromBlender(p);
  for (size_t i = 0; i < w.size(); ++i) {
    Eigen::Vector2d a;
    ASSERT_TRUE(again.WorldToPixel(w[i], &a));
    EXPECT_LT((a - px[i]).norm(), 1e-3);
  }
}

// One planar view pins the focal length only as well as the marks allow:
// 0.3 px of marking noise on 15 points moves it by a few percent (and the
// distance with it), while the reprojection error stays at the noise level.
TEST(SolveCamera, NoisyMarksGiveAConsistentCamera) {
  const Camera truth = Truth();
  std::vector<Eigen::Vector3d> w;
  std::vector<Eigen::Vector2d> px;
  Marks(truth, 0.3, &w, &px);
  const CameraSolveResult r = SolveCamera(w, px, 320, 240);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_NEAR(r.focal_px, truth.K()(0, 0), 0.05 * truth.K()(0, 0));
  EXPECT_LT((r.blender_matrix_world.block<3, 1>(0, 3) - truth.center_in_world())
                .norm(),
            0.25);
  EXPECT_LT(r.rms_px, 0.6);
}

TEST(SolveCamera, GivenFocalNeedsFewerPoints) {
  const Camera truth = Truth();
  std::vector<Eigen::Vector3d> w;
  std::vector<Eigen::Vector2d> px;
  Marks(truth, 0.0, &w, &px);
  w.resize(4);
  px.resize(4);
  CameraSolveOptions o;
  o.focal_px = truth.K()(0, 0);
  const CameraSolveResult r = SolveCamera(w, px, 320, 240, o);
  ASSERT_TRUE(r.ok()) << r.message;
  EXPECT_LT(r.rms_px, 1e-3);
}

TEST(SolveCamera, SaysWhatIsMissingOrWrong) {
  const Camera truth = Truth();
  std::vector<Eigen::Vector3d> w;
  std::vector<Eigen::Vector2d> px;
  Marks(truth, 0.0, &w, &px);
  std::vector<Eigen::Vector3d> w5(w.begin(), w.begin() + 5);
  std::vector<Eigen::Vector2d> p5(px.begin(), px.begin() + 5);
  const CameraSolveResult few = SolveCamera(w5, p5, 320, 240);
  EXPECT_EQ(few.status, CameraSolveResult::Status::kTooFewPoints);
  EXPECT_NE(few.message.find("at least 6"), std::string::npos);
  std::vector<Eigen::Vector3d> off_plane = w;
  off_plane[3].z() += 1.0;  // the focal length needs points on one plane
  EXPECT_EQ(SolveCamera(off_plane, px, 320, 240).status,
            CameraSolveResult::Status::kNotCoplanar);
  std::swap(px[0], px[7]);  // two points named wrongly
  const CameraSolveResult r = SolveCamera(w, px, 320, 240);
  EXPECT_TRUE(r.ok());  // a camera, with a warning
  EXPECT_GT(r.rms_px, 3.0);
  EXPECT_NE(r.message, "");
  EXPECT_THROW(SolveCamera(w, p5, 320, 240), std::invalid_argument);
}

}  // namespace
}  // namespace sunlapse
